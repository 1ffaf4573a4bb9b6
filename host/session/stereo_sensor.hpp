// Kapucu & Baysec's sensor (issue #6, real cameras issue #14): a fixed, calibrated stereo pair
// watches a beacon on the robot's tool. One code path for real cameras (frames from
// host/capture, the pair from `kincal camera stereo`) and for the simulator (host/demo renders
// the frames and states its pair the same way).
//
// Per pose: grab(pose) gives the two frames; in each, the firmware core's labeler finds the
// beacon -- through the colour-class table when one is given (colour frames, the class the table
// scores: `kincal colour-table` builds it), else as the brightest blob of the grey frame
// (thresholded halfway between the background, the median grey level, and the brightest
// pixel; a colour frame without a table is converted to grey). core::triangulate_pair
// (firmware/core/stereo.hpp: undistortion, then the midpoint of the two rays) gives the point in
// the left camera's OpenCV frame (x right, y down, z forward), placed in the device frame by
// device_T_left; its covariance is first-order propagation of pixel_sigma_px (the centroid
// noise, each coordinate of each camera independent) through the same triangulation (central
// differences of a quarter pixel), plus, when the setup has the calibration's covariance
// (`kincal camera stereo` writes it into the stereo file), the calibration's share
// J_calib C_calib J_calib^T: central differences of one standard deviation along each
// eigenvector of C_calib (triangulation_covariance below).
//
// A pose fails (SessionError naming the pose, the camera and its frame's origin, e.g. the
// image file) when a camera's frame is missing, of another size than the calibration's, or not
// 8-bit; when the beacon is missing in a camera (no blob, or too little contrast); doubled (a
// second blob at least kDoubledAreaRatio of the largest: a reflection or a second lamp); cut by
// the frame's border; or occluded in one camera (its blob covers less than kOccludedAreaRatio of
// the other camera's, after scaling by the cameras' pixel densities: the beacon stands at nearly
// the same depth for both); or when the rays do not meet (not the same beacon, or a calibration
// that does not fit these cameras).
//
// Thread safety: one session thread. Cost: two labelings of a frame and nine triangulations,
// plus two per non-zero eigenvalue of the calibration's covariance (at most 48).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include <Eigen/Core>

#include "firmware/core/colour_class.hpp"
#include "firmware/core/stereo.hpp"
#include "host/session/sensor.hpp"

namespace kincal::session {

inline constexpr double kDoubledAreaRatio = 0.25;
inline constexpr double kOccludedAreaRatio = 0.5;

struct StereoFrames {
  cv::Mat left, right;  // 8-bit grey or BGR
  double timestamp_s = 0;
  std::string left_origin, right_origin;  // where each frame came from (file, "camera 0 frame 12")
};

// The calibration's parameters in the order of its covariance (camera::kStereoCalibrationOrder,
// host/camera/uncertainty.hpp): the left camera's fx fy cx cy (px) k1 k2 p1 p2 k3, the right
// camera's, then right_T_left (x_right = R x_left + t) as the rotation vector of R (rad) and t (m).
using CalibrationCovariance = Eigen::Matrix<double, 24, 24>;

struct StereoSetup {
  core::StereoPair pair;                                        // both cameras' intrinsics and distortion, left_T_right
  cv::Size left_size_px, right_size_px;                         // the calibrated frame sizes; empty: not checked
  model::Transform device_T_left;                               // the left camera's OpenCV frame in the device frame
  double pixel_sigma_px = 0.1;                                  // centroid noise the covariance assumes
  std::optional<core::ColourClassTable> colour;                 // the beacon's colour class; none: brightest blob
  std::optional<CalibrationCovariance> calibration_covariance;  // none: the calibration taken as exact
};

// The covariance (3 x 3, m^2, left camera frame) of the point triangulated from left_px and
// right_px by `pair`: the pixels' share (pixel_sigma_px per coordinate) and, when given, the
// calibration's, as `calibration_directions` (calibration_directions(C) below) spans it.
// Throws SessionError (prefixed by `what`) when a perturbed triangulation fails.
using CalibrationDirections = std::vector<Eigen::Matrix<double, 24, 1>>;
model::Matrix3 triangulation_covariance(const core::StereoPair& pair, const core::Vector2<float>& left_px,
                                        const core::Vector2<float>& right_px, double pixel_sigma_px,
                                        const CalibrationDirections& calibration_directions, const std::string& what);
// sqrt(lambda) v for each eigenvalue lambda > 0 and eigenvector v of C (sum of d d^T = C).
// Throws SessionError when C is not a finite symmetric matrix without negative eigenvalues
// (beyond rounding).
CalibrationDirections calibration_directions(const CalibrationCovariance& covariance);
// The pair with its calibration moved by `delta` (in CalibrationCovariance's order).
core::StereoPair perturbed(const core::StereoPair& pair, const Eigen::Matrix<double, 24, 1>& delta);

class StereoBeaconSensor : public Sensor {
 public:
  // grab(pose) returns the frames of that pose (the session asks for each pose once, in plan
  // order; a resumed session starts later). Throws SessionError for a non-positive sigma.
  StereoBeaconSensor(std::function<StereoFrames(int pose)> grab, StereoSetup setup);
  Observation measure(int index, const model::Transform& predicted) override;
  std::string name() const override { return "stereo pair and beacon"; }
  bool gives_orientation() const override { return false; }
  bool gives_covariance() const override { return true; }

 private:
  std::function<StereoFrames(int)> grab_;
  StereoSetup setup_;
  CalibrationDirections calibration_directions_;
};

}  // namespace kincal::session

// What a calibration session measures with (issue #6): the tool's position (and orientation) in
// the measuring device's frame, one observation per pose, or a SessionError that stops the
// session at once (fail fast: a missing sensor, a blob-less frame or a non-flat surface at the
// first pose, not a wasted run).
//
//   PlatformPoseSensor   Doty's ARID platform over CAN: the platform's camera and four rangers
//                        measure square_T_camera on board; the strip layout places the square
//                        in the strip (device) frame: strip_T_camera = strip_T_square[k] *
//                        square_T_camera. Which square k the platform measured against is the
//                        one that puts the camera nearest the nominal prediction (squares are 4
//                        inches apart, far more than any kinematic error), so the platform may
//                        pick any square in view (protocol 3.0: its pose may rest on that
//                        reference square's neighbours too; the report says how many squares,
//                        the observation's note shows it). The observation is a full pose, with
//                        the position's covariance from the report's (protocol 2.0: the platform's
//                        fused pose covariance; its translation block turned into the strip
//                        frame), so identification weights each row by it, and the full 6x6
//                        pose covariance (issue #26: position and rotation, in the dataset's
//                        convention and the strip frame), which the journal and the dataset
//                        carry. Given the platform camera's calibration with its intrinsics'
//                        covariance (issue #22: PlatformCamera, `kincal session --platform-camera`),
//                        the camera's share is added to that 6x6 (camera_share below).
//   StereoBeaconSensor   Kapucu & Baysec's rig: stereo_sensor.hpp.
//   BoardPoseSensor      a camera and a printed board: board_sensor.hpp.
//
// Thread safety: one session thread. Cost: one CAN round trip; with the camera's share, two
// planar_pose solves per non-zero eigenvalue of its covariance (at most 18 solves).
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "firmware/core/camera_model.hpp"
#include "host/can/platform_client.hpp"
#include "host/model/dataset.hpp"
#include "host/model/robot_model.hpp"
#include "host/session/session_error.hpp"

namespace kincal::session {

struct Observation {
  model::Vector3 position = model::Vector3::Zero();  // device frame, m
  std::optional<Eigen::Quaterniond> orientation;     // device_R_tool
  std::optional<model::Matrix3> covariance;          // of position, m^2
  // Of (x, y, z, rx, ry, rz): the position error (m) and the rotation error (rad, a rotation
  // vector on the left, in the device frame), as the dataset's 6x6 columns (dataset.hpp); its
  // position block is `covariance`.
  std::optional<model::Matrix6> pose_covariance;
  std::uint32_t sequence = 0;  // the platform's trigger sequence, if any
  double timestamp_s = 0;      // when the sensor saw it (sensor clock)
  std::string note;            // e.g. "square 3 (pose over 2 squares), 6 fiducials"
};

class Sensor {
 public:
  virtual ~Sensor() = default;
  // One observation at pose `index`; `predicted` is the nominal model's device_T_tool there.
  virtual Observation measure(int index, const model::Transform& predicted) = 0;
  virtual std::string name() const = 0;
  // What every observation carries (the journal's layout is fixed when it is created).
  virtual bool gives_orientation() const = 0;
  virtual bool gives_covariance() const = 0;
  // Every observation carries pose_covariance (a sensor that measures the full pose's 6x6).
  virtual bool gives_pose_covariance() const { return false; }
};

// sqrt(lambda_k) v_k for each eigenvalue lambda_k of `covariance` above 1e-12 of the largest (v_k
// its unit eigenvector): moving the parameters by +-1 sigma along each, the changes of a function
// of them sum, outer product by outer product, to its first-order covariance J C J^T. Errors:
// SessionError "<what> is not a finite symmetric matrix" / "<what> has a negative eigenvalue"
// (below -1e-9 of the largest).
template <int N>
std::vector<Eigen::Matrix<double, N, 1>> covariance_directions(const Eigen::Matrix<double, N, N>& covariance,
                                                               const std::string& what) {
  if (!covariance.allFinite() || !covariance.isApprox(covariance.transpose(), 1e-9))
    throw SessionError(what + " is not a finite symmetric matrix");
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eigen(covariance);
  const double largest = eigen.eigenvalues().cwiseAbs().maxCoeff();
  std::vector<Eigen::Matrix<double, N, 1>> directions;
  for (int k = 0; k < N; ++k) {
    const double lambda = eigen.eigenvalues()(k);
    if (lambda < -1e-9 * largest) throw SessionError(what + " has a negative eigenvalue");
    if (lambda > 1e-12 * largest) directions.push_back(std::sqrt(lambda) * eigen.eigenvectors().col(k));
  }
  return directions;
}

// The intrinsics in the order of a camera file's intrinsics_covariance (camera::kIntrinsicsOrder,
// host/camera/uncertainty.hpp): fx fy cx cy (px) k1 k2 p1 p2 k3.
using IntrinsicsVector = Eigen::Matrix<double, 9, 1>;
// `camera` with its intrinsics moved by `delta` (rounded to the model's float).
core::CameraIntrinsics moved_intrinsics(const core::CameraIntrinsics& camera, const IntrinsicsVector& delta);

// The platform's camera as calibrated, with how well it is known (issue #22).
struct PlatformCamera {
  core::CameraIntrinsics camera;  // as the platform takes it (camera::to_platform, camera_from_block)
  Eigen::Matrix<double, 9, 9> covariance = Eigen::Matrix<double, 9, 9>::Zero();  // IntrinsicsVector's order
  double fiducial_side_m;  // Doty's square's fiducial side s (host/target/doty_square.hpp)
};
// The camera file's camera and intrinsics_covariance (`kincal camera calibrate` writes both), with
// Doty's fiducial side (the default of platform.yaml's fiducial_side_m). Errors: the camera
// loader's (camera::CalibrationError naming the file and the key: a covariance that is not 9x9,
// not symmetric positive semi-definite, ...), also when the file has no intrinsics_covariance.
PlatformCamera load_platform_camera(const std::string& path);

// The camera's share of the pose square_T_camera's covariance (6x6 of (x, y, z, rx, ry, rz) in
// the report's convention and the square frame: the truth's error on the left, as
// strip_pose_covariance takes the report's): the fiducials' blob centroids the camera sees from
// that pose (Doty's six fiducials of the reference square, each image centroid as the platform's
// perspective pass models it) are solved again by the platform's own solver (firmware
// core::planar_pose, natively, the platform's options: 0.1 px, one perspective pass) under the
// intrinsics moved +-1 sigma along each eigenvector of the covariance; the share is
// sum_k (dpose_k)(dpose_k)^T with dpose_k half the two poses' difference. Approximated: the pose
// is solved from the image alone -- the platform fuses the rangers' plane as a prior (when it
// passes its gate), which the report does not carry and which holds depth and tilt against moved
// intrinsics, so the share in those directions is the image-only solve's (larger than the fused
// pose's where the prior holds it); the neighbour squares a protocol 3.0 pose also rests on, and
// fiducials the platform did not find, are left out (all six of the reference square are taken);
// the fiducial side is Doty's (a platform.yaml's own fiducial_side_m is not read). Zero
// covariance: exactly zero. Errors: SessionError when a fiducial leaves the camera's view model
// or a solve fails (its status).
model::Matrix6 camera_share(const PlatformCamera& camera, const model::Transform& square_T_camera);

class PlatformPoseSensor : public Sensor {
 public:
  // strip_T_square: every calibration square's pose in the strip frame. Puts the platform in
  // measuring mode (and clears its error flags); throws SessionError if it does not answer.
  // camera: the platform camera's calibration and its uncertainty (none: the camera taken as
  // exact, the report's covariance as it is); its covariance's directions are checked here
  // (covariance_directions' errors).
  PlatformPoseSensor(can::PlatformClient& client, std::vector<model::Transform> strip_T_square,
                     std::optional<PlatformCamera> camera = std::nullopt);
  Observation measure(int index, const model::Transform& predicted) override;
  std::string name() const override { return "sensor platform over CAN"; }
  bool gives_orientation() const override { return true; }
  bool gives_covariance() const override { return true; }
  bool gives_pose_covariance() const override { return true; }

  // The square k for which strip_T_square[k] * square_T_camera is nearest `predicted`.
  int measured_square(const model::Transform& square_T_camera, const model::Transform& predicted) const;

 private:
  can::PlatformClient& client_;
  std::vector<model::Transform> strip_T_square_;
  std::optional<PlatformCamera> camera_;
};

}  // namespace kincal::session

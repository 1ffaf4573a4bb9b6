// Calibration results on disk and into the platform (issue #6).
//
// Files are OpenCV YAML (cv::FileStorage), readable by OpenCV's own tools, with the keys
// OpenCV's samples use:
//   camera     camera_matrix (3x3), distortion_coefficients (1x5: k1 k2 p1 p2 k3),
//              image_width, image_height, avg_reprojection_error, nr_of_frames,
//              per_view_reprojection_errors, std_deviations_intrinsics (fx fy cx cy k1 k2 p1 p2 k3),
//              board (the board's text form), views (one map per image given: image, used
//              (0/1), corners, detector, rms_px, rejection -- an extra key OpenCV's loaders skip)
//              and issue #22's uncertainty, extra keys too: intrinsics_covariance (9x9, its
//              order in intrinsics_covariance_order: "fx fy cx cy k1 k2 p1 p2 k3"; px^2, px, 1;
//              the view poses marginalised, host/camera/uncertainty.hpp), corner_sigma_px (the
//              corner noise estimated from the residuals), projection_sigma_grid_px (12x16: the
//              worst-axis projection sigma in px at the pixels projection_sigma_grid_x_px (1x16)
//              and projection_sigma_grid_y_px (1x12), the centres of a 16x12 division of the
//              image; .nan where the model does not invert)
//   stereo     as stereo_calib.cpp: M1 D1 M2 D2 R T E F R1 R2 P1 P2 Q, plus image_width,
//              image_height, baseline_m, avg_reprojection_error, and when the calibration has
//              its uncertainty (both cameras' intrinsics covariances given) extra keys:
//              calibration_covariance (24x24: both cameras' intrinsics and right_T_left, its
//              order in calibration_covariance_order, host/camera/uncertainty.hpp) and
//              corner_sigma_px (the stereo solve's)
//   hand-eye   gripper_T_camera and base_T_target (4x4, metres), method (the refinement's start),
//              reprojection_rms_before_px, reprojection_rms_after_px
// Only the keys a loader needs are required; the rest are for people and other tools.
//
// A camera can also be written as ROS's camera_info YAML (camera_calibration_parsers, what
// camera_info_manager and image_proc load): image_width, image_height, camera_name,
// camera_matrix, distortion_model (plumb_bob: k1 k2 p1 p2 k3), distortion_coefficients,
// rectification_matrix (the identity: one camera) and projection_matrix ([K | 0], as
// CameraInfo's documentation gives for a monocular camera), each matrix as {rows, cols, data}.
// With the uncertainty given, the same extra keys as OpenCV YAML's follow ({rows, cols, data}
// matrices; camera_calibration_parsers reads the keys it knows by name and skips the rest). The
// views, when given, follow as YAML comments ("# view IMAGE: N corners, RMS X px, DETECTOR"),
// which ROS's parser skips. load_camera reads both (a file not starting with OpenCV's
// "%YAML:1.0" is read with yaml-cpp, so OpenCV's keys without that line and OpenCV's JSON read
// too), and a Kalibr camera chain of one camera (cam0: pinhole, radtan or none; a chain of several
// is refused, naming how many). Every file first passes files::check_yaml_text: at most
// kMaxYamlNodes nodes, no key given twice, one document. OpenCV XML is refused by name.
//
// Distortion, as other tools write it: kincal's camera is plumb_bob's (k1 k2 p1 p2 k3). A row or a
// column (OpenCV's calibration sample writes 5x1) of 4 (k3 = 0), 5, 8 (k4 k5 k6: OpenCV's rational
// model, ROS's rational_polynomial), 12 (s1..s4) or 14 (tx ty) coefficients is read when every term
// beyond k3 is 0; one that is not is refused naming it. A distortion_model key (either format) must
// be plumb_bob or rational_polynomial (equidistant, a fisheye, is refused); without one, plumb_bob,
// as ROS's camera_calibration_parsers read it. The same for a stereo file's D1 and D2.
//
// to_platform converts a camera to the firmware's camera block (shared::CameraIntrinsics, float
// and u16, as the platform stores it), so a host calibration loads into the platform as it is.
//
// Reading: every loader reads the file through files::read_text (input_file.hpp, kSettingsFile):
// a regular file of at most 16 MiB, UTF-8 (a byte-order mark accepted), CRLF accepted; a
// directory, device or FIFO, UTF-16/Latin-1 text or an empty file is refused by name.
//
// Errors: CalibrationError naming the file and, for a bad or missing key, the key ("PATH: key
// 'camera_matrix' missing or not a 3x3 matrix"); "cannot write" / "cannot read" for I/O.
// to_platform refuses (CalibrationError naming the parameter) a non-finite value, one beyond
// float's range, or an image size of 0 or above 65535.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "host/camera/hand_eye.hpp"
#include "host/camera/intrinsics.hpp"
#include "host/camera/stereo.hpp"
#include "shared/parameters.hpp"

namespace kincal::camera {

void save_camera(const std::string& path, const IntrinsicCalibration& calibration, const std::string& board_text);
void save_camera_ros(const std::string& path, const CameraModel& camera, const std::string& camera_name,
                     const std::vector<ViewReport>& views = {},
                     const std::optional<IntrinsicsCovariance>& uncertainty = std::nullopt);
// The camera of an OpenCV or ROS camera file, with or without the uncertainty keys.
CameraModel load_camera(const std::string& path);
// The intrinsics' covariance and corner sigma of a camera file (either format; `corners` and
// `parameters` are not stored and read as 0), or nullopt when the file has no
// intrinsics_covariance key (files of other tools, of kincal before issue #22, stereo files).
// Errors: as load_camera's, and CalibrationError naming the key when intrinsics_covariance is
// there but not 9x9, intrinsics_covariance_order is missing or another order, corner_sigma_px
// is missing, or the matrix is not symmetric with a non-negative diagonal.
std::optional<IntrinsicsCovariance> load_camera_uncertainty(const std::string& path);

void save_stereo(const std::string& path, const StereoCalibration& calibration);
// The cameras, R, T, E, F, the rectification, the RMS and, when the file has it, the
// uncertainty (pose_uncertainty; per-pair reports are not stored). Errors: as load_camera's, and
// CalibrationError naming the key when calibration_covariance is not 24x24, symmetric with a
// non-negative diagonal, or its order or corner_sigma_px is missing or another.
StereoCalibration load_stereo(const std::string& path);

void save_hand_eye(const std::string& path, const HandEyeCalibration& calibration);
// gripper_T_camera, base_T_target, the method and the RMS before and after.
HandEyeCalibration load_hand_eye(const std::string& path);

// The hand-eye found together with the kinematics (issue #26: `identify --hand-eye`): a
// calibrated model's tool and device registration in the keys `camera hand-eye` writes, so that
// the two can be compared. Mount hand (the camera on the flange, the board the measuring device):
// gripper_T_camera = flange_T_tool and base_T_target = frame0_T_device; mount world (the board
// on the flange, the camera the device): gripper_T_target and base_T_camera. "gripper" is the
// model's flange, "base" its frame 0; an identification has no reprojection RMS to write. The
// file's text (OpenCV YAML), for the caller to write with its other outputs.
std::string rig_hand_eye_text(bool camera_on_flange, const Eigen::Isometry3d& flange_T_tool,
                              const Eigen::Isometry3d& frame0_T_device);

shared::CameraIntrinsics to_platform(const CameraModel& camera);
CameraModel from_platform(const shared::CameraIntrinsics& intrinsics);

}  // namespace kincal::camera

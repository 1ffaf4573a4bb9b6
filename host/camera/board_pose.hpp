// A board's pose from one view, with its covariance (issue #26): what turns a camera and a printed
// board into a pose measurement of the arm that carries one of them.
//
// Pose: camera_T_board from the view's detected corners (board.hpp: refined corners, the whole
// board or nothing) through the camera's full lens model (pinhole with k1 k2 p1 p2 k3): OpenCV's
// solvePnP (SOLVEPNP_ITERATIVE) to start, then cv::solvePnPRefineLM (Levenberg-Marquardt on the
// reprojection error) to convergence.
//
// Covariance (6 x 6), order and convention (the dataset's, host/model/dataset.hpp):
//   (x, y, z, rx, ry, rz): the position error (m) and the rotation error (rad), both in the
//   camera frame; the rotation error d is a rotation vector applied on the left,
//   camera_R_board_estimated = exp([d]x) camera_R_board_true.
// It is sigma^2 (J^T J)^-1, J = d(reprojection) / d(pose) at the solution (cv::projectPoints'
// Jacobian, its rotation-vector columns mapped to d by the left Jacobian of SO(3)), with the
// corner noise sigma^2 = SSR / (2 N - 6) estimated from this view's residuals (N corners), plus,
// when the camera file carries the intrinsics' covariance C (uncertainty.hpp), G C G^T with
// G = -(J^T J)^-1 J^T J_intrinsics: how far the intrinsics' error moves the pose. The intrinsics'
// error is common to all views of one camera; this covariance is per view and says nothing of
// the correlation between views.
//
// Refused views (BoardPose::refusal, the view named; the pose is not used):
//   - the detection's own reason (pattern not found, too few corners, a board of another size);
//   - fewer than options.min_corners corners (the covariance needs 2 N - 6 well above 0);
//   - an outlier: the view's RMS reprojection error above
//     max(options.outlier_floor_px, options.outlier_over_sigma x the camera file's corner sigma)
//     (a bad detection, a moved or bent board; the intrinsics' own gate, intrinsics.hpp);
//   - edge-on: the board's normal more than options.max_tilt_rad (75 degrees) from the line of
//     sight to the board's centre (its corners then foreshorten to lines and the depth and the
//     tilt are barely separable).
// Errors: CalibrationError for a detection whose image size differs from the camera's (another
// camera or resolution, named) or whose corners lack board coordinates.
// Cost: one solvePnP and one LM refinement (a few iterations of a 6-parameter problem), one
// projectPoints with Jacobian: well under a millisecond for a 54-corner board.
#pragma once

#include <optional>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "host/camera/board.hpp"
#include "host/camera/intrinsics.hpp"
#include "host/camera/uncertainty.hpp"

namespace kincal::camera {

using PoseCovariance = Eigen::Matrix<double, 6, 6>;

struct BoardPoseOptions {
  int min_corners = 8;
  double outlier_floor_px = 0.5;
  double outlier_over_sigma = 3.0;
  double max_tilt_rad = 75.0 * 3.14159265358979323846 / 180.0;
};

struct BoardPose {
  std::string view;
  std::string refusal;  // empty when the pose is usable
  Eigen::Isometry3d camera_T_board = Eigen::Isometry3d::Identity();
  PoseCovariance covariance = PoseCovariance::Zero();  // see the header comment
  double rms_px = 0;                                   // RMS reprojection error
  double corner_sigma_px = 0;                          // sqrt(SSR / (2 N - 6))
  double tilt_rad = 0;                                 // board normal against the line of sight
  int corners = 0;
};

BoardPose board_pose(const BoardDetection& detection, const CameraModel& camera,
                     const std::optional<IntrinsicsCovariance>& intrinsics, const BoardPoseOptions& options = {});

// The covariance of the inverse pose (board_T_camera) in the same convention, in the inverse's
// frame: position and rotation errors of board_T_camera in the board frame.
PoseCovariance inverse_pose_covariance(const Eigen::Isometry3d& camera_T_board, const PoseCovariance& covariance);

// A usable view as the rig's pose measurement: with the camera on the flange (hand) the fixed
// board is the device frame and the measurement board_T_camera (the covariance carried over by
// inverse_pose_covariance); with the camera fixed (world) it is camera_T_board as it is.
struct PoseMeasurement {
  Eigen::Isometry3d device_T_tool = Eigen::Isometry3d::Identity();
  PoseCovariance covariance = PoseCovariance::Zero();
};
PoseMeasurement pose_measurement(const BoardPose& pose, bool camera_on_hand);

}  // namespace kincal::camera

// Hand-eye calibration (issue #6): where the camera sits on the gripper (gripper_T_camera), and
// where the board stands in the robot's base frame (base_T_target), from robot poses and images
// of a fixed board taken by a camera on the gripper (eye-in-hand, the sensor platform's case).
//
// What it does, in order, and how each step can refuse:
//  0. Another board than the one given in any view: refuse_wrong_board (intrinsics.hpp).
//  1. Per view: the board's pose in the camera (camera_T_target, cv::solvePnP with the camera
//     model). A view without the board, or whose pose fails, is left out with its reason.
//  2. Enough poses: at least options.min_poses usable views, else CalibrationError "N usable
//     poses ... at least M needed" listing the views left out (and the board they show, when
//     it is another one: seen_board_hint).
//  3. Rotation diversity (AX = XB is degenerate without it): over all pairs of poses, the
//     relative gripper rotation; the largest must reach options.min_rotation_rad, and among the
//     motions that reach it two axes must differ by options.min_axis_angle_rad or more.
//     Otherwise CalibrationError naming the value found and the minimum.
//  4. Convention: robot poses are base_T_gripper (OpenCV's "gripper2base") unless
//     options.convention says they are gripper_T_base ("base2gripper"). Both readings are
//     solved (Park) and judged by their AX = XB rotation residual; if the other reading fits
//     options.convention_ratio times better (and the given one is worse than 0.5 degrees), it is a
//     mix-up: CalibrationError saying which convention fits and both residuals.
//  5. cv::calibrateHandEye by Tsai, Park, Horaud, Andreff and Daniilidis, and
//     cv::calibrateRobotWorldHandEye by Shah and Li; each with its AX = XB residuals (RMS over
//     all pairs of poses of the rotation angle and translation of (A X)^-1 (X B)). An OpenCV solver
//     that throws (motions it cannot use) is CalibrationError "hand-eye calibration: OpenCV's
//     FUNCTION failed on the robot poses (its reason)", here and in step 4.
//  6. Refinement (Ceres, Levenberg-Marquardt): gripper_T_camera and base_T_target minimizing
//     the reprojection error of every board corner in every used view, starting from the
//     AX = XB method with the smallest rotation residual; RMS before and after are reported.
//  7. Consistency: poses and images that do not belong together (another run's poses, shifted
//     by one, the wrong camera) still give a solution; it is refused with CalibrationError and
//     the numbers when the refined AX = XB residual exceeds max_rotation_rms_rad or
//     max_translation_rms_m, or the reprojection RMS exceeds max_reprojection_rms_px. When
//     scaling the board's lengths by a factor k (|k - 1| > 1 %) brings the AX = XB translation
//     within max_translation_rms_m, the message says so and asks after the square size (a board
//     given at the wrong size fits the rotations and misses the translations).
// Robot poses are taken as exact (their errors are what the kinematic calibration finds).
// Cost: O(n^2) motions for the checks and residuals (n poses), O(m^2) in the m large motions for
// the axis check; the refinement is milliseconds for tens of views.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "host/camera/board.hpp"
#include "host/camera/intrinsics.hpp"

namespace kincal::camera {

enum class PoseConvention {
  kGripperToBase,  // poses are base_T_gripper (maps gripper coordinates to base coordinates)
  kBaseToGripper,  // poses are gripper_T_base
};
const char* convention_name(PoseConvention c);  // "gripper2base" / "base2gripper"

struct HandEyeView {
  std::string view;
  Eigen::Isometry3d robot_pose = Eigen::Isometry3d::Identity();  // in options.convention
  BoardDetection detection;
};

struct HandEyeOptions {
  PoseConvention convention = PoseConvention::kGripperToBase;
  int min_poses = 5;
  double min_rotation_rad = 20 * 3.14159265358979323846 / 180;
  double min_axis_angle_rad = 20 * 3.14159265358979323846 / 180;
  double convention_ratio = 5;
  double max_rotation_rms_rad = 2 * 3.14159265358979323846 / 180;
  double max_translation_rms_m = 0.02;
  double max_reprojection_rms_px = 5;
};

struct HandEyeEstimate {
  std::string method;
  Eigen::Isometry3d gripper_T_camera = Eigen::Isometry3d::Identity();
  double rotation_rms_rad = 0;  // AX = XB residuals
  double translation_rms_m = 0;
};

struct HandEyeViewReport {
  std::string view;
  bool used = false;
  std::string rejection;
  Eigen::Isometry3d camera_T_target = Eigen::Isometry3d::Identity();  // this view's own board pose
  // Used views, at the refined result (X = gripper_T_camera, W = base_T_target, H this view's
  // base_T_gripper, C its camera_T_target):
  //   refined_camera_T_target  X^-1 H^-1 W, where the refined chain puts the board;
  //   board_rms_px             the corners' reprojection RMS at C (the board pose's own fit);
  //   refined_rms_px           the corners' reprojection RMS at refined_camera_T_target;
  //   pair_rotation_rms_rad, pair_translation_rms_m   the AX = XB residual (step 5's measure)
  //                            over the pairs of poses holding this one;
  //   loop_rotation_rad, loop_translation_m   the AX = ZB loop closure W^-1 H X C: its angle and
  //                            the length of its translation.
  Eigen::Isometry3d refined_camera_T_target = Eigen::Isometry3d::Identity();
  double board_rms_px = 0, refined_rms_px = 0;
  double pair_rotation_rms_rad = 0, pair_translation_rms_m = 0;
  double loop_rotation_rad = 0, loop_translation_m = 0;
};

struct HandEyeCalibration {
  std::vector<HandEyeViewReport> views;
  int poses_used = 0;
  double largest_rotation_rad = 0;
  double largest_axis_angle_rad = 0;
  double other_convention_rotation_rms_rad = 0;  // step 4's residual of the other reading
  std::vector<HandEyeEstimate> methods;          // Tsai, Park, Horaud, Andreff, Daniilidis
  std::vector<HandEyeEstimate> robot_world;      // Shah, Li
  std::string start_method;
  Eigen::Isometry3d gripper_T_camera = Eigen::Isometry3d::Identity();  // refined
  Eigen::Isometry3d base_T_target = Eigen::Isometry3d::Identity();     // refined
  double rms_before_px = 0, rms_after_px = 0;
  double rotation_rms_rad = 0, translation_rms_m = 0;  // AX = XB residuals of the refined result
};

HandEyeCalibration calibrate_hand_eye(const std::vector<HandEyeView>& views, const CameraModel& camera,
                                      const HandEyeOptions& options = {});

std::string describe(const HandEyeCalibration& calibration);

}  // namespace kincal::camera

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
//  6. Refinement (Ceres, Levenberg-Marquardt; hand_eye_refinement.hpp): gripper_T_camera and
//     base_T_target minimizing the reprojection error of every board corner in every used view
//     through the chain, starting from the AX = XB method with the smallest rotation residual;
//     each robot pose gets a small correction with a prior whose width, like the corners' noise,
//     is estimated from the data (variance components): a motion capture's or a worn arm's pose
//     noise is not pushed into the hand-eye, and exact poses (a simulated robot) leave the
//     corrections at zero. options.correct_poses false holds the poses exact (the corners alone).
//     RMS before and after are reported (through the given, uncorrected poses), and the noise
//     scales found.
//  7. Consistency (issue #43: poor data give an answer with a warning, not a refusal). Refused
//     (CalibrationError with the numbers; the residuals judged are those of the refinement with the
//     poses held exact, exact_rotation_rms_rad), as plainly a mistake: poses shifted against the images
//     -- pairing each image with the pose up to kMaxShiftTested (3) rows before or after its own
//     fits options.convention_ratio times better (AX = XB rotation residual, Park; the given one
//     worse than 0.5 degrees) -- and an AX = XB rotation residual beyond
//     options.refuse_rotation_rms_rad, which no focal length or board size explains (poses of
//     another run). Otherwise the solution is returned, with HandEyeCalibration::warnings: the
//     residuals when beyond max_rotation_rms_rad, max_translation_rms_m or
//     max_reprojection_rms_px (what a good set stays within); and, when scaling the board's
//     lengths by a factor k (|k - 1| > 3 %) lowers the AX = XB translation residual by 30 % or
//     more, the likely cause with the scale the data suggest: the camera's focal length (k fx,
//     k fy: the board's distance scales with it) or the square size (k times the given). (Factory
//     intrinsics 13 % off left residuals within a good set's, 1.0 degrees / 16 mm / 4.7 px on the
//     simulated 8 views, the pose noise found 0.41 degrees / 7.2 mm: only the scale shows them.)
//     The refined result is then biased: the warning says what to fix.
//     The uncertainty comes with every result: gripper_T_camera's standard
//     deviations from the refinement (its normal matrix at the estimated noise scales) and how far
//     the AX = XB methods lie from the refined translation.
// Cost: O(n^2) motions for the checks and residuals (n poses), O(m^2) in the m large motions for
// the axis check; the refinement runs up to 20 rounds of a Ceres solve (hand_eye_refinement.hpp),
// and once more with the poses held exact for step 7.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "host/camera/board.hpp"
#include "host/camera/hand_eye_refinement.hpp"
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
  // What a good set stays within; beyond, a warning (step 7).
  double max_rotation_rms_rad = 2 * 3.14159265358979323846 / 180;
  double max_translation_rms_m = 0.02;
  double max_reprojection_rms_px = 5;
  // Beyond this AX = XB rotation residual, a refusal (step 7).
  double refuse_rotation_rms_rad = 10 * 3.14159265358979323846 / 180;
  // Step 6: the poses get corrections with an estimated noise (true), or are held exact (false).
  bool correct_poses = true;
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
  ChainNoise noise;      // step 6's estimated sigmas: corners (px), poses per axis (rad, m; 0 when exact)
  int noise_rounds = 0;  // its variance component rounds
  double rotation_rms_rad = 0, translation_rms_m = 0;  // AX = XB residuals of the refined result
  // The AX = XB residuals of the refinement with the poses held exact: what step 7's refusals judge
  // (pose corrections would absorb poses of another run); the refined result's own when
  // options.correct_poses is false.
  double exact_rotation_rms_rad = 0, exact_translation_rms_m = 0;
  // The refined gripper_T_camera's standard deviations per axis (step 7): rotation (rad) and
  // translation (m, in the gripper frame); the largest distance (m) of an AX = XB method's
  // translation from the refined one.
  std::array<double, 3> rotation_sigma_rad{}, translation_sigma_m{};
  double methods_spread_m = 0;
  std::vector<std::string> warnings;  // step 7: the residuals beyond a good set's and the likely cause
};

HandEyeCalibration calibrate_hand_eye(const std::vector<HandEyeView>& views, const CameraModel& camera,
                                      const HandEyeOptions& options = {});

std::string describe(const HandEyeCalibration& calibration);

}  // namespace kincal::camera

// Step 6 of calibrate_hand_eye (hand_eye.hpp, issue #43): the hand-eye and the board's place refined
// on the board corners through the chain, with the robot's (or motion capture's) poses treated as
// measurements that carry noise of their own, its size estimated from the data.
//
// Model (Gauss-Helmert written as a bundle adjustment with pose corrections, Triggs et al. 2000):
// view i's board is at camera_T_target_i = X^-1 (H_i D_i)^-1 W, X = gripper_T_camera, W =
// base_T_target, H_i the given base_T_gripper and D_i = [exp(rho_i) | tau_i] a small correction of
// it in the gripper frame. Three groups of residuals, each divided by its own sigma:
//   corners       the detected corner minus its projection (px), sigma_corner;
//   rho_i         the correction's rotation vector (rad), sigma_rotation (a prior rho_i ~ N(0, s^2 I));
//   tau_i         the correction's translation (m, gripper frame), sigma_translation.
// Without the corrections (poses exact) a noisy pose can only be explained by moving X and W, which
// biases both; with them, each pose yields as much as its noise says, and nothing when the corners
// demand it. The sigmas are not constants: Förstner's variance component estimation (Förstner 1979;
// Koch, "Parameter Estimation and Hypothesis Testing in Linear Models", 1999) sets each
// group's sigma^2 to its sum of squared raw residuals over its redundancy (the group's share of
// n - u: its rows minus the trace of N^-1 N_group, N the normal matrix), re-solving until the sigmas
// change by less than 1 % (at most 20 rounds). Poses that are exact (a simulated robot) drive their
// sigmas towards the floor (1e-6 rad, 1e-6 m: below any robot's or tracker's repeatability; VCE
// creeps there slowly, so the 20 rounds may end a little above it), where the result is the
// exact-pose refinement's.
//
// Start values come from the data: the corners' sigma from the views' own board poses (solvePnP:
// their SSR over 2 m - 6 n), the poses' from the AX = ZB loop closures W^-1 H_i X C_i of the start
// hand-eye (RMS angle and shift per axis).
//
// Cost: each round one Ceres solve (Levenberg-Marquardt, dense Schur with the corrections
// eliminated, warm-started) and one dense inverse of the (12 + 6 n)^2 normal matrix (n views); the
// shared AprilGrid/Vicon set's 30 views take 3 rounds, exact simulated poses up to 20 (poses held
// exact, correct_poses false: one round, the corners' scale moving no estimate). Errors:
// CalibrationError when Ceres reports an unusable solution.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Geometry>

#include "host/camera/board.hpp"
#include "host/camera/intrinsics.hpp"

namespace kincal::camera {

struct ChainNoise {
  double corner_px = 1;
  double pose_rotation_rad = 0, pose_translation_m = 0;  // per axis; zero when the poses are held exact
};

struct ChainRefinement {
  Eigen::Isometry3d gripper_T_camera = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d base_T_target = Eigen::Isometry3d::Identity();
  ChainNoise sigma;  // the estimated noise scales
  int rounds = 0;    // variance component rounds run
  // gripper_T_camera's standard deviations per axis at the estimated noise (the inverse of the
  // whitened normal matrix): rotation (rad) and translation (m, gripper frame); zero when that
  // matrix is singular (its inverse not finite; the noise scales are then not updated either).
  std::array<double, 3> rotation_sigma_rad{}, translation_sigma_m{};
};

// detections[i] is seen at base_T_gripper[i]. correct_poses false holds the poses exact: no
// corrections, only the corners' sigma is estimated (SSR / (2 m - 12)) and start's pose sigmas are
// ignored.
ChainRefinement refine_chain(const std::vector<const BoardDetection*>& detections,
                             const std::vector<Eigen::Isometry3d>& base_T_gripper, const CameraModel& camera,
                             const Eigen::Isometry3d& gripper_T_camera, const Eigen::Isometry3d& base_T_target,
                             const ChainNoise& start, bool correct_poses);

}  // namespace kincal::camera

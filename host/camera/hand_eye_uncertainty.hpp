// How well a hand-eye calibration is known from its own data (issue #43): a jackknife over the
// views. Each used view is left out in turn and the hand-eye solved again (calibrate_hand_eye with
// the same options); the spread of the n solutions, scaled by (n - 1) / n, is the covariance of
// gripper_T_camera (Efron & Stein's jackknife variance).
//
// Beside the refinement's own sigma (hand_eye_refinement.hpp: its normal matrix at the noise
// scales it estimates, the poses' included), a check that assumes no noise model. A motion
// capture's poses of a hand-held camera body (a few millimetres and tenths of a degree,
// interpolated between samples 50 ms apart) carry most of the error; on the shared AprilGrid/Vicon
// set (tests/bench/aprilgrid_real_bench.cpp) the refinement's is about 3/4 of the jackknife's per axis.
//
// Rotation: each solution's rotation as the rotation vector of full^-1 * solution (rad, in the
// full solution's camera frame); position: gripper_t_camera (m, gripper frame).
// Errors: none of its own; a leave-one-out solve that throws (its subset fails a gate the whole
// set passed) is not counted (`refused` says how many). Fewer than 3 solutions: counted = the
// number, covariances zero.
// Cost: one calibrate_hand_eye per used view.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "host/camera/hand_eye.hpp"

namespace kincal::camera {

struct HandEyeSpread {
  int counted = 0, refused = 0;
  Eigen::Matrix3d position_covariance_m2 = Eigen::Matrix3d::Zero();    // gripper_t_camera
  Eigen::Matrix3d rotation_covariance_rad2 = Eigen::Matrix3d::Zero();  // rotation vector, see above
};

HandEyeSpread hand_eye_jackknife(const std::vector<HandEyeView>& views, const CameraModel& camera,
                                 const HandEyeOptions& options, const HandEyeCalibration& full);

// One line: "gripper_T_camera uncertainty (jackknife over N views): position sigma x y z mm,
// rotation sigma x y z deg", or why there is none.
std::string describe(const HandEyeSpread& spread);

}  // namespace kincal::camera

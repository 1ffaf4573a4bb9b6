// Cartesian targets to joint readings by the calibrated model's inverse kinematics (issue #24).
//
// A target is a tool point, or a tool pose (point + device_R_tool or base_R_tool), in the robot's
// base frame (frame 0 of the calibrated chain) or in the measuring device's frame (placed in
// frame 0 by the calibrated model's base registration, base_T_frame0). The arm's configuration
// (elbow and wrist branch, turns) is kept from a seed: the target's own seed reading when it has
// one, else the caller's (commands pass the previous target's result, as a program moves). The
// seed first goes to the controller's nominal model (the readings its own inverse kinematics
// would give for the target, in the same branch), and the calibrated solve starts from that
// nominal solution, so the corrected readings are the nominal ones moved by the calibration.
// Both solves are pose_solver.hpp's (damped, limits respected, bounded iterations); when the
// nominal solve does not reach the target the calibrated one starts from the seed. Each returns,
// of the readings that reach the target, the ones nearest its start (pose_solver.hpp): a point
// target (orientation free: a 6-joint arm has three spare degrees of freedom) or a 7-joint arm
// gets the smallest change from the seed, never turns that cancel at the tool.
#pragma once

#include <span>
#include <string>

#include "host/correct/pose_solver.hpp"
#include "host/model/robot_model.hpp"

namespace kincal::correct {

enum class TargetFrame { base, device };

struct CartesianSolution {
  Solution calibrated;  // the readings to send; outcome as pose_solver.hpp
  Solution nominal;     // the controller model's readings for the same target
};

class CartesianSolver {
 public:
  // Throws model::InputError when the joint counts differ.
  CartesianSolver(const model::RobotModel& nominal, const model::RobotModel& calibrated, TargetFrame frame,
                  const SolveOptions& options = {});

  // `target` in the frame given at construction; seed.size() == joint_count (std::invalid_argument).
  CartesianSolution solve(const model::Transform& target, bool orientation, std::span<const double> seed) const;
  // Each solve alone, from `start` and nearest `reference` (empty: the start). solve() is the
  // nominal one from the seed, then the calibrated one from its solution.
  Solution solve_nominal(const model::Transform& target, bool orientation, std::span<const double> start) const;
  Solution solve_calibrated(const model::Transform& target, bool orientation, std::span<const double> start,
                            std::span<const double> reference = {}) const;

  // The calibrated model without its base registration: solutions are evaluated on it, in frame 0.
  const model::RobotModel& calibrated_arm() const { return calibrated_; }
  // The target in frame 0.
  model::Transform in_base(const model::Transform& target) const;
  // The solves' options (their joint units, tolerances).
  const SolveOptions& options() const { return options_; }

 private:
  model::RobotModel nominal_, calibrated_;
  model::Transform frame0_T_frame_;
  SolveOptions options_;
};

}  // namespace kincal::correct

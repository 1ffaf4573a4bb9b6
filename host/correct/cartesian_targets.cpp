#include "host/correct/cartesian_targets.hpp"

namespace kincal::correct {

CartesianSolver::CartesianSolver(const model::RobotModel& nominal, const model::RobotModel& calibrated,
                                 TargetFrame frame, const SolveOptions& options)
    : nominal_(nominal), calibrated_(calibrated), options_(options) {
  if (nominal.joint_count() != calibrated.joint_count())
    throw model::InputError("the nominal model has " + std::to_string(nominal.joint_count()) +
                            " joints, the calibrated one " + std::to_string(calibrated.joint_count()));
  if (frame == TargetFrame::device) frame0_T_frame_ = calibrated.base_T_frame0.inverse();
  nominal_.base_T_frame0 = model::Transform{};
  calibrated_.base_T_frame0 = model::Transform{};
}

model::Transform CartesianSolver::in_base(const model::Transform& target) const { return frame0_T_frame_ * target; }

CartesianSolution CartesianSolver::solve(const model::Transform& target, bool orientation,
                                         std::span<const double> seed) const {
  const model::Transform goal = in_base(target);
  CartesianSolution out;
  out.nominal = solve_pose(nominal_, goal, orientation, seed, options_);
  const std::span<const double> start = out.nominal.outcome == Outcome::reached ? out.nominal.q : seed;
  out.calibrated = solve_pose(calibrated_, goal, orientation, start, options_);
  return out;
}

}  // namespace kincal::correct

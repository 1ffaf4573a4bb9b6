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
  CartesianSolution out;
  out.nominal = solve_nominal(target, orientation, seed);
  out.calibrated =
      solve_calibrated(target, orientation, out.nominal.outcome == Outcome::reached ? out.nominal.q : seed);
  return out;
}

Solution CartesianSolver::solve_nominal(const model::Transform& target, bool orientation,
                                        std::span<const double> start) const {
  return solve_pose(nominal_, in_base(target), orientation, start, options_);
}

Solution CartesianSolver::solve_calibrated(const model::Transform& target, bool orientation,
                                           std::span<const double> start, std::span<const double> reference) const {
  return solve_pose(calibrated_, in_base(target), orientation, start, options_, reference);
}

}  // namespace kincal::correct

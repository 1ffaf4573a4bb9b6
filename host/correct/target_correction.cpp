#include "host/correct/target_correction.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include <Eigen/Geometry>

namespace kincal::correct {

namespace {

// The solves' joint units weigh a prismatic joint's metres against a revolute joint's radians as
// the limits do, so that the nearest readings they find are the smallest change by the limits.
JointCorrectionOptions in_limit_units(JointCorrectionOptions options, const JointChangeLimit& limit) {
  options.solve.prismatic_m_per_rad = limit.prismatic_m / limit.revolute_rad;
  return options;
}

}  // namespace

TargetCorrector::TargetCorrector(const model::RobotModel& nominal, const model::RobotModel& calibrated,
                                 TargetFrame frame, std::optional<ParameterCovariance> covariance,
                                 const JointCorrectionOptions& options, const JointChangeLimit& limit)
    : nominal_arm_(nominal),
      calibrated_(calibrated),
      frame_(frame),
      covariance_(std::move(covariance)),
      joints_(nominal, calibrated, in_limit_units(options, limit)),
      cartesian_(nominal, calibrated, frame, in_limit_units(options, limit).solve),
      limit_(limit),
      orientation_(options.orientation) {
  nominal_arm_.base_T_frame0 = model::Transform{};  // commands are in the robot's base frame
}

std::vector<TargetResult> TargetCorrector::correct(const std::vector<Target>& targets,
                                                   const std::vector<double>& first_seed, const std::string& source) {
  std::vector<TargetResult> results;
  results.reserve(targets.size());
  std::vector<double> seed = first_seed;
  for (const Target& t : targets) {
    TargetResult r;
    if (!t.cartesian) {
      const JointCorrection c = joints_.correct(t.q);
      r.solution = c.solution;
      r.platform_step_used = c.platform_step_used;
      r.refined = c.refined;
      r.nominal = t.q;
      judge_by_spread(r, false, orientation_);
      limit_change(r, t.q, joints_.calibrated_arm(), c.goal, false, orientation_);
    } else {
      const std::vector<double>& start = t.q.empty() ? seed : t.q;
      if (start.empty())
        model::fail_at(source, t.line,
                       "a Cartesian target with no seed reading: give q1..qN columns, a joint target before it, or "
                       "--seed");
      const Solution nominal = cartesian_.solve_nominal(t.pose, t.orientation, start);
      r.nominal = nominal.outcome == Outcome::reached ? nominal.q : start;
      // The reference: the target's own seed reading (what the user's controller goes to) when it
      // has one, else the controller's solution; the calibrated solve starts from the controller's
      // solution (a program and a table with the same seeds get the same readings) and returns the
      // readings nearest the reference.
      const std::vector<double>& reference = t.q.empty() ? r.nominal : t.q;
      r.solution = cartesian_.solve_calibrated(t.pose, t.orientation, r.nominal, reference);
      judge_by_spread(r, frame_ == TargetFrame::device, t.orientation);
      limit_change(r, reference, cartesian_.calibrated_arm(), cartesian_.in_base(t.pose), frame_ == TargetFrame::device,
                   t.orientation);
      r.command = model::forward_kinematics(nominal_arm_, r.solution.q);
    }
    if (covariance_)  // at the readings sent (the joint-change limit may have changed them)
      r.spread =
          predicted_spread(calibrated_, *covariance_, r.solution.q, t.cartesian && frame_ == TargetFrame::device);
    seed = r.nominal;
    results.push_back(std::move(r));
  }
  return results;
}

TargetCorrector::JointChange TargetCorrector::largest_change(const std::vector<double>& q,
                                                             const std::vector<double>& reference) const {
  JointChange out;
  for (std::size_t i = 0; i < reference.size() && i < q.size(); ++i) {
    const double change = std::abs(q[i] - reference[i]);
    const double limit =
        calibrated_.joints[i].type == core::JointType::prismatic ? limit_.prismatic_m : limit_.revolute_rad;
    if (change / limit <= out.over_limit) continue;
    out = {change / limit, static_cast<int>(i), change};
  }
  return out;
}

void TargetCorrector::judge_by_spread(TargetResult& r, bool with_base, bool orientation) const {
  if (!covariance_ || r.solution.outcome == Outcome::reached) return;
  const PoseSpread spread = predicted_spread(calibrated_, *covariance_, r.solution.q, with_base);
  if (r.solution.residual_m > kWithinSpread * spread.position_m ||
      (orientation && r.solution.residual_rad > kWithinSpread * spread.orientation_rad))
    return;
  r.short_of = r.solution.outcome;
  r.solution.outcome = Outcome::reached;
}

void TargetCorrector::limit_change(TargetResult& r, const std::vector<double>& reference, const model::RobotModel& arm,
                                   const model::Transform& goal, bool with_base, bool orientation) const {
  JointChange c = largest_change(r.solution.q, reference);
  if (c.over_limit > 1.0 || r.solution.outcome != Outcome::reached) {
    // The goal again, every joint held within its limit of the reference (the solver's joint
    // limits): followed from the reference (the branch it is on), else, for a goal reached past the
    // limit, from those readings (a redundant arm shares a change that put one joint just past it).
    model::RobotModel within = arm;
    bool box = true;
    for (std::size_t i = 0; i < within.joints.size() && i < reference.size(); ++i) {
      model::Joint& j = within.joints[i];
      // A hair inside the limit, so that a joint clamped at the box's edge counts as within it.
      const double l = (1.0 - 1e-9) * (j.type == core::JointType::prismatic ? limit_.prismatic_m : limit_.revolute_rad);
      j.lower = std::max(j.lower, reference[i] - l);
      j.upper = std::min(j.upper, reference[i] + l);
      box = box && j.lower <= j.upper;
    }
    // Held within the limit, a goal the unbounded solve met may be missed by what the model cannot
    // tell (near a singularity, a hundredth of a degree of its error is a tenth of a degree of a
    // joint): judged by the spread as any solve is.
    std::optional<Solution> nearest;  // the box solves' nearest miss (its spread only if refused)
    const auto take = [&](Solution solution) {
      TargetResult again = r;
      again.solution = std::move(solution);
      again.short_of.reset();
      judge_by_spread(again, with_base, orientation);
      const JointChange a = largest_change(again.solution.q, reference);
      if (a.over_limit <= 1.0 && (!nearest || again.solution.residual_m < nearest->residual_m))
        nearest = again.solution;
      if (again.solution.outcome != Outcome::reached || a.over_limit > 1.0) return false;
      again.refined = r.refined || r.platform_step_used;  // a joint target's readings: the Newton solve's now
      r = std::move(again);
      c = a;
      return true;
    };
    const SolveOptions& options = cartesian_.options();
    if (box && !take(solve_pose_along(within, goal, orientation, reference, options)) &&
        r.solution.outcome == Outcome::reached &&
        !take(solve_pose(within, goal, orientation, r.solution.q, options, reference))) {
      // Refused: the change named is the smallest found, the goal followed from the reference
      // without the box too (a solve landed on another branch would name that branch's change).
      const Solution along = solve_pose_along(arm, goal, orientation, reference, options);
      const JointChange a = largest_change(along.q, reference);
      if (along.outcome == Outcome::reached && a.over_limit < c.over_limit) c = a;
      if (nearest) {
        r.within_limit = {nearest->residual_m, nearest->residual_rad, std::nullopt};
        if (covariance_) r.within_limit->spread = predicted_spread(calibrated_, *covariance_, nearest->q, with_base);
      }
    }
  }
  r.change_over_limit = c.over_limit;
  r.change_joint = c.joint;
  r.change = c.change;
  if (r.change_over_limit <= 1.0 || r.solution.outcome != Outcome::reached) return;
  const Eigen::Matrix<double, 6, 1> correction = pose_residual(goal, model::forward_kinematics(arm, reference));
  r.solution.outcome = Outcome::joint_change_limit;
  r.short_of.reset();
  r.solution.q = reference;
  r.solution.residual_m = correction.head<3>().norm();
  r.solution.residual_rad = orientation ? correction.tail<3>().norm() : 0.0;
}

std::string summary_line(const std::vector<TargetResult>& results) {
  std::map<std::string, int> outcomes;
  int stepped = 0, refined = 0;
  double residual_m = 0.0, residual_rad = 0.0;
  std::vector<double> spread;
  for (const TargetResult& r : results) {
    ++outcomes[outcome_name(r.solution.outcome)];
    const bool reached = r.solution.outcome == Outcome::reached;  // a refused target's readings are its own
    stepped += reached && r.platform_step_used && !r.refined ? 1 : 0;
    refined += reached && r.refined ? 1 : 0;
    residual_m = std::max(residual_m, r.solution.residual_m);
    residual_rad = std::max(residual_rad, r.solution.residual_rad);
    if (r.spread) spread.push_back(r.spread->position_m);
  }
  std::string out = std::to_string(results.size()) + " targets:";
  const char* separator = " ";
  for (const auto& [name, count] : outcomes) {
    out += separator + std::to_string(count) + " " + name;
    separator = ", ";
  }
  char text[256];
  if (stepped > 0)  // the platform's step is named only where it ran
    std::snprintf(text, sizeof text,
                  " (joint targets reached: %d by the platform's step alone, %d by the Newton solve)", stepped,
                  refined);
  else
    std::snprintf(text, sizeof text, " (joint targets reached: %d by the Newton solve)", refined);
  out += text;
  std::snprintf(text, sizeof text, "; largest residual %.4f mm, %.4f mrad", residual_m * 1e3, residual_rad * 1e3);
  out += text;
  if (!spread.empty()) {
    std::sort(spread.begin(), spread.end());
    std::snprintf(text, sizeof text, "; predicted position sd median %.3f mm, max %.3f mm",
                  spread[spread.size() / 2] * 1e3, spread.back() * 1e3);
    out += text;
  }
  return out;
}

}  // namespace kincal::correct

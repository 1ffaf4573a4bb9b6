#include "host/correct/target_correction.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include <Eigen/Geometry>
#include <Eigen/SVD>

namespace kincal::correct {

namespace {

// Steps of the way from a target's reference readings to its correction at which the tool is
// checked (singular_turn): a 180 degree swing is looked at every 11 degrees.
constexpr int kLimitPathSteps = 16;

}  // namespace

TargetCorrector::TargetCorrector(const model::RobotModel& nominal, const model::RobotModel& calibrated,
                                 TargetFrame frame, std::optional<ParameterCovariance> covariance,
                                 const JointCorrectionOptions& options, const JointChangeLimit& limit)
    : nominal_arm_(nominal),
      calibrated_(calibrated),
      frame_(frame),
      covariance_(std::move(covariance)),
      joints_(nominal, calibrated, options),
      cartesian_(nominal, calibrated, frame, options.solve),
      limit_(limit),
      orientation_(options.orientation),
      rotation_weight_m_(options.solve.rotation_weight_m) {
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
      limit_change(r, t.q, joints_.calibrated_arm(), c.goal, orientation_);
    } else {
      const std::vector<double>& start = t.q.empty() ? seed : t.q;
      if (start.empty())
        model::fail_at(source, t.line,
                       "a Cartesian target with no seed reading: give q1..qN columns, a joint target before it, or "
                       "--seed");
      const CartesianSolution c = cartesian_.solve(t.pose, t.orientation, start);
      r.solution = c.calibrated;
      r.command = model::forward_kinematics(nominal_arm_, r.solution.q);
      r.nominal = c.nominal.outcome == Outcome::reached ? c.nominal.q : start;
      // The reference: the controller's solution, unless the target's own seed (the reading the
      // user's controller goes to) is farther from it than the limit -- then the seed.
      const bool seed_reference = !t.q.empty() && largest_change(r.nominal, t.q).over_limit > 1.0;
      limit_change(r, seed_reference ? t.q : r.nominal, cartesian_.calibrated_arm(), cartesian_.in_base(t.pose),
                   t.orientation);
      if (r.solution.outcome == Outcome::joint_change_limit)
        r.command = model::forward_kinematics(nominal_arm_, r.solution.q);
    }
    if (covariance_)
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

void TargetCorrector::limit_change(TargetResult& r, const std::vector<double>& reference, const model::RobotModel& arm,
                                   const model::Transform& goal, bool orientation) const {
  const JointChange c = largest_change(r.solution.q, reference);
  r.change_over_limit = c.over_limit;
  r.change_joint = c.joint;
  r.change = c.change;
  if (r.change_over_limit <= 1.0 || r.solution.outcome != Outcome::reached) return;
  const model::Transform from = model::forward_kinematics(arm, reference);
  const Eigen::Matrix<double, 6, 1> correction = pose_residual(goal, from);
  if (!singular_turn(r.solution.q, reference, c.over_limit, arm, from, correction, orientation)) {
    r.solution.outcome = Outcome::joint_change_limit;
    r.solution.q = reference;
    r.solution.residual_m = correction.head<3>().norm();
    r.solution.residual_rad = orientation ? correction.tail<3>().norm() : 0.0;
  }
}

bool TargetCorrector::singular_turn(const std::vector<double>& q, const std::vector<double>& reference,
                                    double over_limit, const model::RobotModel& arm, const model::Transform& from,
                                    const Eigen::Matrix<double, 6, 1>& correction, bool orientation) const {
  // First order, weighted as the solve: how much less the change moves the tool than the arm's
  // most effective turn of its size would. About 1 away from singularities (the limit stands);
  // large where the change is a singularity's turn (the limit is scaled by it).
  Eigen::MatrixXd j = model::joint_jacobian(arm, reference).topRows(orientation ? 6 : 3);
  if (orientation) j.bottomRows(3) *= rotation_weight_m_;
  Eigen::VectorXd dq(static_cast<Eigen::Index>(reference.size()));
  for (std::size_t i = 0; i < reference.size(); ++i) dq(static_cast<Eigen::Index>(i)) = q[i] - reference[i];
  const double felt = (j * dq).norm();
  const double most = Eigen::JacobiSVD<Eigen::MatrixXd>(j).singularValues()(0) * dq.norm();
  if (over_limit * felt > most) return false;
  // And in full: the tool's way from the reference to the solution, the readings moved in a
  // straight line (as a joint move goes), off the straight way to the goal by no more than the
  // correction's own size.
  const auto weighted = [&](Eigen::Matrix<double, 6, 1> e) {
    if (!orientation) e.tail<3>().setZero();
    return e.head<3>().norm() + rotation_weight_m_ * e.tail<3>().norm();
  };
  const double angle = correction.tail<3>().norm();  // pose_residual's rotation rows: angle times axis
  const model::Vector3 axis = angle > 0.0 ? model::Vector3(correction.tail<3>() / angle) : model::Vector3::UnitZ();
  double off_line = 0.0;
  std::vector<double> at(reference.size());
  for (int k = 1; k < kLimitPathSteps; ++k) {
    const double s = static_cast<double>(k) / kLimitPathSteps;
    for (std::size_t i = 0; i < at.size(); ++i) at[i] = reference[i] + s * (q[i] - reference[i]);
    model::Transform line;
    line.translation = from.translation + s * correction.head<3>();
    line.rotation = Eigen::AngleAxisd(s * angle, axis).toRotationMatrix() * from.rotation;
    off_line = std::max(off_line, weighted(pose_residual(line, model::forward_kinematics(arm, at))));
  }
  return off_line <= weighted(correction);
}

std::string summary_line(const std::vector<TargetResult>& results) {
  std::map<std::string, int> outcomes;
  int stepped = 0, refined = 0;
  double residual_m = 0.0, residual_rad = 0.0;
  std::vector<double> spread;
  for (const TargetResult& r : results) {
    ++outcomes[outcome_name(r.solution.outcome)];
    stepped += r.platform_step_used && !r.refined ? 1 : 0;
    refined += r.refined ? 1 : 0;
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
    std::snprintf(text, sizeof text, " (joint targets: %d by the platform's step alone, %d by the Newton solve)",
                  stepped, refined);
  else
    std::snprintf(text, sizeof text, " (joint targets: %d by the Newton solve)", refined);
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

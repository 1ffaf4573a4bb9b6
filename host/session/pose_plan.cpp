#include "host/session/pose_plan.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "host/model/dataset.hpp"

namespace kincal::session {

namespace {

bool within(const model::Joint& joint, double q) { return q >= joint.lower - 1e-12 && q <= joint.upper + 1e-12; }

}  // namespace

Configurations single_joint_sweeps(const model::RobotModel& model, const std::vector<double>& home,
                                   int readings_per_joint, double span_fraction) {
  if (static_cast<int>(home.size()) != model.joint_count())
    throw model::InputError("sweeps: home has " + std::to_string(home.size()) + " joints, the model " +
                            std::to_string(model.joint_count()));
  if (readings_per_joint < 4)
    throw model::InputError("sweeps: " + std::to_string(readings_per_joint) +
                            " readings per joint; a circle fit needs at least 4");
  if (!(span_fraction > 0 && span_fraction <= 1))
    throw model::InputError("sweeps: span fraction " + std::to_string(span_fraction) + " is not in (0, 1]");
  Configurations out;
  for (std::size_t j = 0; j < home.size(); ++j) {
    const model::Joint& joint = model.joints[j];
    if (!within(joint, home[j]))
      throw model::InputError("sweeps: home reading " + std::to_string(home[j]) + " of joint " + joint.name +
                              " is outside its limits");
    const bool limited = std::isfinite(joint.lower) && std::isfinite(joint.upper);
    if (!limited && joint.type == core::JointType::prismatic)
      throw model::InputError("sweeps: prismatic joint " + joint.name + " has no limits");
    const double range = limited ? joint.upper - joint.lower : 2 * std::numbers::pi;
    const double span = span_fraction * range;
    double first = home[j] - span / 2;
    if (limited) first = std::clamp(first, joint.lower, joint.upper - span);
    for (int k = 0; k < readings_per_joint; ++k) {
      std::vector<double> q = home;
      q[j] = first + span * k / (readings_per_joint - 1);
      out.push_back(std::move(q));
    }
  }
  return out;
}

Configurations read_plan(const model::RobotModel& model, const std::string& path) {
  Configurations plan = model::read_joints(path);
  if (plan.empty()) throw model::InputError(path + ": the plan has no poses");
  model::check_joint_count(model, static_cast<int>(plan.front().size()), path);
  for (std::size_t i = 0; i < plan.size(); ++i)
    for (std::size_t j = 0; j < plan[i].size(); ++j)
      if (!within(model.joints[j], plan[i][j]))
        throw model::InputError(path + ": pose " + std::to_string(i + 1) + ": joint " + model.joints[j].name +
                                " reading " + std::to_string(plan[i][j]) + " is outside its limits");
  return plan;
}

}  // namespace kincal::session

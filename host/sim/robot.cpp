#include "host/sim/robot.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/Core>

#include "host/identify/identify.hpp"

namespace kincal::sim {

bool is_angle(core::ParameterKind k) {
  return k == core::ParameterKind::link_theta || k == core::ParameterKind::link_alpha ||
         k == core::ParameterKind::link_beta ||
         (k >= core::ParameterKind::base_rx && k <= core::ParameterKind::base_rz) || k >= core::ParameterKind::tool_rx;
}

model::RobotModel perturbed(const model::RobotModel& nominal, std::mt19937_64& rng, const ErrorScale& s) {
  const model::RobotModel start = identify::reparameterize_for_identification(nominal, 0.1, nullptr);
  const std::vector<core::ParameterId> ids = model::all_parameters(start);
  Eigen::VectorXd e(static_cast<Eigen::Index>(ids.size()));
  std::normal_distribution<double> unit(0.0, 1.0);
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const bool base = ids[i].kind >= core::ParameterKind::base_x && ids[i].kind <= core::ParameterKind::base_rz;
    const double sigma =
        is_angle(ids[i].kind) ? (base ? s.base_angle_rad : s.angle_rad) : (base ? s.base_length_m : s.length_m);
    e(static_cast<Eigen::Index>(i)) = sigma * unit(rng);
  }
  return model::apply_parameter_errors(start, ids, e);
}

std::vector<double> random_configuration(const model::RobotModel& m, std::mt19937_64& rng) {
  std::vector<double> q;
  for (const model::Joint& j : m.joints) {
    const double lo = std::isfinite(j.lower) ? j.lower : -std::numbers::pi;
    const double hi = std::isfinite(j.upper) ? j.upper : std::numbers::pi;
    q.push_back(std::uniform_real_distribution<double>(lo, hi)(rng));
  }
  return q;
}

std::vector<std::vector<double>> random_configurations(const model::RobotModel& m, int count, std::mt19937_64& rng) {
  std::vector<std::vector<double>> qs;
  for (int i = 0; i < count; ++i) qs.push_back(random_configuration(m, rng));
  return qs;
}

SimulatedRobot::SimulatedRobot(model::RobotModel nominal, std::uint64_t seed, const ErrorScale& scale)
    : nominal_(std::move(nominal)) {
  std::mt19937_64 rng(seed);
  truth_ = perturbed(nominal_, rng, scale);
}

model::Transform SimulatedRobot::tool_pose(std::span<const double> q) const {
  if (static_cast<int>(q.size()) != nominal_.joint_count()) {
    throw std::invalid_argument("SimulatedRobot::tool_pose: " + std::to_string(q.size()) + " joint readings for the " +
                                std::to_string(nominal_.joint_count()) + " joints of '" + nominal_.name + "'");
  }
  for (std::size_t i = 0; i < q.size(); ++i) {
    const model::Joint& j = nominal_.joints[i];
    if (!std::isfinite(q[i]) || q[i] < j.lower || q[i] > j.upper) {
      throw std::invalid_argument("SimulatedRobot::tool_pose: joint " + std::to_string(i + 1) + " ('" + j.name +
                                  "') reading " + std::to_string(q[i]) + " is outside its limits [" +
                                  std::to_string(j.lower) + ", " + std::to_string(j.upper) + "]");
    }
  }
  return model::forward_kinematics(truth_, q);
}

}  // namespace kincal::sim

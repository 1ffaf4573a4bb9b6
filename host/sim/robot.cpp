#include "host/sim/robot.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/Core>

#include "host/identify/identify.hpp"

namespace kincal::sim {

Imperfections typical_imperfections(double reach_m) {
  Imperfections i;
  i.link_mass_kg_per_m = 60.0 * reach_m;  // a 2 m arm: 120 kg/m, a 0.5 m arm: 30 kg/m
  i.payload_kg = 10.0 * reach_m;
  // Sag about 1e-4 rad at full stretch: compliance = 1e-4 / (m g reach^2 / 2 + payload g reach).
  const double torque_Nm = (i.link_mass_kg_per_m * reach_m * reach_m / 2 + i.payload_kg * reach_m) * 9.81;
  i.compliance_rad_per_Nm = 1e-4 / torque_Nm;
  i.joint_repeatability_rad = 2e-5;
  i.position_jitter_m = 2e-5;
  return i;
}

double reach_m(const model::RobotModel& m) {
  double reach = m.flange_T_tool.translation.norm();
  for (const model::Joint& j : m.joints) reach += std::abs(j.parameters.a_m) + std::abs(j.parameters.d_m);
  return reach;
}

model::RobotModel with_imperfections(const model::RobotModel& truth, const Imperfections& imp) {
  model::RobotModel m = truth;
  const std::vector<double> zero(m.joints.size(), 0.0);
  const model::ChainAtJoints at = model::chain_at_joints(truth, zero);
  for (std::size_t i = 0; i < m.joints.size(); ++i) {
    model::Joint& j = m.joints[i];
    if (j.mass_kg == 0.0 && imp.link_mass_kg_per_m > 0.0) {
      const model::Transform& from = at.frames.base_T_frame[i];
      const model::Transform& to = at.frames.base_T_frame[i + 1];
      j.mass_kg = imp.link_mass_kg_per_m * (to.translation - from.translation).norm();
      j.centre_of_mass_m = to.inverse() * (0.5 * (from.translation + to.translation));
    }
    if (imp.compliance_rad_per_Nm > 0.0 && j.type == core::JointType::revolute)
      j.compliance = j.compliance.value_or(0.0) + imp.compliance_rad_per_Nm;
  }
  if (m.payload.mass_kg == 0.0 && imp.payload_kg > 0.0) {
    m.payload.mass_kg = imp.payload_kg;
    m.payload.centre_of_mass_m = m.flange_T_tool.translation;
  }
  return m;
}

model::RobotModel perturbed(const model::RobotModel& nominal, std::mt19937_64& rng, const ErrorScale& s) {
  const model::RobotModel start = identify::reparameterize_for_identification(nominal, 0.1, nullptr);
  const std::vector<core::ParameterId> ids = model::all_parameters(start);
  Eigen::VectorXd e(static_cast<Eigen::Index>(ids.size()));
  std::normal_distribution<double> unit(0.0, 1.0);
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const bool base = model::is_base_parameter(ids[i].kind);
    double sigma = model::is_angle_parameter(ids[i].kind) ? (base ? s.base_angle_rad : s.angle_rad)
                                                          : (base ? s.base_length_m : s.length_m);
    if (ids[i].kind == model::kJointScale || ids[i].kind == model::kJointCoupling) sigma = s.scale_sigma;
    if (ids[i].kind == model::kJointCompliance || model::is_gravity_direction_parameter(ids[i].kind)) sigma = 0.0;
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

SimulatedRobot::SimulatedRobot(model::RobotModel nominal, std::uint64_t seed, const ErrorScale& scale,
                               const Imperfections& imperfections)
    : nominal_(std::move(nominal)), imperfections_(imperfections), seed_(seed) {
  std::mt19937_64 rng(seed);
  truth_ = with_imperfections(perturbed(nominal_, rng, scale), imperfections);
}

model::Transform SimulatedRobot::visit_pose(std::span<const double> q, std::uint64_t visit) const {
  if (imperfections_.joint_repeatability_rad == 0.0 && imperfections_.position_jitter_m == 0.0)
    return model::forward_kinematics(truth_, q);
  const auto low = [](std::uint64_t v) { return static_cast<std::uint32_t>(v & 0xffffffffu); };
  std::seed_seq seq{low(seed_), low(seed_ >> 32), low(visit), low(visit >> 32), std::uint32_t{0x72657065u}};
  std::mt19937_64 rng(seq);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::vector<double> off(q.begin(), q.end());
  for (double& v : off) v += imperfections_.joint_repeatability_rad * unit(rng);
  model::Transform t = model::forward_kinematics(truth_, off);
  for (int k = 0; k < 3; ++k) t.translation(k) += imperfections_.position_jitter_m * unit(rng);
  return t;
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

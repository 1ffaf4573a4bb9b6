#include "host/correct/joint_offsets.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Cholesky>

#include "host/model/number_text.hpp"

namespace kincal::correct {

namespace {

double joint_zero(const core::Link<double>& link) {
  return link.joint == core::JointType::prismatic ? link.parameters.d_m : link.parameters.theta_rad;
}

ArmErrors errors_of(const std::vector<double>& lengths_m) {
  ArmErrors e;
  double sum = 0.0;
  for (double v : lengths_m) {
    sum += v * v;
    e.max_m = std::max(e.max_m, v);
  }
  e.rms_m = lengths_m.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(lengths_m.size()));
  return e;
}

// The three arms' tool points against `truth(q, row)` over the readings.
template <class Truth>
OffsetShare share(const model::RobotModel& nominal, const model::RobotModel& calibrated,
                  const std::vector<double>& offsets, const std::vector<std::vector<double>>& readings, Truth truth) {
  model::RobotModel registered = nominal;
  registered.base_T_frame0 = calibrated.base_T_frame0;
  registered.flange_T_tool = calibrated.flange_T_tool;
  const model::RobotModel with_offsets = offsets_only_model(nominal, calibrated, offsets);
  std::vector<double> a, b, c;
  for (std::size_t i = 0; i < readings.size(); ++i) {
    const model::Vector3 p = truth(readings[i], i);
    a.push_back((model::forward_kinematics(registered, readings[i]).translation - p).norm());
    b.push_back((model::forward_kinematics(with_offsets, readings[i]).translation - p).norm());
    c.push_back((model::forward_kinematics(calibrated, readings[i]).translation - p).norm());
  }
  OffsetShare s;
  s.rows = static_cast<int>(readings.size());
  s.nominal = errors_of(a);
  s.offsets_only = errors_of(b);
  s.calibrated = errors_of(c);
  const double gain = s.nominal.rms_m - s.calibrated.rms_m;
  s.carried = gain > 0.0 ? (s.nominal.rms_m - s.offsets_only.rms_m) / gain : 0.0;
  return s;
}

// A radian (or metre) of offset away from the zero change costs as much as this much tool
// displacement at every reading.
constexpr double kPrior_m = 0.01;

std::vector<std::vector<double>> random_readings(const model::RobotModel& model, int samples, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<std::vector<double>> readings(static_cast<std::size_t>(samples));
  for (std::vector<double>& q : readings)
    for (const model::Joint& j : model.joints) {
      const double span = j.type == core::JointType::prismatic ? 0.5 : std::numbers::pi;
      const double lo = std::isfinite(j.lower) ? j.lower : -span, hi = std::isfinite(j.upper) ? j.upper : span;
      q.push_back(std::uniform_real_distribution<double>(lo, hi)(rng));
    }
  return readings;
}

}  // namespace

std::vector<double> fitted_joint_offsets(const model::RobotModel& nominal, const model::RobotModel& calibrated,
                                         int samples, std::uint64_t seed) {
  const std::vector<double> zero_changes = joint_offsets(nominal, calibrated);
  std::vector<double> offsets = zero_changes;
  const std::vector<std::vector<double>> readings = random_readings(calibrated, samples, seed);
  std::vector<core::ParameterId> ids;
  for (std::size_t j = 0; j < nominal.joints.size(); ++j)
    ids.push_back({nominal.joints[j].type == core::JointType::prismatic ? core::ParameterKind::link_d
                                                                        : core::ParameterKind::link_theta,
                   static_cast<std::uint8_t>(j)});
  const auto n = static_cast<Eigen::Index>(ids.size());
  for (int iteration = 0; iteration < 8; ++iteration) {
    const model::RobotModel m = offsets_only_model(nominal, calibrated, offsets);
    Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
    for (const std::vector<double>& q : readings) {
      const Eigen::MatrixXd e = model::parameter_jacobian(m, q, ids).topRows(3);
      const Eigen::Vector3d r =
          model::forward_kinematics(calibrated, q).translation - model::forward_kinematics(m, q).translation;
      normal += e.transpose() * e;
      rhs += e.transpose() * r;
    }
    // The prior: a joint that hardly moves the tool point (a wrist turning a probe on its axis)
    // keeps its zero change rather than a value the points cannot tell.
    const double prior = kPrior_m * kPrior_m * static_cast<double>(readings.size());
    normal.diagonal().array() += prior;
    for (Eigen::Index k = 0; k < n; ++k)
      rhs(k) += prior * (zero_changes[static_cast<std::size_t>(k)] - offsets[static_cast<std::size_t>(k)]);
    const Eigen::VectorXd step = normal.ldlt().solve(rhs);
    for (Eigen::Index k = 0; k < n; ++k) offsets[static_cast<std::size_t>(k)] += step(k);
    if (step.lpNorm<Eigen::Infinity>() < 1e-12) break;
  }
  return offsets;
}

std::vector<double> joint_offsets(const model::RobotModel& nominal, const model::RobotModel& calibrated) {
  if (nominal.joint_count() != calibrated.joint_count())
    throw model::InputError("the nominal model has " + std::to_string(nominal.joint_count()) +
                            " joints, the calibrated one " + std::to_string(calibrated.joint_count()));
  const core::ChainModel<double> a = model::to_chain(nominal), b = model::to_chain(calibrated);
  std::vector<double> offsets;
  for (int j = 0; j < nominal.joint_count(); ++j) {
    const core::Link<double>&la = a.links[static_cast<std::size_t>(j)], &lb = b.links[static_cast<std::size_t>(j)];
    if (la.joint != lb.joint || la.convention != lb.convention)
      throw model::InputError("joint " + std::to_string(j + 1) +
                              " differs in type or link convention between the nominal and the calibrated model: "
                              "its zero cannot be compared (leave out --nominal to take the calibration record's)");
    offsets.push_back(joint_zero(lb) - joint_zero(la));
  }
  return offsets;
}

model::RobotModel offsets_only_model(const model::RobotModel& nominal, const model::RobotModel& calibrated,
                                     const std::vector<double>& offsets) {
  model::RobotModel m = nominal;
  for (std::size_t j = 0; j < m.joints.size() && j < offsets.size(); ++j) m.joints[j].offset += offsets[j];
  m.base_T_frame0 = calibrated.base_T_frame0;
  m.flange_T_tool = calibrated.flange_T_tool;
  return m;
}

OffsetShare offset_share(const model::RobotModel& nominal, const model::RobotModel& calibrated,
                         const std::vector<double>& offsets, const model::Dataset& data) {
  model::check_joint_count(calibrated, data.joint_count, data.source);
  std::vector<std::vector<double>> readings;
  for (const model::Measurement& m : data.rows) readings.push_back(m.q);
  return share(nominal, calibrated, offsets, readings,
               [&](const std::vector<double>&, std::size_t i) { return data.rows[i].position; });
}

OffsetShare offset_share(const model::RobotModel& nominal, const model::RobotModel& calibrated,
                         const std::vector<double>& offsets, int samples, std::uint64_t seed) {
  const std::vector<std::vector<double>> readings = random_readings(calibrated, samples, seed);
  return share(nominal, calibrated, offsets, readings, [&](const std::vector<double>& q, std::size_t) {
    return model::forward_kinematics(calibrated, q).translation;
  });
}

std::string write_joint_offsets(const model::RobotModel& calibrated, const std::vector<double>& offsets) {
  std::string out =
      "# kincal joint-offsets of '" + calibrated.name +
      "': per-joint zero offsets (rad for a revolute joint, m for a prismatic one),\n"
      "# fitted to the calibrated arm's tool over readings within the limits.\n"
      "# The calibrated arm at reading r is where the nominal model puts it at r + offset: a controller that\n"
      "# computes joint angle = encoder angle + offset takes them as they are; one that subtracts takes -offset.\n"
      "joint,name,type,offset\n";
  for (std::size_t j = 0; j < offsets.size(); ++j) {
    const model::Joint& joint = calibrated.joints[j];
    out += std::to_string(j + 1) + "," + joint.name + "," +
           (joint.type == core::JointType::prismatic ? "prismatic" : "revolute") + "," +
           model::shortest_number_text(offsets[j]) + "\n";
  }
  return out;
}

}  // namespace kincal::correct

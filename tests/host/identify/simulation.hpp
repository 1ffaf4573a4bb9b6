// Simulated robots and measurements for the identification tests and benchmarks: a true robot
// drawn around a nominal model, random configurations within the limits, noisy measurements.
#pragma once

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "host/identify/identify.hpp"
#include "host/model/dataset.hpp"
#include "host/model/robot_model.hpp"

namespace kincal::simulation {

struct ErrorScale {
  double length_m = 1e-3;
  double angle_rad = 0.1 * std::numbers::pi / 180.0;
  double base_length_m = 5e-3;
  double base_angle_rad = 0.5 * std::numbers::pi / 180.0;
};

inline bool is_angle(core::ParameterKind k) {
  return k == core::ParameterKind::link_theta || k == core::ParameterKind::link_alpha ||
         k == core::ParameterKind::link_beta ||
         (k >= core::ParameterKind::base_rx && k <= core::ParameterKind::base_rz) || k >= core::ParameterKind::tool_rx;
}

// The true robot: every parameter of the (reparameterized) nominal model off by a Gaussian error.
inline model::RobotModel perturbed(const model::RobotModel& nominal, std::mt19937_64& rng, const ErrorScale& s = {}) {
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

inline std::vector<double> random_configuration(const model::RobotModel& m, std::mt19937_64& rng) {
  std::vector<double> q;
  for (const model::Joint& j : m.joints) {
    const double lo = std::isfinite(j.lower) ? j.lower : -std::numbers::pi;
    const double hi = std::isfinite(j.upper) ? j.upper : std::numbers::pi;
    q.push_back(std::uniform_real_distribution<double>(lo, hi)(rng));
  }
  return q;
}

// Measurements of `truth` at the configurations: position noise sigma_m per axis (recorded as
// the sigma column when record_sigma), orientation noise sigma_rad (rotation vector per axis)
// when `pose`.
inline model::Dataset measure(const model::RobotModel& truth, const std::vector<std::vector<double>>& configurations,
                              std::mt19937_64& rng, double sigma_m, bool pose, double sigma_rad, bool record_sigma) {
  model::Dataset d;
  d.source = "simulated";
  d.joint_count = truth.joint_count();
  d.has_orientation = pose;
  d.noise = record_sigma ? model::NoiseColumns::sigma : model::NoiseColumns::none;
  std::normal_distribution<double> unit(0.0, 1.0);
  int line = 2;
  for (const auto& q : configurations) {
    const model::Transform t = model::forward_kinematics(truth, q);
    model::Measurement m;
    m.q = q;
    m.line = line++;
    m.position = t.translation + sigma_m * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    if (pose) {
      const Eigen::Vector3d r = sigma_rad * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
      const Eigen::Matrix3d noise =
          r.norm() > 0 ? Eigen::AngleAxisd(r.norm(), r.normalized()).toRotationMatrix() : Eigen::Matrix3d::Identity();
      m.orientation = Eigen::Quaterniond(noise * t.rotation);
    }
    if (record_sigma) m.covariance = Eigen::Matrix3d::Identity() * sigma_m * sigma_m;
    d.rows.push_back(m);
  }
  return d;
}

inline std::vector<std::vector<double>> random_configurations(const model::RobotModel& m, int count,
                                                              std::mt19937_64& rng) {
  std::vector<std::vector<double>> qs;
  for (int i = 0; i < count; ++i) qs.push_back(random_configuration(m, rng));
  return qs;
}

// RMS distance between two models' tool points over configurations.
inline double prediction_rms(const model::RobotModel& a, const model::RobotModel& b,
                             const std::vector<std::vector<double>>& configurations) {
  double sum = 0.0;
  for (const auto& q : configurations)
    sum += (model::forward_kinematics(a, q).translation - model::forward_kinematics(b, q).translation).squaredNorm();
  return std::sqrt(sum / static_cast<double>(configurations.size()));
}

}  // namespace kincal::simulation

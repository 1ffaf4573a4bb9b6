// Simulated measurements for the identification tests and benchmarks: noisy point or pose
// measurements of a true robot, and the prediction error between two models (tool points, and
// flange orientations). The true robot and the configurations come from the simulator
// (host/sim/robot.hpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "host/identify/prior.hpp"
#include "host/identify/problem.hpp"
#include "host/model/dataset.hpp"
#include "host/model/model_file.hpp"
#include "host/model/robot_model.hpp"
#include "host/sim/robot.hpp"

namespace kincal::simulation {

// `prior` with no prior on any link's mass or centre of mass or any joint's compliance (mass<i>,
// com_*<i>, compliance<i>) of a model with `joints` joints: geometry+sag's terms free, as they were
// before their priors (issue #41).
inline void free_sag_priors(identify::PriorOptions& prior, std::size_t joints) {
  for (std::size_t i = 1; i <= joints; ++i)
    for (const char* p : {"mass", "com_x", "com_y", "com_z", "compliance"})
      prior.sigma.emplace_back(p + std::to_string(i), std::numeric_limits<double>::infinity());
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

// Single-joint sweeps: joint j takes the readings readings[j] in turn, the others stay at home.
inline std::vector<std::vector<double>> single_joint_sweeps(const std::vector<double>& home,
                                                            const std::vector<std::vector<double>>& readings) {
  std::vector<std::vector<double>> qs;
  for (std::size_t j = 0; j < readings.size(); ++j)
    for (double r : readings[j]) {
      std::vector<double> q = home;
      q[j] = r;
      qs.push_back(q);
    }
  return qs;
}

// The Cramer-Rao bound on the squared tool-point error of a model identified from noise-free
// rows `exact` with weights `w` (whitening the true noise), summed over held-out
// configurations: sum of trace(J_q F^-1 J_q^T), F = J^T J the Fisher information of the
// parameters `ids` at the truth (held-fixed parameters change nothing the data can see).
inline double prediction_bound(const model::RobotModel& truth, const identify::ParameterIds& ids,
                               const model::Dataset& exact, const identify::Weights& w,
                               const std::vector<std::vector<double>>& held_out) {
  identify::Parameterization at_truth(truth, ids);
  std::vector<int> rows(exact.rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) rows[i] = static_cast<int>(i);
  Eigen::VectorXd residual;
  Eigen::MatrixXd j;
  identify::stacked(at_truth, exact, w, rows, residual, &j);
  const Eigen::LDLT<Eigen::MatrixXd> information(j.transpose() * j);
  double bound = 0.0;
  for (const auto& q : held_out) {
    Eigen::MatrixXd jq;
    (void)at_truth.pose(q, &jq);
    const Eigen::MatrixXd p = jq.topRows(3);
    bound += (p * information.solve(p.transpose())).trace();
  }
  return bound;
}

// Single-joint sweeps around a home configuration: `per_joint` readings of each joint in turn,
// evenly over `fraction` of its range, centred on home.
inline std::vector<std::vector<double>> sweeps(const model::RobotModel& m, const std::vector<double>& home,
                                               int per_joint, double fraction) {
  std::vector<std::vector<double>> qs;
  for (std::size_t j = 0; j < m.joints.size(); ++j) {
    const double span = fraction * (m.joints[j].upper - m.joints[j].lower);
    for (int k = 0; k < per_joint; ++k) {
      std::vector<double> q = home;
      q[j] = home[j] - 0.5 * span + span * k / (per_joint - 1);
      qs.push_back(q);
    }
  }
  return qs;
}

// The simulated sagging sweep set (issue #23: the class where rejection cost held out): a
// perturbed `nominal` (seed) that sags under gravity, 0.5 mm at full torque on joints 2 and 3 and
// not in the model, with 0.05 mm of repeatability and the tracker's 0.01 mm as covariance;
// trained on `per_joint` readings of each joint's sweep over 80 % of its range (6 on a 6R: 36
// readings), judged on 100 random configurations.
struct SaggingSweeps {
  model::Dataset train, held_out;
};
inline SaggingSweeps sagging_sweeps(const model::RobotModel& nominal, std::uint64_t seed, int per_joint) {
  std::mt19937_64 rng(seed);
  const model::RobotModel truth = sim::perturbed(nominal, rng);
  std::vector<double> home;
  for (const auto& j : nominal.joints) home.push_back(0.5 * (j.lower + j.upper) + 0.1);
  const auto measure = [&](const std::vector<std::vector<double>>& qs) {
    model::Dataset d = simulation::measure(truth, qs, rng, 5e-5, false, 0.0, false);
    d.noise = model::NoiseColumns::covariance;
    for (model::Measurement& m : d.rows) {
      m.position.z() -= 5e-4 * (std::cos(m.q[1]) + 0.6 * std::cos(m.q[1] + m.q[2]));
      m.covariance = Eigen::Matrix3d::Identity() * 1e-10;
    }
    return d;
  };
  SaggingSweeps s;
  s.train = measure(sweeps(nominal, home, per_joint, 0.8));
  s.held_out = measure(sim::random_configurations(nominal, 100, rng));
  return s;
}

// A service robot's arm (issue #41's class): a prismatic torso lift and a 7-joint arm (shoulder
// pan and lift, upper-arm roll, elbow, forearm roll, wrist flex and roll), in a motion-capture
// frame, the marker 12 cm off the flange and off the last axis. Plausible dimensions, no maker's.
inline model::RobotModel service_arm() {
  return model::parse_model(
      "name: service-arm\n"
      "angles: deg\n"
      "base:\n"
      "  translation: [0.4, -0.2, 0.05]\n"
      "  rpy: [0, 0, 30]\n"
      "joints:\n"
      "  - {type: prismatic, convention: dh, d: 0.75, theta: 0, a: 0.05, alpha: 0, limits: [0, 0.35]}\n"
      "  - {type: revolute, convention: dh, d: 0.1, theta: 0, a: 0.1, alpha: -90, limits: [-100, 100]}\n"
      "  - {type: revolute, convention: dh, d: 0, theta: 0, a: 0, alpha: 90, limits: [-60, 80]}\n"
      "  - {type: revolute, convention: dh, d: 0.35, theta: 0, a: 0, alpha: -90, limits: [-160, 160]}\n"
      "  - {type: revolute, convention: dh, d: 0, theta: 0, a: 0, alpha: 90, limits: [-130, -5]}\n"
      "  - {type: revolute, convention: dh, d: 0.32, theta: 0, a: 0, alpha: -90, limits: [-160, 160]}\n"
      "  - {type: revolute, convention: dh, d: 0, theta: 0, a: 0, alpha: 90, limits: [-120, -5]}\n"
      "  - {type: revolute, convention: dh, d: 0.08, theta: 0, a: 0, alpha: 0, limits: [-170, 170]}\n"
      "tool:\n"
      "  point: [0.03, 0.02, 0.12]\n",
      "service-arm");
}

// An arm of a given error class measured at random configurations: the truth drawn around
// `nominal` (sim::perturbed with `errors`), `rows` noisy position rows (noise_m per axis, no
// sigma column: the noise is for identify to estimate), and `held_out` further configurations
// to judge a model against the truth.
struct ArmCase {
  model::RobotModel truth;
  model::Dataset train;
  std::vector<std::vector<double>> held_out;
};
inline ArmCase simulated_arm(const model::RobotModel& nominal, const sim::ErrorScale& errors, double noise_m, int rows,
                             std::uint64_t seed, int held_out = 200) {
  std::mt19937_64 rng(seed);
  ArmCase c;
  c.truth = sim::perturbed(nominal, rng, errors);
  c.train = measure(c.truth, sim::random_configurations(nominal, rows, rng), rng, noise_m, false, 0.0, false);
  c.held_out = sim::random_configurations(nominal, held_out, rng);
  return c;
}

// RMS distance between two models' tool points over configurations.
inline double prediction_rms(const model::RobotModel& a, const model::RobotModel& b,
                             const std::vector<std::vector<double>>& configurations) {
  double sum = 0.0;
  for (const auto& q : configurations)
    sum += (model::forward_kinematics(a, q).translation - model::forward_kinematics(b, q).translation).squaredNorm();
  return std::sqrt(sum / static_cast<double>(configurations.size()));
}

// The flange's orientation in the device frame: the tool pose less the flange-to-tool turn.
inline Eigen::Matrix3d flange_rotation(const model::RobotModel& m, const std::vector<double>& q) {
  return model::forward_kinematics(m, q).rotation * m.flange_T_tool.rotation.transpose();
}

struct FlangeDifference {
  double largest_rad = 0.0, rms_rad = 0.0;
};

// The angles (rad) between the two models' flange orientations over the rows, less their mean turn.
inline FlangeDifference flange_difference(const model::RobotModel& a, const model::RobotModel& b,
                                          const model::Dataset& rows) {
  std::vector<Eigen::Matrix3d> turn;
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  for (const model::Measurement& m : rows.rows) {
    turn.push_back(flange_rotation(a, m.q).transpose() * flange_rotation(b, m.q));
    sum += turn.back();
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d mean = svd.matrixU() * svd.matrixV().transpose();  // the rotation nearest the mean
  if (mean.determinant() < 0) mean = -mean;
  FlangeDifference out;
  for (const Eigen::Matrix3d& t : turn) {
    const double angle = identify::so3_log(mean.transpose() * t).norm();
    out.largest_rad = std::max(out.largest_rad, angle);
    out.rms_rad += angle * angle;
  }
  out.rms_rad = std::sqrt(out.rms_rad / static_cast<double>(turn.size()));
  return out;
}

}  // namespace kincal::simulation

#include "sample_report.hpp"

#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Geometry>

namespace kincal::report::testing {

namespace {

constexpr double kPi = std::numbers::pi;

void add_joint_rows(Run& run, std::mt19937_64& rng, int joint, double d, double a, double alpha) {
  std::normal_distribution<double> n(0.0, 1.0);
  const std::string group = "joint " + std::to_string(joint);
  const struct {
    const char* name;
    Quantity quantity;
    double nominal, error, sigma;
  } rows[] = {{"theta", Quantity::angle_rad, 0.0, 2e-3, 4e-5},
              {"d", Quantity::length_m, d, 1e-3, 2e-5},
              {"a", Quantity::length_m, a, -8e-4, 1.5e-5},
              {"alpha", Quantity::angle_rad, alpha, 1e-3, 3e-5}};
  for (const auto& r : rows) {
    ParameterRow p;
    p.group = group;
    p.name = r.name + std::to_string(joint);
    p.quantity = r.quantity;
    p.nominal = r.nominal;
    p.truth = r.nominal + r.error * n(rng);
    p.identified = *p.truth + r.sigma * n(rng);
    p.stddev = r.sigma;
    run.parameters.push_back(p);
  }
}

Run arm_run(std::mt19937_64& rng) {
  Run run;
  run.title = "ARID platform on a PUMA-like 6R arm";
  run.robot = "puma560 (host/model/robots/puma560.yaml)";
  run.method = "full (nonlinear least squares), started from the nominal model";
  run.data = "simulated: 60 poses, camera pose + ranges, sigma 20 um";
  run.simulated = true;
  run.measurements = 60;
  const double d[] = {0.0, 0.0, 0.15005, 0.4318, 0.0, 0.0};
  const double a[] = {0.0, 0.4318, 0.0203, 0.0, 0.0, 0.0};
  const double alpha[] = {kPi / 2, 0.0, -kPi / 2, kPi / 2, -kPi / 2, 0.0};
  for (int j = 0; j < 6; ++j) {
    run.joints.push_back({"j" + std::to_string(j + 1), false});
    add_joint_rows(run, rng, j + 1, d[j], a[j], alpha[j]);
  }
  for (const char* name : {"base_x", "base_y", "base_z"})
    run.parameters.push_back({"base", name, Quantity::length_m, 0.5, 0.5021, 3e-5, 0.50205});
  run.parameters.push_back({"tool", "tool_z", Quantity::length_m, 0.1, 0.1, std::nullopt, 0.1});
  // An identified value 5 sigma off the truth: the table marks it.
  run.parameters.push_back({"tool", "tool_x", Quantity::length_m, 0.0, 2e-4, 1e-5, 1.5e-4});
  run.held_fixed = {{"theta1", "the same motion as base_rz"}, {"d1", "the same motion as base_z"}};
  run.notes = {"standard-DH links 2-3 promoted to Doty (axes 0.0 rad apart)", "rank 30 of 32 candidates"};
  run.accuracy = {{"nominal model", 30, 3.21e-3, 3.6e-3, 6.9e-3, 2.1e-3, 2.4e-3, 4.4e-3},
                  {"identified (full)", 30, 2.7e-5, 3.12e-5, 7.4e-5, 3e-5, 3.5e-5, 8e-5}};
  std::uniform_real_distribution<double> q(-kPi, kPi);
  std::uniform_real_distribution<double> before(1e-3, 6.9e-3), after(5e-6, 7.4e-5);
  for (int i = 0; i < 30; ++i) {
    ValidationPose pose;
    for (int j = 0; j < 6; ++j) pose.q.push_back(q(rng));
    pose.before_m = before(rng);
    pose.after_m = after(rng);
    run.validation.push_back(pose);
  }
  return run;
}

Run rig_run(std::mt19937_64& rng) {
  Run run;
  run.title = "Kapucu & Baysec stereo rig <RRP>";
  run.robot = "stanford-rrp";
  run.method = "cpa, then full";
  run.data = "simulated stereo triangulations of the beacon, 3 sweeps of 24 points";
  run.simulated = true;
  run.measurements = 72;
  run.joints = {{"waist", false}, {"shoulder", false}, {"slide", true}};
  std::normal_distribution<double> noise(0.0, 5e-5);
  const Eigen::Vector3d axes[] = {Eigen::Vector3d::UnitZ(), Eigen::Vector3d(1, 0.02, 0).normalized()};
  const double radii[] = {0.32, 0.21};
  for (int j = 0; j < 2; ++j) {
    SweepPlot s;
    s.joint = j;
    s.circle = true;
    s.axis_point_m = Eigen::Vector3d(0.1 * j, 0.2, 1.5);
    s.axis_direction = axes[j];
    s.radius_m = radii[j];
    s.rms_m = 5e-5;
    const Eigen::Vector3d u = axes[j].unitOrthogonal(), v = axes[j].cross(u);
    for (int k = 0; k < 24; ++k) {
      const double angle = -1.2 + 2.4 * k / 23.0;
      s.points_m.push_back(s.axis_point_m + radii[j] * (std::cos(angle) * u + std::sin(angle) * v) +
                           Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
    }
    run.sweeps.push_back(s);
  }
  SweepPlot line;
  line.joint = 2;
  line.circle = false;
  line.axis_point_m = Eigen::Vector3d(0.3, 0.1, 1.2);
  line.axis_direction = Eigen::Vector3d(0, 0.1, -1).normalized();
  line.rms_m = 5e-5;
  line.rejected = 1;
  for (int k = 0; k < 24; ++k)
    line.points_m.push_back(line.axis_point_m + line.axis_direction * (0.02 * k) +
                            Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
  run.sweeps.push_back(line);
  run.accuracy = {{"nominal model", 20, 4.1e-3, 4.5e-3, 8.2e-3, {}, {}, {}},
                  {"identified (cpa)", 20, 2.9e-4, 3.3e-4, 7.1e-4, {}, {}, {}},
                  {"identified (full)", 20, 4.4e-5, 5.0e-5, 1.1e-4, {}, {}, {}}};
  run.bus = BusStatistics{"in-process loopback, classic CAN 1 Mbit/s", 2163, 14020, 0, 4.25, 0.061};
  Comparison table;
  table.title = "Kapucu & Baysec, Table 1, against ours";
  table.columns = {"Kapucu & Baysec", "ours (cpa)", "ours (full)", "truth"};
  table.rows = {{"a1", Quantity::length_m, {0.0661, 0.0028, 0.0022, 0.0}},
                {"alpha1", Quantity::angle_rad, {-1.5533, -1.5703, -1.5707, -kPi / 2}},
                {"d2", Quantity::length_m, {std::nullopt, 0.3021, 0.3003, 0.3}}};
  table.note = "Their values as printed; ours from the same simulated rig.";
  run.comparisons.push_back(table);
  return run;
}

}  // namespace

Report sample_report() {
  std::mt19937_64 rng(2024);
  Report report;
  report.title = "kincal calibration report";
  report.date = "2024-05-17T10:00:00Z";
  report.runs.push_back(arm_run(rng));
  report.runs.push_back(rig_run(rng));
  return report;
}

}  // namespace kincal::report::testing

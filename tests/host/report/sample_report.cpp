#include "sample_report.hpp"

#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Geometry>

#include "host/report/svg_plot.hpp"

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
    p.identifiable_truth = p.truth;
    p.stddev = r.sigma;
    run.parameters.push_back(p);
  }
}

Run arm_run(std::mt19937_64& rng) {
  Run run;
  run.title = "ARID platform on a PUMA-like 6R arm";
  run.robot = "puma560 (host/model/robots/puma560.yaml)";
  run.method = "full (nonlinear least squares), started from the nominal model";
  run.data = "simulated: 60 poses, camera pose + ranges, sigma 0.02 mm";
  run.simulated = true;
  run.measurements = 60;
  const double d[] = {0.0, 0.0, 0.15005, 0.4318, 0.0, 0.0};
  const double a[] = {0.0, 0.4318, 0.0203, 0.0, 0.0, 0.0};
  const double alpha[] = {kPi / 2, 0.0, -kPi / 2, kPi / 2, -kPi / 2, 0.0};
  for (int j = 0; j < 6; ++j) {
    run.joints.push_back({"j" + std::to_string(j + 1), false});
    add_joint_rows(run, rng, j + 1, d[j], a[j], alpha[j]);
  }
  for (const char* name : {"base_x", "base_y"})
    run.parameters.push_back({"base", name, Quantity::length_m, 0.5, 0.5021, 3e-5, 0.50205, 0.50205, "", {}, {}});
  // base_z takes up the true error of d1 (held fixed): 1.4 mm from its own true value, correct
  // as the data can identify it, so not marked.
  run.parameters.push_back({"base", "base_z", Quantity::length_m, 0.5, 0.5021, 3e-5, 0.50065, 0.50205, "d1", {}, {}});
  run.parameters.push_back({"base", "base_rx", Quantity::angle_rad, 0.0, 1.2e-3, 1e-4, 1.1e-3, 1.1e-3, "", {}, {}});
  run.parameters.push_back({"tool", "tool_z", Quantity::length_m, 0.1, 0.1, std::nullopt, 0.1, 0.1, "", {}, {}});
  // An identified value 5 sigma off the truth: the table marks it.
  run.parameters.push_back({"tool", "tool_x", Quantity::length_m, 0.0, 2e-4, 1e-5, 1.5e-4, 1.5e-4, "", {}, {}});
  run.held_fixed = {{"theta1", "the same motion as base_rz"}, {"d1", "the same motion as base_z"}};
  run.notes = {"standard-DH links 2-3 promoted to Doty (axes 0.0 rad apart)", "rank 30 of 32 candidates",
               "noise: position: instrument sigma 0.0200 mm (given)\n  rejected line 14: residual 0.412 mm\n  "
               "rejected line 52: residual 0.388 mm\n"};
  run.accuracy = {
      {"nominal model", 30, 3.21e-3, 3.6e-3, 6.9e-3, 2.1e-3, 2.4e-3, 4.4e-3},
      {"identified (full)", 30, 2.7e-5, 3.12e-5, 7.4e-5, 3e-5, 3.5e-5, 8e-5},
      {"online correction: corrected targets vs the simulated truth", 30, 3.3e-5, 3.9e-5, 8.8e-5, {}, {}, {}}};
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
  run.tables.push_back({"Joint-type tests",
                        {"joint", "verdict", "p(line affine in q)", "p(circle at angle q)", "p(unit-speed line)"},
                        {{"1", "revolute", "1.2e-40", "0.53", "3.1e-41"},
                         {"2", "revolute", "2.5e-33", "0.21", "7.7e-35"},
                         {"3", "prismatic", "0.64", "0.0021", "0.48"}},
                        "p-values of the joint-type tests at significance 0.01"});
  return run;
}

// `words` random words of 1 to 12 letters, some capitals, digits and units among them.
std::string words(std::mt19937_64& rng, int count) {
  static const char* const kPieces[] = {"online",     "correction:", "WWWW",   "mmmm",      "targets", "RMS",
                                        "\u00b5m",    "(deg)",       "x10",    "simulated", "truth",   "i",
                                        "MMMMMMMMMM", "residual",    "5255.1", "\u2212",    "along",   "axis"};
  std::uniform_int_distribution<std::size_t> pick(0, std::size(kPieces) - 1);
  std::string out;
  for (int i = 0; i < count; ++i) out += (i ? " " : "") + std::string(kPieces[pick(rng)]);
  return out;
}

}  // namespace

std::string layout_stress_page() {
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> few(0, 4), width(200, 620), height(120, 360), length(1, 14);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::string html =
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>layout stress</title><style>"
      "body{font-family:\"DejaVu Sans\",Helvetica,Arial,sans-serif}.plots{display:flex;flex-wrap:wrap;gap:8px}"
      "svg.plot{border:1px solid #ddd}svg.plot .frame{fill:none;stroke:#444}svg.plot .grid{stroke:#e4e4e4}" +
      plot_style() + "</style></head><body><div class=\"plots\">";
  for (int k = 0; k < kStressPlots; ++k) {
    PlotSpec spec;
    spec.title = words(rng, length(rng));
    spec.width_px = width(rng);
    spec.height_px = height(rng);
    spec.equal_aspect = k % 5 == 0;
    spec.x.label = words(rng, length(rng));
    spec.y.label = words(rng, length(rng));
    spec.x.log = k % 4 == 1;
    spec.y.log = k % 3 == 2;
    if (k % 6 == 3)
      for (int c = few(rng) + 1; c > 0; --c) spec.y.categories.push_back(words(rng, length(rng)));
    const double scale = std::pow(10.0, 7.0 * unit(rng) - 2.0), offset = k % 2 ? -3.0 * scale : 0.0;
    for (int s = few(rng) + 1; s > 0; --s) {
      PlotSeries series{s % 2 ? words(rng, length(rng) / 2) : "", "#1b9e77", {}, {}, s == 3};
      for (int i = 0; i < 12; ++i) {
        series.x.push_back(spec.x.log ? std::pow(10.0, 9.0 * unit(rng) - 4.0) : offset + scale * unit(rng));
        series.y.push_back(spec.y.categories.empty()
                               ? (spec.y.log ? std::pow(10.0, 9.0 * unit(rng) - 4.0) : offset + scale * unit(rng))
                               : static_cast<double>(static_cast<std::size_t>(i) % spec.y.categories.size()));
      }
      spec.series.push_back(series);
    }
    for (int n = few(rng); n > 0; --n) spec.notes.push_back(words(rng, length(rng) * 2));
    html += svg_plot(spec);
  }
  return html + "</div></body></html>\n";
}

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

#include "host/cli/discover_command.hpp"

#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "host/cli/number_options.hpp"
#include "host/files/output_file.hpp"
#include "host/identify/discover.hpp"
#include "host/model/dataset.hpp"
#include "host/model/model_file.hpp"
#include "host/model/urdf.hpp"
#include "host/report/report.hpp"
#include "host/session/session_report.hpp"

namespace kincal::cli {

namespace {

struct DiscoverArgs {
  std::string data, out, urdf, report, name = "discovered";
  double significance = 0.01, outlier_probability = 1e-3, still_tolerance = 0.0;
};

std::string p_value_text(double p) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", p);
  return text;
}

// The discovery as a report: each sweep's fit in 3-D and in its plane, the joint-type tests with
// their p-values, the discovered link table with standard deviations, and the discovery's notes.
report::Report discovery_report(const DiscoverArgs& a, const model::Dataset& data,
                                const identify::DiscoverResult& result) {
  report::Run run;
  run.title = "Discovered from single-joint sweeps: " + a.data;
  run.robot = result.model.name;
  run.method = "manipulator-independent discovery (no model): joint-type tests, axis fits, link table";
  run.data = a.data;
  run.simulated = std::nullopt;  // a dataset does not say where its measurements came from
  run.measurements = static_cast<int>(data.rows.size());
  for (const model::Joint& j : result.model.joints)
    run.joints.push_back({j.name, j.type == core::JointType::prismatic});
  run.notes = result.notes;
  run.sweeps = session::report_sweeps(data, result.fits, a.still_tolerance);
  report::Comparison table;
  table.title = "Discovered link table";
  table.columns = {"value", "1 sigma"};
  table.note = "theta includes each joint's zero offset; the base frame is placed by convention (see the notes)";
  const core::ChainModel<double> chain = model::to_chain(result.model);
  for (std::size_t j = 0; j < result.stddev.size() && j < static_cast<std::size_t>(chain.joint_count); ++j) {
    const core::LinkParameters<double>& p = chain.links[j].parameters;
    const identify::LinkSpread& sd = result.stddev[j];
    const std::string n = std::to_string(j + 1);
    const auto row = [&table](const std::string& name, report::Quantity q, double value, double sigma) {
      table.rows.push_back({name, q, {value, sigma}});
    };
    row("theta" + n, report::Quantity::angle_rad, p.theta_rad, sd.theta_rad);
    row("d" + n, report::Quantity::length_m, p.d_m, sd.d_m);
    row("a" + n, report::Quantity::length_m, p.a_m, sd.a_m);
    row("alpha" + n, report::Quantity::angle_rad, p.alpha_rad, sd.alpha_rad);
    if (p.beta_rad != 0.0 || sd.beta_rad != 0.0) row("beta" + n, report::Quantity::angle_rad, p.beta_rad, sd.beta_rad);
  }
  run.comparisons.push_back(table);
  report::TextTable tests;
  tests.title = "Joint-type tests";
  tests.columns = {"joint", "type taken", "p(line affine in q)", "p(circle at angle q)", "p(unit-speed line)"};
  for (const identify::SweepFit& f : result.fits)
    tests.rows.push_back(
        {std::to_string(f.joint + 1),
         std::string(f.curved ? "revolute" : "prismatic") + (!f.test.tested      ? " (by fit: too few points to test)"
                                                             : f.test.conclusive ? ""
                                                                                 : " (inconclusive)"),
         p_value_text(f.test.p_line), p_value_text(f.test.p_circle), p_value_text(f.test.p_unit_speed)});
  tests.note = "Each sweep tested at significance " + p_value_text(a.significance) +
               ": a hypothesis with p below it is rejected. line affine in q: a prismatic joint; circle at angle "
               "q: a revolute joint; unit-speed line: a prismatic joint read in metres. A type is conclusive when "
               "exactly one of the first two is rejected.";
  run.tables.push_back(tests);
  report::Report out;
  out.title = "kincal discover";
  out.date = report::utc_date_now();
  out.runs.push_back(std::move(run));
  return out;
}

int run_discover(const DiscoverArgs& a) {
  identify::DiscoverOptions options;
  options.name = a.name;
  options.cpa.significance = a.significance;
  options.cpa.outlier_probability = a.outlier_probability;
  options.cpa.still_tolerance = a.still_tolerance;
  try {
    files::refuse_overwriting({{"--out", a.out}, {"--urdf", a.urdf}, {"--report", a.report}}, {{"--data", a.data}});
    const model::Dataset data = model::read_dataset(a.data);
    const identify::DiscoverResult result = identify::discover(data, options);
    std::cout << "kincal discover: " << a.data << " (" << data.rows.size() << " rows; joint types tested at "
              << a.significance << ")\n"
              << identify::format_discovery(result);
    // Every output is made before the first is written, so that a failure leaves none behind.
    const std::vector<std::pair<std::string, std::string>> outputs = {
        {a.out, model::write_model(result.model)},
        {a.urdf, a.urdf.empty() ? std::string() : model::write_urdf(result.model)},
        {a.report, a.report.empty() ? std::string() : report::render_html(discovery_report(a, data, result))}};
    for (const auto& [path, text] : outputs) {
      if (path.empty()) continue;
      files::write_file_atomically(path, text);
      std::cout << "wrote " << path << '\n';
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "kincal discover: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

void add_discover_command(CLI::App& app, int& status) {
  auto a = std::make_shared<DiscoverArgs>();
  auto* cmd = app.add_subcommand("discover",
                                 "Find an unknown arm's model (joint types, axes, link table) from single-joint "
                                 "sweeps alone");
  cmd->add_option("--data", a->data, "measurements (CSV) with one sweep per joint")->required();
  cmd->add_option("-o,--out", a->out, "model file to write (YAML)")->required();
  cmd->add_option("--urdf", a->urdf, "also write the model as URDF");
  cmd->add_option("--report", a->report,
                  "also write an HTML report: each sweep's fit in 3-D and in its plane, the link table");
  cmd->add_option("--name", a->name, "the robot's name in the model file");
  cmd->add_option("--significance", a->significance, "level of the joint-type tests (default 0.01)")
      ->check(finite_in(1e-12, 0.5));
  cmd->add_option("--outlier-probability", a->outlier_probability,
                  "family-wise probability per sweep of rejecting a good point (default 0.001)")
      ->check(finite_in(1e-12, 0.5));
  cmd->add_option("--still-tolerance", a->still_tolerance,
                  "a joint whose reading changes by no more than this (rad or m) counts as still (default 0)")
      ->check(finite_in(0.0, 1.0));
  cmd->callback([a, &status] { status = run_discover(*a); });
}

}  // namespace kincal::cli

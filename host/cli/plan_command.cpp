#include "host/cli/plan_command.hpp"

#include <charconv>
#include <iostream>
#include <memory>
#include <sstream>

#include "host/cli/model_option.hpp"
#include "host/cli/number_options.hpp"
#include "host/files/output_file.hpp"
#include "host/identify/plan.hpp"
#include "host/model/model_file.hpp"

namespace kincal::cli {

namespace {

struct PlanArgs {
  ModelOption model;
  std::string out;
  int count = 30, pool = 1000;
  std::uint64_t seed = 1;
  bool orientation = false;
};

int run_plan(const PlanArgs& a) {
  try {
    files::refuse_overwriting({{"-o", a.out}}, {{"--model", a.model.path}});
    const model::RobotModel m = a.model.load();
    identify::PlanOptions options;
    options.count = a.count;
    options.pool = a.pool;
    options.seed = a.seed;
    options.orientation = a.orientation;
    options.progress = [](int sweep, std::size_t done, std::size_t total) {
      std::cerr << "kincal plan: exchange sweep " << sweep << ": " << done << " of " << total << " configurations\n";
    };
    const identify::PlanResult r = identify::plan_configurations(m, options);
    std::ostringstream out;
    // The summary as comment lines, which the dataset reader skips.
    char line[1024];
    std::snprintf(line, sizeof line,
                  "# kincal plan: %d configurations of %s for %zu identifiable parameters (%zu held fixed)\n"
                  "# observability index O1: planned %.6g, random plans mean %.6g (best of %d: %.6g): %.2fx\n"
                  "# predicted position rms over the workspace per unit sigma: planned %.4g, random %.4g: %.2fx "
                  "smaller\n",
                  a.count, m.name.c_str(), r.identified.size(), r.held_fixed.size(), r.index, r.random_index_mean, 50,
                  r.random_index_best, r.index / r.random_index_mean, r.prediction_rms, r.random_prediction_rms,
                  r.random_prediction_rms / r.prediction_rms);
    out << line;
    if (!a.out.empty()) std::cout << line;
    for (int j = 1; j <= m.joint_count(); ++j) out << 'q' << j << (j < m.joint_count() ? "," : "\n");
    for (const auto& q : r.configurations) {
      for (std::size_t j = 0; j < q.size(); ++j) {
        char buffer[64];
        const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, q[j]);
        out << std::string(buffer, ec == std::errc() ? end : buffer) << (j + 1 < q.size() ? "," : "\n");
      }
    }
    if (a.out.empty())
      std::cout << out.str();
    else
      files::write_file_atomically(a.out, out.str());
    return std::cout ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "kincal plan: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

void add_plan_command(CLI::App& app, int& status) {
  auto a = std::make_shared<PlanArgs>();
  auto* cmd = app.add_subcommand("plan", "Propose calibration configurations that maximize observability");
  add_model_option(*cmd, a->model, "model with joint limits");
  cmd->add_option("-n,--count", a->count, "number of configurations (default 30)")->check(whole_in(1, 100000));
  cmd->add_option("--pool", a->pool, "random candidate configurations to choose from (default 1000)")
      ->check(whole_in(1, 1000000));
  cmd->add_option("--seed", a->seed, "random seed (default 1)");
  cmd->add_flag("--orientation", a->orientation, "plan for pose measurements (tool frame) instead of points");
  cmd->add_option("-o,--out", a->out, "output CSV q1..qN (default: standard output)");
  cmd->callback([a, &status] { status = run_plan(*a); });
}

}  // namespace kincal::cli

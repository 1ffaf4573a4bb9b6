#include "host/cli/discover_command.hpp"

#include <iostream>
#include <memory>

#include "host/cli/number_options.hpp"
#include "host/files/output_file.hpp"
#include "host/identify/discover.hpp"
#include "host/model/dataset.hpp"
#include "host/model/model_file.hpp"
#include "host/model/urdf.hpp"

namespace kincal::cli {

namespace {

struct DiscoverArgs {
  std::string data, out, urdf, name = "discovered";
  double significance = 0.01, outlier_probability = 1e-3, still_tolerance = 0.0;
};

int run_discover(const DiscoverArgs& a) {
  identify::DiscoverOptions options;
  options.name = a.name;
  options.cpa.significance = a.significance;
  options.cpa.outlier_probability = a.outlier_probability;
  options.cpa.still_tolerance = a.still_tolerance;
  try {
    files::refuse_overwriting({{"--out", a.out}, {"--urdf", a.urdf}}, {{"--data", a.data}});
    const model::Dataset data = model::read_dataset(a.data);
    const identify::DiscoverResult result = identify::discover(data, options);
    std::cout << "kincal discover: " << a.data << " (" << data.rows.size() << " rows; joint types tested at "
              << a.significance << ")\n"
              << identify::format_discovery(result);
    model::save_model(result.model, a.out);
    std::cout << "wrote " << a.out << '\n';
    if (!a.urdf.empty()) {
      files::write_file_atomically(a.urdf, model::write_urdf(result.model));
      std::cout << "wrote " << a.urdf << '\n';
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

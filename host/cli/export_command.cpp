#include "host/cli/export_command.hpp"

#include <iostream>
#include <memory>

#include "host/cli/model_option.hpp"
#include "host/files/output_file.hpp"
#include "host/model/ur_kinematics.hpp"

namespace kincal::cli {

namespace {

struct ExportArgs {
  ModelOption model;
  std::string format, out;
};

int run_export(const ExportArgs& a) {
  try {
    files::refuse_overwriting({{"-o", a.out, true}}, {{"--model", a.model.path}});
    const model::UrKinematics k = model::ur_kinematics(a.model.load());
    files::write_output(a.out, model::write_ur_kinematics(k));
    if (!a.out.empty() && a.out != "-") {
      std::cout << "wrote " << a.out << '\n';
      for (const std::string& note : k.notes) std::cout << "note: " << note << '\n';
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "kincal export: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

void add_export_command(CLI::App& app, int& status) {
  auto a = std::make_shared<ExportArgs>();
  auto* cmd = app.add_subcommand("export", "Write a calibrated model in a robot controller's format");
  cmd->add_option("--format", a->format,
                  "ur-kinematics: Universal Robots' ROS description's kinematics_params_file (YAML)")
      ->required()
      ->check(CLI::IsMember({"ur-kinematics"}));
  add_model_option(*cmd, a->model, "the calibrated model");
  cmd->add_option("-o,--out", a->out, "output file (default or '-': standard output)");
  cmd->callback([a, &status] { status = run_export(*a); });
}

}  // namespace kincal::cli

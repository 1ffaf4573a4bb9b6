#include "host/cli/export_command.hpp"

#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>

#include "host/cli/model_option.hpp"
#include "host/correct/joint_correction.hpp"
#include "host/correct/joint_offsets.hpp"
#include "host/files/output_file.hpp"
#include "host/model/model_file.hpp"
#include "host/model/ur_kinematics.hpp"

namespace kincal::cli {

namespace {

struct ExportArgs {
  ModelOption model;
  std::string format, out, nominal, data;
};

std::string millimetres(const correct::ArmErrors& e) {
  char text[96];
  std::snprintf(text, sizeof text, "%.3f mm RMS, %.3f mm max", e.rms_m * 1e3, e.max_m * 1e3);
  return text;
}

// Per-joint zero offsets, and how much of the calibration they carry (printed on `log`).
std::string joint_offsets(const ExportArgs& a, std::ostream& log) {
  const model::RobotModel calibrated = a.model.load();
  const model::RobotModel nominal =
      a.nominal.empty() ? correct::nominal_from_record(calibrated) : model::load_model(a.nominal, a.model.ends);
  const std::optional<model::Dataset> data =
      a.data.empty() ? std::nullopt : std::optional<model::Dataset>(model::read_dataset(a.data));
  const std::vector<double> raw = correct::joint_offsets(nominal, calibrated);
  const std::vector<double> offsets = correct::fitted_joint_offsets(nominal, calibrated, 500, 24);
  const auto share = [&](const std::vector<double>& o) {
    return data ? correct::offset_share(nominal, calibrated, o, *data)
                : correct::offset_share(nominal, calibrated, o, 2000, 25);
  };
  const correct::OffsetShare s = share(offsets), r = share(raw);
  log << "joint offsets: "
      << (data ? "position errors on the " + std::to_string(s.rows) + " rows of " + a.data
               : "tool displacement from the calibrated arm over " + std::to_string(s.rows) +
                     " random readings within the limits (predicted, not measured; --data held-out rows measure it)")
      << ", each arm with the calibrated base registration and tool:\n"
      << "  nominal arm             " << millimetres(s.nominal) << '\n'
      << "  nominal + zero changes  " << millimetres(r.offsets_only) << "  (the calibration's own theta/d changes)\n"
      << "  nominal + offsets       " << millimetres(s.offsets_only) << "  (fitted: the ones written)\n"
      << "  calibrated arm          " << millimetres(s.calibrated) << '\n';
  char text[160];
  std::snprintf(text, sizeof text, "  the offsets carry %.0f %% of the calibration's RMS improvement\n",
                100.0 * s.carried);
  log << text;
  return correct::write_joint_offsets(calibrated, offsets);
}

int run_export(const ExportArgs& a) {
  try {
    files::refuse_overwriting({{"-o", a.out, true}},
                              {{"--model", a.model.path}, {"--nominal", a.nominal}, {"--data", a.data}});
    if (a.format == "joint-offsets") {
      std::ostream& log = a.out.empty() || a.out == "-" ? std::cerr : std::cout;
      const std::string text = joint_offsets(a, log);
      files::write_output(a.out, text);
      if (!a.out.empty() && a.out != "-") std::cout << "wrote " << a.out << '\n';
      return 0;
    }
    if (!a.nominal.empty() || !a.data.empty())
      throw model::InputError("--nominal and --data go with --format joint-offsets");
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
                  "ur-kinematics: Universal Robots' ROS description's kinematics_params_file (YAML); joint-offsets: "
                  "per-joint zero offsets a controller takes (CSV), and how much of the calibration they carry")
      ->required()
      ->check(CLI::IsMember({"ur-kinematics", "joint-offsets"}));
  add_model_option(*cmd, a->model, "the calibrated model");
  cmd->add_option("--nominal", a->nominal,
                  "joint-offsets: the controller's model (default: the calibrated model's record undone)");
  cmd->add_option("--data", a->data,
                  "joint-offsets: measured rows (dataset CSV, best held out) to measure what the offsets carry");
  cmd->add_option("-o,--out", a->out, "output file (default or '-': standard output)");
  cmd->callback([a, &status] { status = run_export(*a); });
}

}  // namespace kincal::cli

#include "host/cli/urdf_command.hpp"

#include <iostream>
#include <memory>
#include <sstream>

#include "host/cli/model_option.hpp"
#include "host/files/input_file.hpp"
#include "host/files/output_file.hpp"
#include "host/model/model_file.hpp"
#include "host/model/urdf.hpp"

namespace kincal::cli {

namespace {

struct UrdfArgs {
  ModelOption model;
  std::string original, out, marker_link;
};

int run_urdf(const UrdfArgs& a) {
  try {
    files::refuse_overwriting({{"-o", a.out}}, {{"--model", a.model.path}, {"--original", a.original}});
    std::string text;
    if (a.original.empty()) {
      if (!a.marker_link.empty())
        throw model::InputError("--marker-link: only with --original (a URDF made from the model ends at its tool)");
      text = model::write_urdf(a.model.load());
    } else {
      // The chain options name the original's chain; a YAML model has none.
      const model::RobotModel m =
          model::load_model(a.model.path, model::is_urdf_path(a.model.path) ? a.model.ends : model::UrdfChainEnds{});
      // Read with its byte-order mark, if any: every byte but the changed values is written back.
      const std::string original = files::read_text(a.original, files::kOriginalUrdfFile);
      const model::CalibratedUrdf c =
          model::write_calibrated_urdf(original, a.original, a.model.ends, m, a.marker_link);
      text = c.text;
      std::ostream& report = a.out.empty() ? std::cerr : std::cout;
      report << print_registration(c);
    }
    if (a.out.empty()) {
      std::cout << text;
    } else {
      files::write_file_atomically(a.out, text);
      std::cout << "wrote " << a.out << '\n';
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "kincal urdf: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

std::string print_registration(const model::CalibratedUrdf& c) {
  // + 0.0: no "-0" in what a user reads.
  const model::Vector3 rpy = model::rpy_from_rotation(c.device_T_base_link.rotation) + model::Vector3::Zero();
  std::ostringstream out;
  out.precision(6);
  const model::Vector3 xyz = c.device_T_base_link.translation + model::Vector3::Zero();
  out << "the base link in the measuring device's frame (device_T_base_link): xyz " << xyz.x() << ' ' << xyz.y() << ' '
      << xyz.z() << " m, rpy " << rpy.x() << ' ' << rpy.y() << ' ' << rpy.z() << " rad\n";
  for (const std::string& note : c.notes) out << "note: " << note << '\n';
  return out.str();
}

void add_urdf_command(CLI::App& app, int& status) {
  auto a = std::make_shared<UrdfArgs>();
  auto* cmd = app.add_subcommand("urdf", "Write a model as URDF, or into the robot's own URDF (--original)");
  add_model_option(*cmd, a->model, "the model to write");
  cmd->add_option("--original", a->original,
                  "the robot's URDF: keep it all (names, meshes, inertias) and put the model's geometry into the "
                  "joint origins of its chain (--base-link, --tip-link)");
  cmd->add_option("--marker-link", a->marker_link,
                  "with --original: also write the measured point (the model's tool: a reflector, a marker) as a "
                  "new link of this name, fixed to the tip link; without it the URDF's links keep their place and "
                  "no link is added");
  cmd->add_option("-o,--out", a->out, "output file (default: standard output)");
  cmd->callback([a, &status] { status = run_urdf(*a); });
}

}  // namespace kincal::cli

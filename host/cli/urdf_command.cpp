#include "host/cli/urdf_command.hpp"

#include <fstream>
#include <iostream>
#include <memory>

#include "host/model/model_file.hpp"
#include "host/model/urdf.hpp"

namespace kincal::cli {

void add_urdf_command(CLI::App& app, int& status) {
  auto model_path = std::make_shared<std::string>();
  auto out_path = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand("urdf", "Export a model as URDF (geometry in the joint origins)");
  cmd->add_option("--model", *model_path, "model (YAML)")->required();
  cmd->add_option("-o,--out", *out_path, "output file (default: standard output)");
  cmd->callback([=, &status] {
    try {
      const std::string text = model::write_urdf(model::load_model(*model_path));
      if (out_path->empty()) {
        std::cout << text;
      } else {
        std::ofstream out(*out_path);
        out << text;
        if (!out) throw model::InputError(*out_path + ": cannot write");
      }
      status = 0;
    } catch (const model::InputError& e) {
      std::cerr << "kincal urdf: " << e.what() << '\n';
      status = 1;
    }
  });
}

}  // namespace kincal::cli

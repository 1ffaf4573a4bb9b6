#include "host/cli/urdf_command.hpp"

#include <iostream>
#include <memory>

#include "host/files/output_file.hpp"
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
      files::refuse_overwriting({{"-o", *out_path}}, {{"--model", *model_path}});
      const std::string text = model::write_urdf(model::load_model(*model_path));
      if (out_path->empty())
        std::cout << text;
      else
        files::write_file_atomically(*out_path, text);
      status = 0;
    } catch (const std::exception& e) {
      std::cerr << "kincal urdf: " << e.what() << '\n';
      status = 1;
    }
  });
}

}  // namespace kincal::cli

#include "host/cli/model_option.hpp"

#include "host/model/model_file.hpp"

namespace kincal::cli {

model::RobotModel ModelOption::load() const { return model::load_model(path, ends); }

void add_model_option(CLI::App& cmd, ModelOption& option, const std::string& what, bool required) {
  CLI::Option* model =
      cmd.add_option("--model", option.path, what + ": kincal model (YAML) or the robot's URDF (*.urdf)");
  if (required) model->required();
  cmd.add_option("--base-link", option.ends.base_link, "URDF model: the chain's first link (default: the root)")
      ->needs(model);
  cmd.add_option("--tip-link", option.ends.tip_link,
                 "URDF model: the chain's last link, the tool frame (default: the leaf with the most joints)")
      ->needs(model);
}

}  // namespace kincal::cli

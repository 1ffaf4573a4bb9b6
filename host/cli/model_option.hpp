// The --model option of every subcommand that takes a robot model: a kincal model file (YAML) or
// the robot's URDF (*.urdf), with --base-link and --tip-link choosing the URDF's chain
// (host/model/urdf_chain.hpp says the defaults). One place, so every command reads models alike.
#pragma once

#include <string>

#include <CLI/App.hpp>

#include "host/model/robot_model.hpp"
#include "host/model/urdf_chain.hpp"

namespace kincal::cli {

struct ModelOption {
  std::string path;
  model::UrdfChainEnds ends;

  // model::load_model(path, ends); throws model::InputError.
  model::RobotModel load() const;
};

// Adds --model (required unless `required` is false; `what` describes the model), --base-link
// and --tip-link to `cmd`, storing into `option` (which must outlive the parse).
void add_model_option(CLI::App& cmd, ModelOption& option, const std::string& what, bool required = true);

}  // namespace kincal::cli

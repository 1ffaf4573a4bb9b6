// `kincal urdf`: a model as URDF with the (calibrated) geometry in the joint origins, either
// written from the model alone or put into the robot's own URDF (--original), which keeps
// everything else (host/model/urdf.hpp).
#pragma once

#include <string>

#include <CLI/App.hpp>

#include "host/model/urdf.hpp"

namespace kincal::cli {

// Registers the subcommand; when it runs, its exit status goes to `status`.
void add_urdf_command(CLI::App& app, int& status);

// The registration a calibrated URDF leaves out, and its notes, as lines for the user
// (`kincal urdf --original`, `kincal identify --urdf` with a URDF model).
std::string print_registration(const model::CalibratedUrdf& calibrated);

}  // namespace kincal::cli

// `kincal predict`: the measured point (or pose) a model predicts for each row of joint readings,
// as CSV, so a model can be checked against measurements kept back; with --at tcp the
// controller's TCP instead (refused for a model without one), where correct's targets are aimed.
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

// Registers the subcommand; when it runs, its exit status goes to `status`.
void add_predict_command(CLI::App& app, int& status);

}  // namespace kincal::cli

// `kincal exercise`: runs the platform scenario (host/can/scenario.hpp) against a platform on a
// SocketCAN interface: parameters up and back, measurements, a correction stream. Exit 0 on PASS.
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

void add_exercise_command(CLI::App& app, int& status);

}  // namespace kincal::cli

// `kincal session`: run a calibration session (simulated robot by default, or a real one over
// SocketCAN), identify, upload the correction and verify it, write the model and the report.
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

// Registers the subcommand; when it runs, its exit status goes to `status`.
void add_session_command(CLI::App& app, int& status);

}  // namespace kincal::cli

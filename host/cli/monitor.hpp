// `kincal monitor`: decodes the platform's traffic, live from a SocketCAN interface or from a
// candump -L log (one line per frame, plus one per reassembled ISO-TP message).
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

void add_monitor_command(CLI::App& app, int& status);

}  // namespace kincal::cli

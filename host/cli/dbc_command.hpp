// `kincal dbc`: writes the DBC file of the protocol's single-frame messages (host/can/dbc.hpp).
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

void add_dbc_command(CLI::App& app, int& status);

}  // namespace kincal::cli

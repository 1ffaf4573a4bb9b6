#include "host/cli/dbc_command.hpp"

#include <fstream>
#include <iostream>
#include <memory>

#include "host/can/dbc.hpp"

namespace kincal::cli {

void add_dbc_command(CLI::App& app, int& status) {
  auto path = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand("dbc", "Write the DBC file of the CAN protocol's single-frame messages");
  cmd->add_option("-o,--output", *path, "output file (default: standard output)");
  cmd->callback([path, &status] {
    if (path->empty()) {
      can::write_dbc(std::cout);
      status = 0;
      return;
    }
    std::ofstream out(*path);
    if (!out) {
      std::cerr << "kincal dbc: cannot create " << *path << "\n";
      status = 1;
      return;
    }
    can::write_dbc(out);
    status = out ? 0 : 1;
  });
}

}  // namespace kincal::cli

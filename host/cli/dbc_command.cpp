#include "host/cli/dbc_command.hpp"

#include <iostream>
#include <memory>
#include <sstream>

#include "host/can/dbc.hpp"
#include "host/files/output_file.hpp"

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
    std::ostringstream out;
    can::write_dbc(out);
    try {
      files::write_file_atomically(*path, out.str());
      status = 0;
    } catch (const files::OutputError& e) {
      std::cerr << "kincal dbc: " << e.what() << "\n";
      status = 1;
    }
  });
}

}  // namespace kincal::cli

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
  cmd->add_option("-o,--output", *path, "output file (default or '-': standard output)");
  cmd->callback([path, &status] {
    std::ostringstream out;
    can::write_dbc(out);
    try {
      files::refuse_overwriting({{"-o", *path, true}}, {});
      files::write_output(*path, out.str());
      status = 0;
    } catch (const files::OutputError& e) {
      std::cerr << "kincal dbc: " << e.what() << "\n";
      status = 1;
    }
  });
}

}  // namespace kincal::cli

// `kincal plan`: calibration configurations within the joint limits that maximize the
// observability index of the identification Jacobian, compared with random ones; chosen from a
// random pool or from --candidates (a joint target table, correct/target_table.hpp: refused rows
// named FILE:LINE:COLUMN), within --constraints (identify/plan_constraints.hpp). The printout
// says how many candidates each constraint rejected and which are active, and the lines of the
// chosen candidates.
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

// Registers the subcommand; when it runs, its exit status goes to `status`.
void add_plan_command(CLI::App& app, int& status);

}  // namespace kincal::cli

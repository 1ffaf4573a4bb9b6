#include "host/cli/exercise.hpp"

#include <iostream>
#include <memory>

#include "host/can/platform_client.hpp"
#include "host/can/scenario.hpp"
#include "host/can/socketcan.hpp"
#include "host/cli/number_options.hpp"

namespace kincal::cli {

namespace {

struct ExerciseOptions {
  std::string interface;
  std::string log;
  bool fd = false;
  bool no_padding = false;
  int measurements = 10;
  int corrections = 200;
  int correction_timeout_ms = 100;
};

}  // namespace

void add_exercise_command(CLI::App& app, int& status) {
  auto o = std::make_shared<ExerciseOptions>();
  auto* cmd = app.add_subcommand("exercise", "Run the platform scenario (parameters, measurements, corrections)");
  cmd->add_option("--can", o->interface, "SocketCAN interface of the platform (e.g. vcan0)")->required();
  cmd->add_flag("--fd", o->fd, "CAN FD: ISO-TP frames of 64 bytes and the FD joint stream");
  cmd->add_flag("--no-padding", o->no_padding, "do not pad ISO-TP frames");
  cmd->add_option("--log", o->log, "write the session as a candump -L log");
  cmd->add_option("--measurements", o->measurements, "measurements to run")->check(whole_in(0, 100000));
  cmd->add_option("--corrections", o->corrections, "correction cycles to run")->check(whole_in(0, 1000000));
  cmd->add_option("--correction-timeout-ms", o->correction_timeout_ms, "longest wait for one corrected joint state")
      ->check(whole_in(1, 60000))
      ->capture_default_str();
  cmd->callback([o, &status] {
    try {
      can::SocketCanTransport transport(o->interface, {o->fd, !o->no_padding, o->log});
      can::PlatformClient client(transport);
      const can::ScenarioResult r = can::run_platform_scenario(
          client, {o->measurements, o->corrections, o->fd, std::chrono::milliseconds(o->correction_timeout_ms)},
          std::cout);
      status = r.ok() ? 0 : 1;
    } catch (const std::exception& e) {
      std::cerr << "kincal exercise: " << e.what() << "\n";
      status = 1;
    }
  });
}

}  // namespace kincal::cli

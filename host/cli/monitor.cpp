#include "host/cli/monitor.hpp"

#include <chrono>
#include <iostream>
#include <memory>

#include "host/can/candump_log.hpp"
#include "host/can/monitor.hpp"
#include "host/can/socketcan.hpp"
#include "host/cli/number_options.hpp"
#include "host/files/output_file.hpp"

namespace kincal::cli {

namespace {

struct MonitorOptions {
  std::string interface;
  std::string replay;
  std::string log;
  bool fd = false;
  double duration_s = 0;
};

int replay(const MonitorOptions& o) {
  can::CandumpReader reader(o.replay);
  can::Monitor monitor;
  while (auto logged = reader.next())
    for (const std::string& line : monitor.feed(logged->frame, logged->time_us)) std::cout << line << "\n";
  std::cout << "monitor: " << monitor.frames() << " frames, " << monitor.messages() << " ISO-TP messages, "
            << monitor.undecodable() << " malformed\n";
  return 0;
}

int live(const MonitorOptions& o) {
  can::RawCanSocket socket(o.interface, o.fd, {});
  std::unique_ptr<can::CandumpWriter> log;
  if (!o.log.empty()) log = std::make_unique<can::CandumpWriter>(o.log);
  can::Monitor monitor;
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                          std::chrono::duration<double>(o.duration_s));
  while (o.duration_s <= 0 || std::chrono::steady_clock::now() < end) {
    can::CanFrame frame;
    if (!socket.receive(frame, std::chrono::milliseconds(100))) continue;
    const std::uint64_t t = can::now_unix_us();
    if (log) log->write(can::LoggedFrame{t, o.interface, frame, false});
    for (const std::string& line : monitor.feed(frame, t)) std::cout << line << "\n";
    std::cout.flush();
  }
  std::cout << "monitor: " << monitor.frames() << " frames, " << monitor.messages() << " ISO-TP messages, "
            << monitor.undecodable() << " malformed\n";
  return 0;
}

}  // namespace

void add_monitor_command(CLI::App& app, int& status) {
  auto options = std::make_shared<MonitorOptions>();
  auto* cmd = app.add_subcommand("monitor", "Decode the platform's CAN traffic, live or from a candump -L log");
  auto* can_opt = cmd->add_option("--can", options->interface, "SocketCAN interface to listen on (e.g. vcan0)");
  auto* replay_opt = cmd->add_option("--replay", options->replay, "decode this candump -L log instead");
  can_opt->excludes(replay_opt);
  // What a live capture does: a replay receives nothing, logs nothing and runs to the log's end.
  cmd->add_flag("--fd", options->fd, "also receive CAN FD frames")->needs(can_opt);
  cmd->add_option("--log", options->log, "also write what is received as a candump -L log")->needs(can_opt);
  cmd->add_option("--duration-s", options->duration_s, "stop after this many seconds (0 = until interrupted)")
      ->check(finite_non_negative())
      ->needs(can_opt);
  cmd->callback([options, &status, can_opt, replay_opt] {
    if (can_opt->count() == 0 && replay_opt->count() == 0)
      throw CLI::ValidationError("--can/--replay", "monitor needs --can IFACE or --replay FILE");
    try {
      files::refuse_overwriting({{"--log", options->log}}, {{"--replay", options->replay}});
      status = options->replay.empty() ? live(*options) : replay(*options);
    } catch (const std::exception& e) {
      std::cerr << "kincal monitor: " << e.what() << "\n";
      status = 1;
    }
  });
}

}  // namespace kincal::cli

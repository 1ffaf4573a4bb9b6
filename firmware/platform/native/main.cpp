// kincal_platform: the sensor platform's firmware as a Linux process on a SocketCAN interface.
// The same firmware/app as on the STM32F407, bound to native ports (native_ports.hpp).
//   kincal_platform --can vcan0 [--fd] [--storage DIR] [--ranges FILE|-] [--frames DIR|FILE]
//                   [--no-padding] [--duration-s S]
// Measurement: PlatformMeasurement (firmware/app/platform_measurement.hpp) over the camera frames
// of --frames (PGM files, native_ports.hpp) and the rangers of --ranges; correction:
// KinematicCorrection. Stops on SIGINT/SIGTERM or after --duration-s. Exit status 0, or 1 with a
// message naming what failed (no such interface, storage directory not writable, ranges file
// missing, frames missing or malformed).
#include <poll.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <csignal>
#include <iostream>
#include <memory>

#include "firmware/app/kinematic_correction.hpp"
#include "firmware/app/platform_app.hpp"
#include "firmware/app/platform_measurement.hpp"
#include "firmware/platform/native/native_ports.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

using NativeMeasurement = kincal::app::PlatformMeasurement<kincal::native::PgmFrames, kincal::native::LineRangers>;
using NativeApp = kincal::app::PlatformApp<kincal::native::SocketCanPort, kincal::native::FileStorage,
                                           NativeMeasurement, kincal::app::KinematicCorrection>;

int run(const std::string& interface, bool fd, bool padding, const std::string& storage_dir,
        const std::string& ranges_path, const std::string& frames_path, double duration_s) {
  // The inputs first: a wrong --ranges or --frames is reported before the interface is needed.
  kincal::native::LineRangers rangers(ranges_path);
  kincal::native::PgmFrames camera(frames_path);
  kincal::native::SocketCanPort can(interface, fd);
  kincal::native::FileStorage storage(storage_dir);
  // The steps (22 KiB and 3.5 KiB) and the application (11 KiB): off the stack.
  auto measure = std::make_unique<NativeMeasurement>(camera, rangers);
  auto correct = std::make_unique<kincal::app::KinematicCorrection>();
  kincal::app::AppConfig config;
  config.fd = fd;
  config.isotp_padding = padding;
  auto app = std::make_unique<NativeApp>(config, can, storage, *measure, *correct);

  const std::uint64_t start_us = kincal::native::monotonic_us();
  app->start(start_us);
  std::cerr << "kincal_platform: running on " << interface << (fd ? " (CAN FD)" : "") << ", storage " << storage_dir
            << "\n";
  const auto end_us = duration_s > 0 ? start_us + static_cast<std::uint64_t>(duration_s * 1e6) : ~std::uint64_t{0};
  while (!g_stop) {
    std::uint64_t now = kincal::native::monotonic_us();
    if (now >= end_us) break;
    const std::uint64_t deadline = app->next_deadline_us();
    const int wait_ms =
        deadline <= now ? 0 : static_cast<int>(std::min<std::uint64_t>((deadline - now + 999) / 1000, 10));
    pollfd p{can.descriptor(), POLLIN, 0};
    (void)::poll(&p, 1, wait_ms);
    kincal::shared::CanFrame frame;
    for (int i = 0; i < 256 && can.try_receive(frame); ++i) app->on_frame(frame, kincal::native::monotonic_us());
    now = kincal::native::monotonic_us();
    app->poll(now);
  }
  std::cerr << "kincal_platform: stopped (rejected frames: " << static_cast<int>(app->rejected_frames())
            << ", ISO-TP messages in/out: " << app->isotp_stats().rx_messages << "/" << app->isotp_stats().tx_messages
            << ")\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"kincal_platform: the sensor platform's firmware as a Linux process on SocketCAN", "kincal_platform"};
  std::string interface, storage_dir = "kincal-platform-storage", ranges_path, frames_path;
  bool fd = false, no_padding = false;
  double duration_s = 0;
  cli.add_option("--can", interface, "SocketCAN interface (e.g. vcan0)")->required();
  cli.add_flag("--fd", fd, "CAN FD interface: FD frames for ISO-TP and the FD joint stream");
  cli.add_flag("--no-padding", no_padding, "do not pad ISO-TP frames to 8 bytes");
  cli.add_option("--storage", storage_dir, "directory of the parameter storage slots");
  cli.add_option("--ranges", ranges_path, "file or pipe of range lines (4 ranges in metres); '-' = stdin");
  cli.add_option("--frames", frames_path,
                 "camera frames: a directory of binary 8-bit PGM files (one per measurement, in name order) "
                 "or one PGM file for every measurement");
  cli.add_option("--duration-s", duration_s, "stop after this many seconds (0 = until SIGTERM)")
      ->check(CLI::NonNegativeNumber);
  CLI11_PARSE(cli, argc, argv);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  try {
    return run(interface, fd, !no_padding, storage_dir, ranges_path, frames_path, duration_s);
  } catch (const std::exception& e) {
    std::cerr << "kincal_platform: " << e.what() << "\n";
    return 1;
  }
}

// kincal_platform: the sensor platform's firmware as a Linux process on a SocketCAN interface.
// The same firmware/app as on the STM32F407, bound to native ports (native_ports.hpp).
//   kincal_platform --can vcan0 [--fd] [--storage DIR] [--ranges FILE|-]
//                   [--frames DIR|FILE | --camera /dev/videoN [--camera-size WxH]]
//                   [--no-padding] [--duration-s S]
// Measurement: PlatformMeasurement (firmware/app/platform_measurement.hpp) over the camera frames
// of --frames (PGM files, native_ports.hpp) or of a live V4L2 camera (--camera, v4l2_camera.hpp)
// and the rangers of --ranges; correction: KinematicCorrection. Stops on SIGINT/SIGTERM or after
// --duration-s. Exit status 0, or 1 with a message naming what failed (no such interface, storage
// directory not writable, ranges file missing, frames missing or malformed, camera missing or
// not a V4L2 capture device or refusing the format).
#include <poll.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>

#include "firmware/app/kinematic_correction.hpp"
#include "firmware/app/platform_app.hpp"
#include "firmware/app/platform_measurement.hpp"
#include "firmware/platform/native/native_ports.hpp"
#include "firmware/platform/native/v4l2_camera.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

struct Options {
  std::string interface, storage_dir = "kincal-platform-storage", ranges_path, frames_path, camera_device;
  std::string camera_size = "640x480";
  bool fd = false, no_padding = false;
  double duration_s = 0;
};

// "WxH" within the labeler's frame (at most kMaxWidthPx x kLabelerMaxRows); else a message.
std::string parse_frame_size(const std::string& text, std::uint16_t& width_px, std::uint16_t& height_px) {
  unsigned width = 0, height = 0;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%u%c%u%c", &width, &x, &height, &extra) != 3 || x != 'x')
    return "'" + text + "' is not a frame size WIDTHxHEIGHT in pixels (e.g. 640x480)";
  if (width < 1 || width > kincal::app::MeasurementPipeline::kMaxWidthPx || height < 1 ||
      height > static_cast<unsigned>(kincal::core::kLabelerMaxRows))
    return "frame size " + text + " is outside 1..640 x 1..4096 (the labeler's row and frame)";
  width_px = static_cast<std::uint16_t>(width);
  height_px = static_cast<std::uint16_t>(height);
  return "";
}

template <class Camera>
int serve(const Options& o, Camera& camera, kincal::native::LineRangers& rangers) {
  using NativeMeasurement = kincal::app::PlatformMeasurement<Camera, kincal::native::LineRangers>;
  using NativeApp = kincal::app::PlatformApp<kincal::native::SocketCanPort, kincal::native::FileStorage,
                                             NativeMeasurement, kincal::app::KinematicCorrection>;
  kincal::native::SocketCanPort can(o.interface, o.fd);
  kincal::native::FileStorage storage(o.storage_dir);
  // The steps (22 KiB and 3.5 KiB) and the application (11 KiB): off the stack.
  auto measure = std::make_unique<NativeMeasurement>(camera, rangers);
  auto correct = std::make_unique<kincal::app::KinematicCorrection>();
  kincal::app::AppConfig config;
  config.fd = o.fd;
  config.isotp_padding = !o.no_padding;
  auto app = std::make_unique<NativeApp>(config, can, storage, *measure, *correct);

  const std::uint64_t start_us = kincal::native::monotonic_us();
  app->start(start_us);
  std::cerr << "kincal_platform: running on " << o.interface << (o.fd ? " (CAN FD)" : "") << ", storage "
            << o.storage_dir << "\n";
  const auto end_us = o.duration_s > 0 ? start_us + static_cast<std::uint64_t>(o.duration_s * 1e6) : ~std::uint64_t{0};
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

int run(const Options& o) {
  // The inputs first: a wrong --ranges, --frames or --camera is reported before the interface
  // is needed.
  kincal::native::LineRangers rangers(o.ranges_path);
  if (!o.camera_device.empty()) {
    std::uint16_t width_px = 0, height_px = 0;
    const std::string error = parse_frame_size(o.camera_size, width_px, height_px);
    if (!error.empty()) throw std::runtime_error("--camera-size: " + error);
    kincal::native::V4l2Camera camera(o.camera_device, width_px, height_px);
    return serve(o, camera, rangers);
  }
  kincal::native::PgmFrames camera(o.frames_path);
  return serve(o, camera, rangers);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"kincal_platform: the sensor platform's firmware as a Linux process on SocketCAN", "kincal_platform"};
  Options o;
  cli.add_option("--can", o.interface, "SocketCAN interface (e.g. vcan0)")->required();
  cli.add_flag("--fd", o.fd, "CAN FD interface: FD frames for ISO-TP and the FD joint stream");
  cli.add_flag("--no-padding", o.no_padding, "do not pad ISO-TP frames to 8 bytes");
  cli.add_option("--storage", o.storage_dir, "directory of the parameter storage slots");
  cli.add_option("--ranges", o.ranges_path, "file or pipe of range lines (4 ranges in metres); '-' = stdin");
  CLI::Option* frames = cli.add_option("--frames", o.frames_path,
                                       "camera frames: a directory of binary 8-bit PGM files (one per measurement, "
                                       "in name order) or one PGM file for every measurement");
  CLI::Option* camera = cli.add_option("--camera", o.camera_device,
                                       "live V4L2 capture device (e.g. /dev/video0), GREY or YUYV; "
                                       "exclusive with --frames");
  camera->excludes(frames);
  cli.add_option("--camera-size", o.camera_size,
                 "the camera's frame size WIDTHxHEIGHT, as its intrinsics were calibrated (a larger driver frame "
                 "is cropped to its top-left corner)")
      ->needs(camera);
  cli.add_option("--duration-s", o.duration_s, "stop after this many seconds (0 = until SIGTERM)")
      ->check(CLI::NonNegativeNumber);
  CLI11_PARSE(cli, argc, argv);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  try {
    return run(o);
  } catch (const std::exception& e) {
    std::cerr << "kincal_platform: " << e.what() << "\n";
    return 1;
  }
}

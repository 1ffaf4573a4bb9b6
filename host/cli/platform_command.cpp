#include "host/cli/platform_command.hpp"

#include <chrono>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "host/can/platform_client.hpp"
#include "host/can/socketcan.hpp"
#include "host/session/platform_setup.hpp"

namespace kincal::cli {

namespace {

struct PlatformOptions {
  std::string interface;
  bool fd = false;
  std::string camera;
  std::string geometry;
};

void add_bus_options(CLI::App& cmd, PlatformOptions& o) {
  cmd.add_option("--can", o.interface, "SocketCAN interface of the platform (e.g. can0)")->required();
  cmd.add_flag("--fd", o.fd, "CAN FD: ISO-TP frames of 64 bytes");
}

int load(const PlatformOptions& o) {
  if (o.camera.empty() && o.geometry.empty())
    throw session::PlatformSetupError("give --camera camera.yaml, --geometry platform.yaml or both");
  std::optional<shared::CameraIntrinsics> camera;
  std::optional<shared::PlatformGeometry> geometry;
  if (!o.camera.empty()) camera = session::read_camera_block(o.camera);
  if (!o.geometry.empty()) geometry = session::read_geometry_block(o.geometry);

  can::SocketCanTransport transport(o.interface, {o.fd, true, {}});
  can::PlatformClient client(transport);
  (void)client.wait_heartbeat(std::chrono::milliseconds(1000));  // a platform is there, of our protocol
  if (camera) {
    const std::uint32_t sequence = session::load_block(client, *camera);
    std::cout << "loaded " << o.camera << " (read back equal, storage sequence " << sequence << ")\n"
              << session::describe(*camera);
  }
  if (geometry) {
    const std::uint32_t sequence = session::load_block(client, *geometry);
    std::cout << "loaded " << o.geometry << " (read back equal, storage sequence " << sequence << ")\n"
              << session::describe(*geometry);
  }
  return 0;
}

int show(const PlatformOptions& o) {
  can::SocketCanTransport transport(o.interface, {o.fd, true, {}});
  can::PlatformClient client(transport);
  const session::PlatformBlocks blocks = session::read_platform_blocks(client);
  std::cout << blocks.text;
  return blocks.complete ? 0 : 1;
}

// Runs `run` for the subcommand; an exception is its message and exit status 1.
void on_run(CLI::App& cmd, const std::string& name, const std::shared_ptr<PlatformOptions>& o, int& status,
            int (*run)(const PlatformOptions&)) {
  cmd.callback([name, o, &status, run] {
    try {
      status = run(*o);
    } catch (const std::exception& e) {
      std::cerr << "kincal platform " << name << ": " << e.what() << "\n";
      status = 1;
    }
  });
}

}  // namespace

void add_platform_command(CLI::App& app, int& status) {
  auto* cmd = app.add_subcommand("platform", "Set up a sensor platform: load its camera and geometry, show them");
  cmd->require_subcommand(1);

  auto lo = std::make_shared<PlatformOptions>();
  auto* load_cmd = cmd->add_subcommand(
      "load", "Load the camera calibration and the platform geometry into the platform, read back and compare");
  add_bus_options(*load_cmd, *lo);
  load_cmd->add_option("--camera", lo->camera, "camera calibration (kincal camera calibrate's YAML, OpenCV or ROS)");
  load_cmd->add_option("--geometry", lo->geometry, "platform geometry YAML: rangers, fiducial_side_m, square_pitch_m");
  on_run(*load_cmd, "load", lo, status, load);

  auto so = std::make_shared<PlatformOptions>();
  auto* show_cmd = cmd->add_subcommand("show", "Print the platform's camera and geometry blocks");
  add_bus_options(*show_cmd, *so);
  on_run(*show_cmd, "show", so, status, show);
}

}  // namespace kincal::cli

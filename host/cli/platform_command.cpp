#include "host/cli/platform_command.hpp"

#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

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

// The block decoded and described, or why not (printed; false).
template <class Block>
bool show_block(can::PlatformClient& client, shared::ParameterBlock id, const char* name) {
  std::vector<std::uint8_t> image;
  try {
    image = client.download(id);
  } catch (const can::PlatformError& e) {
    std::cout << name << ": not loaded (" << e.what() << ")\n";
    return false;
  }
  Block block;
  const shared::DecodeStatus status = shared::decode_block(image, block);
  if (status != shared::DecodeStatus::kOk) {
    std::cout << name << ": does not decode (" << can::to_string(status) << ")\n";
    return false;
  }
  std::cout << session::describe(block);
  return true;
}

int show(const PlatformOptions& o) {
  can::SocketCanTransport transport(o.interface, {o.fd, true, {}});
  can::PlatformClient client(transport);
  const bool camera = show_block<shared::CameraIntrinsics>(client, shared::ParameterBlock::kIntrinsics, "camera");
  const bool geometry = show_block<shared::PlatformGeometry>(client, shared::ParameterBlock::kGeometry, "geometry");
  return camera && geometry ? 0 : 1;
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

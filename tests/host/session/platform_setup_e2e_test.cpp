// A platform set up from files: the real firmware app (sim::SimulatedPlatform on the loopback
// bus, seeing rendered frames of Doty's strip) gets its camera and geometry blocks from a ROS
// camera file and a platform.yaml through session::load_block, exactly as `kincal platform load`
// gives them to a real one, and then measures the square's pose. Before the load it cannot.
#include <doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "host/camera/calibration_file.hpp"
#include "host/can/loopback.hpp"
#include "host/can/platform_client.hpp"
#include "host/session/platform_setup.hpp"
#include "host/sim/parameter_blocks.hpp"
#include "host/sim/rangers.hpp"
#include "host/sim/render.hpp"
#include "host/sim/simulated_platform.hpp"
#include "host/sim/strip.hpp"

using namespace kincal;

namespace {

std::filesystem::path test_dir() {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "kincal-platform-setup-e2e";
  std::filesystem::create_directories(dir);
  return dir;
}

// platform.yaml for the simulator's rangers and strip, written as an integrator would.
std::string write_platform_yaml(const sim::RangerSpec& rangers, const sim::StripSpec& strip) {
  std::ostringstream text;
  text.precision(17);
  text << "rangers:\n";
  for (const sim::Beam& b : sim::ranger_beams(rangers)) {
    text << "  - origin_m: [" << b.origin_m.x() << ", " << b.origin_m.y() << ", " << b.origin_m.z() << "]\n"
         << "    direction: [" << 3 * b.direction.x() << ", " << 3 * b.direction.y() << ", " << 3 * b.direction.z()
         << "]\n";
  }
  text << "fiducial_side_m: " << strip.fiducial_side_m << "\nsquare_pitch_m: " << strip.square_m << "\n";
  const std::string path = (test_dir() / "platform.yaml").string();
  std::ofstream(path) << text.str();
  return path;
}

constexpr std::uint8_t kPoseSections =
    shared::section::kRanges | shared::section::kPlane | shared::section::kFiducials | shared::section::kPose;

}  // namespace

TEST_CASE("kincal platform load's steps: a platform set up from files measures the square's pose") {
  sim::CameraSpec camera;
  camera.distortion = {-0.05, 0.01, 0.0002, -0.0001, 0};
  const sim::StripSpec strip;
  sim::RangerSpec rangers;
  rangers.origin_z_m = 0.004;
  rangers.sigma_m = 0;

  // The view: square 2 of the strip, 0.3 m in front, tilted.
  const Eigen::Isometry3d camera_T_square = sim::facing_camera(Eigen::Vector3d(0.005, -0.004, 0.3), 0.15, -0.1);
  const Eigen::Isometry3d camera_T_strip = camera_T_square * sim::strip_T_square(strip, 2).inverse();
  sim::SimulatedView view;
  std::mt19937_64 rng(7);
  view.set(sim::render_plane(camera, camera_T_strip, sim::strip_target(strip), sim::ImagingConditions{}),
           sim::simulate_ranges(rangers, camera_T_strip, rng));

  can::LoopbackBus bus;
  sim::SimulatedPlatform platform(bus, false, camera.width_px, camera.height_px, view);
  can::LoopbackTransport transport(bus.attach(), can::LoopbackOptions{});
  can::PlatformClient client(transport);

  // Without the blocks: no pose.
  client.set_mode(true, false, true);
  const shared::MeasurementReport before = client.measure(kPoseSections);
  CHECK(before.status == shared::MeasureStatus::kNoParameters);
  CHECK((before.sections & shared::section::kPose) == 0);
  // A running platform refuses the load, and the message says why.
  CHECK_THROWS_WITH_AS(session::load_block(client, sim::to_intrinsics(camera)),
                       doctest::Contains("camera block: parameter upload refused: not idle (the platform is measuring"),
                       can::PlatformError);
  client.set_mode(false, false);
  // `kincal platform show` says what is missing.
  const session::PlatformBlocks empty = session::read_platform_blocks(client);
  CHECK_FALSE(empty.complete);
  CHECK(empty.text.find("camera: not loaded (") != std::string::npos);
  CHECK(empty.text.find("geometry: not loaded (") != std::string::npos);

  // The files, as the integrator has them.
  const std::string camera_yaml = (test_dir() / "camera.yaml").string();
  camera::save_camera_ros(camera_yaml, camera::from_platform(sim::to_intrinsics(camera)), "platform");
  const std::string platform_yaml = write_platform_yaml(rangers, strip);
  const shared::CameraIntrinsics intrinsics = session::read_camera_block(camera_yaml);
  const shared::PlatformGeometry geometry = session::read_geometry_block(platform_yaml);

  // What the files give is what the simulator's own blocks say (the beams normalized again).
  std::array<std::uint8_t, shared::kMaxBlockBytes> ours{}, sims{};
  CHECK(shared::encode_block(intrinsics, ours) == shared::kIntrinsicsBytes);
  CHECK(shared::encode_block(sim::to_intrinsics(camera), sims) == shared::kIntrinsicsBytes);
  CHECK(ours == sims);
  const shared::PlatformGeometry sim_geometry = sim::platform_geometry(strip, rangers);
  for (std::size_t i = 0; i < shared::kRangers; ++i) {
    CHECK(geometry.rangers[i].origin_m == sim_geometry.rangers[i].origin_m);
    CHECK(geometry.rangers[i].direction == sim_geometry.rangers[i].direction);
  }
  CHECK(geometry.fiducial_count == sim_geometry.fiducial_count);
  CHECK(geometry.fiducial_square_m == sim_geometry.fiducial_square_m);
  CHECK(geometry.square_pitch_m == sim_geometry.square_pitch_m);

  // Loaded and read back equal (load_block compares); a second load is stored anew, with a newer
  // storage sequence.
  (void)session::load_block(client, intrinsics);
  const std::uint32_t geometry_sequence = session::load_block(client, geometry);
  CHECK(session::load_block(client, geometry) > geometry_sequence);
  shared::PlatformGeometry stored;
  REQUIRE(shared::decode_block(client.download(shared::ParameterBlock::kGeometry), stored) ==
          shared::DecodeStatus::kOk);
  CHECK(stored.square_pitch_m == geometry.square_pitch_m);
  CHECK(stored.rangers[3].origin_m == geometry.rangers[3].origin_m);
  const session::PlatformBlocks shown = session::read_platform_blocks(client);
  CHECK(shown.complete);
  CHECK(shown.text == session::describe(intrinsics) + session::describe(geometry));

  // Now the pose: the camera centre in the square's frame, within a few millimetres of the truth
  // (the reference square is the one the FID found: the nearest of the strip's).
  client.set_mode(true, false, true);
  const shared::MeasurementReport after = client.measure(kPoseSections);
  CHECK(after.status == shared::MeasureStatus::kOk);
  REQUIRE((after.sections & shared::section::kPose) != 0);
  Eigen::Vector3d measured_m;
  for (int k = 0; k < 3; ++k) measured_m(k) = after.translation_raw[static_cast<std::size_t>(k)] * std::ldexp(1.0, -18);
  double nearest_m = std::numeric_limits<double>::infinity();
  for (int square = 0; square < strip.squares; ++square) {
    const Eigen::Isometry3d square_T_camera = (camera_T_strip * sim::strip_T_square(strip, square)).inverse();
    nearest_m = std::min(nearest_m, (square_T_camera.translation() - measured_m).norm());
  }
  CAPTURE(measured_m.transpose());
  CHECK(nearest_m < 0.002);
  CHECK(after.pose_squares >= 2);  // the pitch from platform.yaml let it use the neighbours
  client.set_mode(false, false);
}

// libFuzzer target for the files the camera commands, the stereo rig and `platform load` read
// (issue #25), each through a temporary file and the input layer where the reader takes a path:
//   - robot poses (camera::parse_robot_poses, `camera hand-eye --poses`): CalibrationError
//     "FILE:LINE: what" with a short message, or poses with a finite translation within reach
//     and a rotation orthonormal to 1e-9;
//   - camera files (camera::load_camera, load_camera_uncertainty; OpenCV YAML or ROS
//     camera_info) and the platform's camera block (session::read_camera_block): an error naming
//     the file, or a camera that the writer writes and the reader reads back to the same matrix;
//   - stereo and hand-eye files, the platform's geometry (session::read_geometry_block): an
//     error naming the file, or a value;
//   - colour tables (core::parse_colour_table, `--colour-table`): the fuzzer signs the block with
//     its CRC (so mutations reach the checks behind it); a block parsed serializes back to the
//     same bytes.
// The first input byte chooses the reader: 0-1 poses (bits 3-4: the rotation columns' meaning),
// 2-3 camera, 4 stereo, 5 hand-eye, 6 geometry, 7 colour table; the rest is the file. Any other
// exception, a crash, a leak or undefined behaviour is a finding. Runs standalone too, and as the
// ctest fuzz.camera_inputs for a bounded time; seeds in camera_inputs_seeds/.
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <span>
#include <sstream>
#include <string>

#include "firmware/core/colour_class.hpp"
#include "host/camera/calibration_file.hpp"
#include "host/camera/robot_poses.hpp"
#include "host/session/platform_files.hpp"
#include "shared/crc32.hpp"

using namespace kincal;

namespace {

void require(bool condition) {
  if (!condition) std::abort();
}

void short_message_naming(const std::exception& e, const std::string& source) {
  const std::string message = e.what();
  require(message.size() < 4096 && message.rfind(source, 0) == 0);
}

void robot_poses(const std::string& text, std::uint8_t choice) {
  static const camera::RotationColumns kRotation[] = {camera::RotationColumns::kUnnamed,
                                                      camera::RotationColumns::kRotationVector,
                                                      camera::RotationColumns::kRpy, camera::RotationColumns::kRpyDeg};
  std::istringstream in(text);
  try {
    for (const camera::RobotPose& p : camera::parse_robot_poses(in, "fuzz.csv", kRotation[(choice >> 3) & 3])) {
      require(p.pose.translation().allFinite() && p.pose.translation().norm() <= camera::kMaxRobotReach_m);
      const Eigen::Matrix3d r = p.pose.rotation();
      require((r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-9 && r.determinant() > 0);
    }
  } catch (const camera::CalibrationError& e) {
    short_message_naming(e, "fuzz.csv");
  }
}

// Reader `which`: 0 a camera (and its uncertainty keys, and the platform's camera block), 1 a
// stereo pair, 2 hand-eye, 3 the platform's geometry (platform.yaml).
void settings_file(const std::string& text, int which) {
  const std::string path = "/tmp/kincal_camera_fuzz_" + std::to_string(::getpid()) + ".yaml";
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
  try {
    if (which == 0) {
      (void)camera::load_camera_uncertainty(path);
      const camera::CameraModel c = camera::load_camera(path);
      (void)session::read_camera_block(path);
      camera::save_camera_ros(path, c, "fuzz");
      require(camera::load_camera(path).camera_matrix == c.camera_matrix);
    } else if (which == 1) {
      (void)camera::load_stereo(path);
    } else if (which == 2) {
      (void)camera::load_hand_eye(path);
    } else {
      (void)session::read_geometry_block(path);
    }
  } catch (const camera::CalibrationError& e) {
    short_message_naming(e, path);
  } catch (const session::PlatformSetupError& e) {
    short_message_naming(e, path);
  }
  std::remove(path.c_str());
}

void colour_table(std::string text) {
  if (text.size() == core::kColourTableBlockBytes) {  // CRC-32 of all but the last 4 bytes, little-endian
    const std::uint32_t crc = shared::crc32_text(std::span(text).first(text.size() - 4));
    for (std::size_t k = 0; k < 4; ++k) text[text.size() - 4 + k] = static_cast<char>(crc >> (8 * k));
  }
  const std::span<const std::uint8_t> block(reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
  core::ColourClassTable table;
  if (core::parse_colour_table(block, table) != core::ColourTableStatus::kOk) return;
  std::array<std::uint8_t, core::kColourTableBlockBytes> again{};
  core::serialize_colour_table(table, again);
  require(std::equal(again.begin(), again.end(), block.begin()));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  switch (data[0] & 7) {
    case 0:
    case 1:
      robot_poses(text, data[0]);
      break;
    case 2:
    case 3:
      settings_file(text, 0);
      break;
    case 7:
      colour_table(text);
      break;
    default:
      settings_file(text, (data[0] & 7) - 3);
  }
  return 0;
}

#include "host/session/platform_setup.hpp"

#include <array>
#include <chrono>
#include <sstream>
#include <vector>

#include "firmware/app/platform_measurement.hpp"

namespace kincal::session {

namespace {

template <class Block>
std::uint32_t upload_and_verify(can::PlatformClient& client, shared::ParameterBlock id, const Block& block,
                                const char* name) {
  std::array<std::uint8_t, shared::kMaxBlockBytes> image{};
  const std::size_t n = shared::encode_block(block, image);
  const std::span<const std::uint8_t> sent(image.data(), n);
  std::uint32_t sequence = 0;
  try {
    sequence = client.upload(id, sent);
  } catch (const can::PlatformError& e) {
    throw can::PlatformError(std::string(name) + " block: " + e.what());
  }
  const std::vector<std::uint8_t> back = client.download(id);
  if (back.size() != n)
    throw PlatformSetupError(std::string(name) + " block read back with " + std::to_string(back.size()) +
                             " bytes, uploaded " + std::to_string(n));
  for (std::size_t i = 0; i < n; ++i) {
    if (back[i] != sent[i])
      throw PlatformSetupError(std::string(name) + " block read back differs from the upload at byte " +
                               std::to_string(i));
  }
  return sequence;
}

}  // namespace

std::uint32_t load_block(can::PlatformClient& client, const shared::CameraIntrinsics& camera) {
  return upload_and_verify(client, shared::ParameterBlock::kIntrinsics, camera, "camera");
}

std::uint32_t load_block(can::PlatformClient& client, const shared::PlatformGeometry& geometry) {
  return upload_and_verify(client, shared::ParameterBlock::kGeometry, geometry, "geometry");
}

std::string describe(const shared::CameraIntrinsics& c) {
  std::ostringstream s;
  s << "camera: " << c.width_px << " x " << c.height_px << " px, fx " << c.fx_px << " fy " << c.fy_px << " cx "
    << c.cx_px << " cy " << c.cy_px << " px\n"
    << "  distortion k1 " << c.k1 << " k2 " << c.k2 << " p1 " << c.p1 << " p2 " << c.p2 << " k3 " << c.k3 << "\n";
  return s.str();
}

std::string describe(const shared::PlatformGeometry& g) {
  std::ostringstream s;
  s << "geometry: " << int{shared::kRangers} << " rangers (camera frame, m)\n";
  for (std::size_t i = 0; i < g.rangers.size(); ++i) {
    const shared::RangerBeam& b = g.rangers[i];
    s << "  ranger " << i << ": origin (" << b.origin_m[0] << ", " << b.origin_m[1] << ", " << b.origin_m[2]
      << ") direction (" << b.direction[0] << ", " << b.direction[1] << ", " << b.direction[2] << ")\n";
  }
  s << "  fiducials: " << int{g.fiducial_count} << " (square frame, m):";
  for (std::size_t k = 0; k < g.fiducial_count && k < g.fiducial_square_m.size(); ++k)
    s << " p" << k + 1 << " (" << g.fiducial_square_m[k][0] << ", " << g.fiducial_square_m[k][1] << ")";
  // The side as the platform recovers it.
  if (const float side_m = app::fiducial_side_m(g); side_m > 0.0f) s << "\n  fiducial side: " << side_m << " m";
  s << "\n  square pitch: " << g.square_pitch_m << " m" << (g.square_pitch_m == 0.0f ? " (one square per frame)" : "")
    << "\n";
  return s.str();
}

namespace {

// The block described, or why not; false when it is not there.
template <class Block>
bool describe_stored(can::PlatformClient& client, shared::ParameterBlock id, const char* name, std::string& text) {
  std::vector<std::uint8_t> image;
  try {
    image = client.download(id);
  } catch (const can::PlatformError& e) {
    text += std::string(name) + ": not loaded (" + e.what() + ")\n";
    return false;
  }
  Block block;
  const shared::DecodeStatus status = shared::decode_block(image, block);
  if (status != shared::DecodeStatus::kOk) {
    text += std::string(name) + ": stored, but does not decode (" + can::to_string(status) + ")\n";
    return false;
  }
  text += describe(block);
  return true;
}

}  // namespace

PlatformBlocks read_platform_blocks(can::PlatformClient& client) {
  PlatformBlocks out;
  (void)client.wait_heartbeat(std::chrono::milliseconds(1000));  // a platform is there, of our protocol
  const bool camera =
      describe_stored<shared::CameraIntrinsics>(client, shared::ParameterBlock::kIntrinsics, "camera", out.text);
  const bool geometry =
      describe_stored<shared::PlatformGeometry>(client, shared::ParameterBlock::kGeometry, "geometry", out.text);
  out.complete = camera && geometry;
  return out;
}

}  // namespace kincal::session

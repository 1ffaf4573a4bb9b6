#include "host/sim/parameter_blocks.hpp"

#include <cstdint>
#include <stdexcept>
#include <string>

namespace kincal::sim {

shared::CameraIntrinsics to_intrinsics(const CameraSpec& camera) {
  // render_plane's checks, on an empty projection: the same errors for the same fields.
  (void)project_points(camera, Eigen::Isometry3d::Identity(), {});
  shared::CameraIntrinsics block;
  block.fx_px = static_cast<float>(camera.fx_px);
  block.fy_px = static_cast<float>(camera.fy_px);
  block.cx_px = static_cast<float>(camera.cx_px);
  block.cy_px = static_cast<float>(camera.cy_px);
  block.k1 = static_cast<float>(camera.distortion[0]);
  block.k2 = static_cast<float>(camera.distortion[1]);
  block.p1 = static_cast<float>(camera.distortion[2]);
  block.p2 = static_cast<float>(camera.distortion[3]);
  block.k3 = static_cast<float>(camera.distortion[4]);
  block.width_px = static_cast<std::uint16_t>(camera.width_px);
  block.height_px = static_cast<std::uint16_t>(camera.height_px);
  return block;
}

shared::PlatformGeometry platform_geometry(const StripSpec& strip, const RangerSpec& rangers) {
  shared::PlatformGeometry block;
  const std::array<Beam, kRangerCount> beams = ranger_beams(rangers);
  static_assert(kRangerCount == shared::kRangers);
  for (std::size_t i = 0; i < beams.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      block.rangers[i].origin_m[static_cast<std::size_t>(k)] = static_cast<float>(beams[i].origin_m(k));
      block.rangers[i].direction[static_cast<std::size_t>(k)] = static_cast<float>(beams[i].direction(k));
    }
  }
  const std::array<FiducialRect, 6> fiducials = square_fiducials(strip);
  static_assert(6 <= shared::kMaxFiducials);
  block.fiducial_count = static_cast<std::uint8_t>(fiducials.size());
  for (std::size_t i = 0; i < fiducials.size(); ++i) {
    block.fiducial_square_m[i] = {static_cast<float>(fiducials[i].centre_m.x()),
                                  static_cast<float>(fiducials[i].centre_m.y()), 0.0f};
  }
  // Square k's centre is at (k square_m, 0, 0) in the strip frame, axes parallel (strip.hpp).
  block.square_pitch_m = static_cast<float>(strip.square_m);
  if (!(block.square_pitch_m >= shared::kMinSquarePitchM && block.square_pitch_m <= shared::kMaxSquarePitchM))
    throw std::invalid_argument("square_m " + std::to_string(strip.square_m) +
                                " m: the geometry block's square pitch must be within [0.01, 2] m");
  return block;
}

}  // namespace kincal::sim

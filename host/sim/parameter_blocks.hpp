// The simulated platform's parameter blocks (shared/parameters.hpp), as the host would load
// them into the firmware: the camera's intrinsics, and the geometry block (ranger beams in the
// camera frame, fiducial positions in the square frame, the strip's square pitch).
//
// Values are rounded to float32, the blocks' type. Cost: trivial. Errors: std::invalid_argument
// naming the field: a CameraSpec that render_plane would refuse (its sizes then fit the block's
// u16 fields); the StripSpec / RangerSpec checks of strip.hpp and rangers.hpp; a square_m outside
// the block's square pitch range [0.01, 2] m.
#pragma once

#include "host/sim/rangers.hpp"
#include "host/sim/render.hpp"
#include "host/sim/strip.hpp"
#include "shared/parameters.hpp"

namespace kincal::sim {

shared::CameraIntrinsics to_intrinsics(const CameraSpec& camera);

// fiducial_count 6, fiducial_square_m[k - 1] = p_k's centre (z = 0), rangers as ranger_beams(),
// square_pitch_m = strip.square_m (the platform's pose may use every square in view).
shared::PlatformGeometry platform_geometry(const StripSpec& strip, const RangerSpec& rangers);

}  // namespace kincal::sim

// Doty's calibration strip (ARID report sections 5 and 7): calibration squares of 4 inches in a
// row, each printed dark on light with the fiducial layout that Doty's FID identifies
// (firmware/core/fiducial_id.hpp), as a PlanarTarget the renderer draws.
//
// One square, in its own frame, carries Doty's fiducial layout (host/target/doty_square.hpp).
// Strip frame: square k's centre at (k square_m, 0, 0), axes parallel to the squares'
// (so the strip is read from +z too); squares touch, the strip is square_m wide in y; beyond
// it the surround's reflectance.
//
// Cost: the reflectance is a few comparisons per call. Errors: std::invalid_argument naming the
// field (square count outside 1..64, non-positive sizes, fiducials that do not fit inside the
// square, reflectances outside [0, 1]).
#pragma once

#include <array>

#include <Eigen/Geometry>

#include "host/sim/render.hpp"
#include "host/target/doty_square.hpp"

namespace kincal::sim {

using target::kInch_m;

struct StripSpec {
  int squares = 5;
  double square_m = 4 * kInch_m;
  double fiducial_side_m = kInch_m / 4;  // s
  double paper = 0.9;                    // reflectance of the vellum
  double ink = 0.05;                     // of the fiducials
  double surround = 0.5;                 // beyond the strip
};

using target::FiducialRect;

// The six fiducials of one square (target::doty_square_fiducials with the spec's side), after
// the spec's checks.
std::array<FiducialRect, 6> square_fiducials(const StripSpec& spec);

// The strip as the renderer's target (strip frame).
PlanarTarget strip_target(const StripSpec& spec);

// strip_T_square for square `index` (0..squares-1); throws std::invalid_argument otherwise.
Eigen::Isometry3d strip_T_square(const StripSpec& spec, int index);

}  // namespace kincal::sim

// Doty's calibration strip (ARID report sections 5 and 7): calibration squares of 4 inches in a
// row, each printed dark on light with the fiducial layout that Doty's FID identifies
// (firmware/core/fiducial_id.hpp), as a PlanarTarget the renderer draws.
//
// One square, in its own frame (the frame of fiducial_id.hpp and of the platform's pose
// report: origin at the centre fiducial p4, x toward p5, y toward p2, z out of the printed side),
// with s the small fiducial's side (1/4 inch):
//   p1 corner marker  s x s  at (-7s, +7s)
//   p2                s x s  at (0, +7s)
//   p3                s x s  at (-7s, 0)
//   p4 centre         s x 2s at (0, 0) (its long side along y)
//   p5                s x s  at (+7s, 0)
//   p6                s x s  at (0, -7s)
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

namespace kincal::sim {

inline constexpr double kInch_m = 0.0254;

struct StripSpec {
  int squares = 5;
  double square_m = 4 * kInch_m;
  double fiducial_side_m = kInch_m / 4;  // s
  double paper = 0.9;                    // reflectance of the vellum
  double ink = 0.05;                     // of the fiducials
  double surround = 0.5;                 // beyond the strip
};

// A fiducial rectangle in the square frame: centre and full sizes along x and y, metres.
struct FiducialRect {
  int id = 0;  // Doty's p1..p6
  Eigen::Vector2d centre_m;
  Eigen::Vector2d size_m;
};

// The six fiducials of one square, in the order the FID reports them (p1..p6): element k - 1
// is p_k, so their centres load directly into PlatformGeometry::fiducial_square_m.
std::array<FiducialRect, 6> square_fiducials(const StripSpec& spec);

// The strip as the renderer's target (strip frame).
PlanarTarget strip_target(const StripSpec& spec);

// strip_T_square for square `index` (0..squares-1); throws std::invalid_argument otherwise.
Eigen::Isometry3d strip_T_square(const StripSpec& spec, int index);

}  // namespace kincal::sim

// Doty's calibration square (ARID report sections 5 and 7): the fiducial layout that Doty's FID
// identifies (firmware/core/fiducial_id.hpp), in metres, for the host code that needs it as
// numbers: the simulator draws it (host/sim/strip.hpp), the platform setup loads its centres into
// the platform's geometry block (host/session/platform_files.hpp).
//
// The square frame (that of fiducial_id.hpp and of the platform's pose report): origin at the
// centre fiducial p4, x toward p5, y toward p2, z out of the printed side. With s the small
// fiducial's side (Doty's: 1/4 inch):
//   p1 corner marker  s x s  at (-7s, +7s)
//   p2                s x s  at (0, +7s)
//   p3                s x s  at (-7s, 0)
//   p4 centre         s x 2s at (0, 0) (its long side along y)
//   p5                s x s  at (+7s, 0)
//   p6                s x s  at (0, -7s)
// The outermost fiducial edges lie 7.5 s from the centre.
//
// Cost: trivial. Errors: std::invalid_argument if the side is not positive and finite.
#pragma once

#include <array>

#include <Eigen/Core>

namespace kincal::target {

inline constexpr double kInch_m = 0.0254;
inline constexpr double kDotyFiducialSideM = kInch_m / 4;  // s
inline constexpr double kDotySquareM = 4 * kInch_m;        // the strip's squares, touching
inline constexpr double kDotyFarSides = 7;                 // perimeter fiducials at 7 s from p4

// A fiducial rectangle in the square frame: centre and full sizes along x and y, metres.
struct FiducialRect {
  int id = 0;  // Doty's p1..p6
  Eigen::Vector2d centre_m;
  Eigen::Vector2d size_m;
};

// The six fiducials of one square for the side `fiducial_side_m` (s), in the order the FID
// reports them: element k - 1 is p_k, so their centres load directly into
// shared::PlatformGeometry::fiducial_square_m.
std::array<FiducialRect, 6> doty_square_fiducials(double fiducial_side_m);

}  // namespace kincal::target

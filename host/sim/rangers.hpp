// The sensor platform's four range sensors, simulated (ARID mode, issue #6): narrow beams in a
// + pattern around the camera, parallel to its optical axis, each reporting the distance along
// its beam to the calibration strip's plane, with Gaussian noise.
//
// Layout (camera frame, OpenCV axes: x right, y down, z along the optical axis), in the order
// of core::plus_pattern_layout (firmware/core/range_plane.hpp): sensor 0 at (+d/2, 0, z0),
// 1 at (0, +d/2, z0), 2 at (-d/2, 0, z0), 3 at (0, -d/2, z0), d = spacing_m; all beams along +z.
// These are the rangers of shared::PlatformGeometry (parameter_blocks.hpp writes them there).
//
// A reading is the ray parameter t >= 0 where origin + t direction meets the target's z = 0
// plane (the strip's plane is unbounded here: beyond the strip a beam meets the surface the
// strip lies on), plus N(0, sigma_m^2). No echo (NaN) when the plane is behind the sensor or
// parallel to the beam, when the true range exceeds max_range_m, or when the incidence angle
// (between the beam and the plane's normal) exceeds max_incidence_rad: the echo is reflected
// away. Cost: a few flops per sensor. Errors: std::invalid_argument naming the RangerSpec field
// (non-positive or non-finite spacing, max range or incidence limit, negative noise) or a
// non-finite pose.
#pragma once

#include <array>
#include <numbers>
#include <random>

#include <Eigen/Geometry>

namespace kincal::sim {

inline constexpr int kRangerCount = 4;

struct RangerSpec {
  double spacing_m = 0.1;    // d: between the sensors of each opposite pair
  double origin_z_m = 0.0;   // z0: the sensors' faces relative to the camera centre
  double sigma_m = 0.5e-3;   // reading noise, Gaussian
  double max_range_m = 0.9;  // beyond: no echo (the report's range field ends at 1 m)
  double max_incidence_rad = 50 * std::numbers::pi / 180;
};

struct Beam {
  Eigen::Vector3d origin_m;   // camera frame
  Eigen::Vector3d direction;  // unit, camera frame
};

std::array<Beam, kRangerCount> ranger_beams(const RangerSpec& spec);

// The four readings (metres; NaN: no echo) of the plane z = 0 of a target at camera_T_target.
// Noise comes from `rng` (four normal draws per call, whether or not a sensor echoes, so that a
// sequence of calls stays aligned).
std::array<double, kRangerCount> simulate_ranges(const RangerSpec& spec, const Eigen::Isometry3d& camera_T_target,
                                                 std::mt19937_64& rng);

}  // namespace kincal::sim

// The calibration plane in the camera frame, from the four range sensors around the camera.
//
// Doty's ARID platform (report section 7) carries four rangers in a + pattern around the
// camera; their readings fix the plane of the calibration square, on which every fiducial
// lies, so that one image gives 3-D fiducial points (camera_model.hpp). Doty derives the plane
// from sonar heights through ad hoc corner points (7-1..7-5), a 3x3 solve (7-10), a
// pseudo-inverse (7-11) and a planarity condition (7-24). Here the same ideas are derived again
// for any sensor layout, and exactly:
//
//   along_beam      (narrow-beam time-of-flight rangers) sensor i's beam leaves (x_i, y_i, z0)
//                   parallel to the optical axis and hits the surface at z_i = z0 + range_i.
//                   The plane z = c0 + cx x + cy y is linear in the ranges.
//   perpendicular   (wide-beam sonar, Doty's assumption) sensor i at (x_i, y_i, z0) reports its
//                   perpendicular distance h_i to the plane n.p = rho, i.e. h_i = rho - n.s_i =
//                   (rho - n_z z0) - n_x x_i - n_y y_i: again linear, in (c0, -n_x, -n_y).
//
// Because the sensor positions are fixed, each fit is a constant 3x4 matrix times the readings:
// prepare_range_plane() computes the least-squares matrix (all four; Doty's 7-11 without a
// run-time pseudo-inverse), the four exact three-point matrices (Doty's 7-10/7-21, one per
// left-out sensor), and the null vector of the layout, which turns the four readings into the
// least-squares residuals directly: residual_i = null_i * (null . readings). For the + pattern
// that is +-(r0 - r1 + r2 - r3)/4 -- Doty's planarity condition 7-24 in its exact form
// (opposite pairs have equal sums), without his cosine factors, which came from his corner
// construction.
//
// Frames and units: camera frame as in OpenCV (x right, y down, z forward along the optical
// axis, origin at the projection centre); metres. The plane is n . p = distance_m with n the
// unit normal pointing away from the camera (n_z > 0) and distance_m > 0 its distance from the
// camera centre.
//
// Error bound (asserted by tests/firmware/core/range_plane_test.cpp against a double-precision
// fit over random planes, tilts up to 40 degrees, ranges 0.05..2 m, spacing 0.05..0.3 m): with
// exact readings (rounded to float) the normal is within kPlaneNormalErrorPerRange * (max range /
// spacing) rad and the distance within kPlaneDistanceErrorPerRange * max range * (1 + max range /
// spacing) of the exact plane (the tilt error moves the along-beam distance too).
//
// Cost: fit_range_plane is about 40 multiply-adds and one square root, 198 instructions on the
// M4F (-O3, geometry_m4_bench); no loops beyond the four sensors. prepare_range_plane runs once
// per configuration (five 3x3 inversions).
#pragma once

#include <array>
#include <cstdint>

#include "firmware/core/rigid_transform.hpp"

namespace kincal::core {

inline constexpr int kRangeSensorCount = 4;

// Bound constants of the header comment (float eps = 1.19e-7).
inline constexpr float kPlaneNormalErrorPerRange = 6.0e-7f;
inline constexpr float kPlaneDistanceErrorPerRange = 3.0e-7f;

enum class [[nodiscard]] PlaneStatus : std::uint8_t{
    ok,
    bad_layout,           // prepare: three sensors collinear, or limits/tolerance not positive
    range_missing,        // a reading is NaN or infinite and no three-point fallback applies
    range_out_of_limits,  // a reading is outside [min_range_m, max_range_m], no fallback applies
    not_flat,             // four readings, least-squares residual above flatness_tolerance_m
    plane_not_facing,     // the fitted plane does not face the camera (distance <= 0, or a
                          // perpendicular-model normal that is not a unit vector)
};

enum class RangeModel : std::uint8_t { along_beam, perpendicular };

struct RangeSensorLayout {
  std::array<Vector2<float>, kRangeSensorCount> position_m{};  // (x, y) of each sensor, camera frame
  float origin_z_m = 0.0f;                                     // z of the sensors (common)
  RangeModel model = RangeModel::along_beam;
  float min_range_m = 0.02f;
  float max_range_m = 4.0f;
  float flatness_tolerance_m = 0.002f;  // largest least-squares residual accepted
  bool allow_three_point = true;        // one bad reading: exact plane from the other three
};

// The + pattern of the issue: sensors 0..3 at (+s/2, 0), (0, +s/2), (-s/2, 0), (0, -s/2),
// i.e. spacing_m between the sensors of each opposite pair (Doty's d).
RangeSensorLayout plus_pattern_layout(float spacing_m, RangeModel model) noexcept;

// Constant matrices of a layout; build with prepare_range_plane, then only read.
struct RangePlaneModel {
  RangeModel model = RangeModel::along_beam;
  float origin_z_m = 0.0f;
  float min_range_m = 0.0f;
  float max_range_m = 0.0f;
  float flatness_tolerance_m = 0.0f;
  bool allow_three_point = true;
  // Rows (c0, cx, cy) from the four readings (z_i or h_i): least squares, and exact with
  // sensor k left out (column k zero).
  Eigen::Matrix<float, 3, kRangeSensorCount> least_squares{};
  std::array<Eigen::Matrix<float, 3, kRangeSensorCount>, kRangeSensorCount> three_point{};
  Eigen::Matrix<float, kRangeSensorCount, 1> null_vector{};  // unit; residuals = null * (null . values)
};

struct CalibrationPlane {
  Vector3<float> normal{0.0f, 0.0f, 1.0f};  // unit, camera frame, pointing away from the camera
  float distance_m = 0.0f;                  // n . p = distance_m for points p on the plane
  float flatness_residual_m = 0.0f;         // largest |least-squares residual|; 0 for three points
  std::uint8_t sensors_used = 0;            // bit i set: reading i entered the fit
};

PlaneStatus prepare_range_plane(const RangeSensorLayout& layout, RangePlaneModel& model) noexcept;

// The plane from the four readings (range_m[i] from sensor i; NaN marks a missing reading).
// Four good readings: least-squares plane and the flatness check. Exactly one bad reading and
// allow_three_point: the exact plane through the other three (no flatness check possible).
// Otherwise the status names the first bad reading's problem. `plane` is written on ok, and on
// not_flat (the least-squares fit and its residual, for diagnostics); else left as it was.
PlaneStatus fit_range_plane(const RangePlaneModel& model, const std::array<float, kRangeSensorCount>& range_m,
                            CalibrationPlane& plane) noexcept;

// The covariance of the fitted plane in the slope form z = c0 + slope_x x + slope_y y (camera
// frame; order (c0_m, slope_x, slope_y); c0 = distance_m / n_z, slope = -(n_x, n_y) / n_z), from
// independent range noise of standard deviation range_sigma_m on each reading that entered the fit
// (plane.sensors_used: all four, or three). Along-beam: the fit is a constant matrix F times the
// readings, so the covariance is sigma^2 F F^T exactly. Perpendicular: F gives (c0', -n_x, -n_y)
// and the slope form follows to first order at `plane`. This is the prior planar_pose.hpp takes.
// Statuses: ok; bad_layout when range_sigma_m is not positive and finite; range_missing when
// sensors_used names fewer than three sensors; plane_not_facing when n_z <= 0. `covariance` is
// written only on ok. Cost: about 60 multiply-adds.
PlaneStatus range_plane_covariance(const RangePlaneModel& model, const CalibrationPlane& plane, float range_sigma_m,
                                   Matrix3<float>& covariance) noexcept;

}  // namespace kincal::core

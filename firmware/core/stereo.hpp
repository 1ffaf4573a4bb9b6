// Stereo triangulation of a beacon seen by two cameras, with its depth uncertainty.
//
// Kapucu & Baysec watch a beacon on the robot's tip with two parallel, identical cameras
// (baseline 12.6 cm, f = 1 cm, 11 um pixels, 4.54 m away) and turn the two centroids into a
// point. Two functions here:
//
//   triangulate_parallel   their rig: rectified cameras, same focal length, right camera at
//                          +baseline along the left camera's x axis. disparity d = (u_L - cx_L) -
//                          (u_R - cx_R) px; Z = fx b / d, X = (u_L - cx_L) Z / fx, Y from the
//                          mean row. Depth sigma = Z^2 / (fx b) * sqrt(2) sigma_px (two
//                          independent centroids): at their 4.54 m, one pixel of disparity is
//                          0.18 m of depth -- their centimetre errors are sub-pixel noise.
//   triangulate_pair       any calibrated pair (OpenCV intrinsics and distortion for each camera,
//                          left_T_right from stereoCalibrate): both pixels are undistorted to rays
//                          and the point is the midpoint of the shortest segment between them.
//                          The closed form uses n = d_L x d_R throughout (|n|^2 instead of
//                          (a c - b^2), which cancels for far points). The depth sigma is first-
//                          order propagation of sigma_px through undistortion and triangulation
//                          (the exact Jacobian, four columns).
//
// Frames: the left camera's (OpenCV: x right, y down, z forward); Kapucu & Baysec put the origin
// at the right camera with y up -- translate and flip y to compare. Units: metres and pixels.
//
// Statuses (the point is written only on ok):
//   bad_rig           non-positive or non-finite focal length, baseline or sigma
//   behind_camera     the rays meet behind either camera (negative disparity)
//   zero_disparity    rays parallel within min_disparity_px (parallel rig) or min_ray_angle_rad:
//                     the point is at infinity, its depth unbounded
//   rows_mismatch     parallel rig: rows differ by more than max_row_difference_px -- not the
//                     same beacon, or the rig is not rectified
//   rays_miss         general pair: the rays pass further apart than max_ray_gap_px (measured
//                     as an angle at the left camera, in its pixels): mismatched centroids
//   undistortion_failed   a pixel the camera model cannot invert (camera_model.hpp)
//
// Error bounds (tests/firmware/core/stereo_test.cpp against double precision over random rigs and
// points): parallel rig, relative error <= 3e-7 * (1 + max|u - cx| / d) for the given float pixels
// (the rounding of a centred column, relative to the disparity, is the floor);
// general pair, point error <= kStereoPointErrorPerM2 * (Z^2 / b + Z) (undistortion error
// amplified by the triangulation's geometry); depth sigma within 1e-4 relative of a double
// finite-difference propagation (measured 3.5e-7 and 1.4e-5).
//
// Cost on the M4F (-O3, tests/bench/geometry_m4_bench.cpp): triangulate_parallel 111
// instructions, triangulate_pair 1,399 (two undistortions included). No state, no allocation.
#pragma once

#include <cstdint>

#include "firmware/core/camera_model.hpp"
#include "firmware/core/rigid_transform.hpp"

namespace kincal::core {

inline constexpr float kStereoPointErrorPerM2 = 1.0e-6f;

enum class [[nodiscard]] StereoStatus : std::uint8_t{
    ok, bad_rig, behind_camera, zero_disparity, rows_mismatch, rays_miss, undistortion_failed,
};

struct ParallelStereoRig {
  float focal_x_px = 0.0f;  // fx = f / pixel width
  float focal_y_px = 0.0f;  // fy = f / pixel height (K&B's cells are 11 x 13 um)
  float baseline_m = 0.0f;
  Vector2<float> principal_left_px{0.0f, 0.0f};
  Vector2<float> principal_right_px{0.0f, 0.0f};
  float min_disparity_px = 1.0e-3f;
  float max_row_difference_px = 2.0f;
};

struct StereoPair {
  CameraIntrinsics left;
  CameraIntrinsics right;
  RigidTransform<float> left_T_right;  // the right camera's pose in the left camera's frame
  float min_ray_angle_rad = 1.0e-6f;
  float max_ray_gap_px = 2.0f;
};

struct StereoPoint {
  Vector3<float> point_left_m{0.0f, 0.0f, 0.0f};  // in the left camera's frame
  float depth_sigma_m = 0.0f;                     // standard deviation of the point's z
  float ray_gap_px = 0.0f;                        // closest distance of the two rays, as pixels of the left camera
};

StereoStatus triangulate_parallel(const ParallelStereoRig& rig, const Vector2<float>& left_px,
                                  const Vector2<float>& right_px, float pixel_sigma_px, StereoPoint& point) noexcept;

StereoStatus triangulate_pair(const StereoPair& pair, const Vector2<float>& left_px, const Vector2<float>& right_px,
                              float pixel_sigma_px, StereoPoint& point) noexcept;

}  // namespace kincal::core

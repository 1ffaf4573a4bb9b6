// The platform camera: OpenCV's pinhole model with radial-tangential distortion, pixel -> ray,
// and ray -> 3-D point on the calibration plane.
//
// Why OpenCV's convention: the host calibrates the camera with calib3d (issue #6), and its
// cameraMatrix (fx, fy, cx, cy; zero skew) and distCoeffs (k1, k2, p1, p2, k3) must load here
// as they are. The model, for a point (X, Y, Z) in the camera frame (x right, y down, z forward):
//
//   x = X/Z, y = Y/Z, r^2 = x^2 + y^2, radial = 1 + k1 r^2 + k2 r^4 + k3 r^6
//   x_d = x radial + 2 p1 x y + p2 (r^2 + 2 x^2),  y_d = y radial + p1 (r^2 + 2 y^2) + 2 p2 x y
//   u = fx x_d + cx,  v = fy y_d + cy            (pixel (0, 0) = centre of the top-left pixel)
//
// pixel_to_normalized inverts the distortion by Newton's method on the 2x2 map with a
// backtracking line search: at most kUndistortMaxIterations steps of at most
// kUndistortMaxHalvings halvings each, so the cost is bounded; every accepted step lowers the
// residual, so it converges wherever the map is invertible. OpenCV's own undistortPoints is a
// fixed-point iteration with a fixed count and no convergence test; this one says when it
// failed:
//   not_converged          the residual |distort(x) - x_d| stayed above kUndistortTolerance
//   outside_model_domain   the iterate left |x| <= max_normalized_radius, or the map folds
//                          there (Jacobian determinant <= 0): no unique ray for that pixel.
// Error bound (asserted against the exact double-precision normalized point over random lenses
// with |k1| <= 0.25 out to radius 0.9, and over a whole 640x480 webcam image with k1 = -0.41):
// |x - x_exact| <= 1e-6 in normalized units (measured 4.7e-7), i.e. 0.001 px at fx = 1000 -- far below centroid noise.
//
// Doty's 7-25..7-32 intersect the ray with the calibration plane for an ideal pinhole of focal
// length f; point_on_plane does it for any intrinsics, after undistortion: p = rho/(n.d) d with
// d = (x, y, 1). Relative error below 1e-6 / cos(incidence); a ray within kMinRayPlaneCosine
// of parallel to the plane, or meeting it behind the camera, is refused.
//
// Cost (M4F): project_point about 30 flops and one division; pixel_to_normalized about
// 60 flops per Newton step, typically 3-4 steps; point_on_plane 10 flops and one division;
// pixel_to_plane_point measured at 570 instructions (-O3, geometry_m4_bench, a 640x480 lens
// with k1 = -0.41).
// No state, no allocation; every function may be called from any context.
#pragma once

#include <cstdint>

#include "firmware/core/range_plane.hpp"
#include "firmware/core/rigid_transform.hpp"
#include "shared/parameters.hpp"

namespace kincal::core {

inline constexpr int kUndistortMaxIterations = 12;
inline constexpr int kUndistortMaxHalvings = 5;
inline constexpr float kUndistortTolerance = 1.0e-6f;  // normalized units, max-norm
inline constexpr float kMinRayPlaneCosine = 1.0e-3f;

enum class [[nodiscard]] CameraStatus : std::uint8_t{
    ok,
    bad_intrinsics,        // fx or fy not positive and finite, or non-finite coefficients
    behind_camera,         // project_point: Z <= 0
    outside_model_domain,  // see above
    not_converged,         // see above
    ray_misses_plane,      // point_on_plane: ray (nearly) parallel to the plane or meets it behind
};

template <class S>
struct Distortion {
  S k1{}, k2{}, p1{}, p2{}, k3{};
};

struct CameraIntrinsics {
  float fx_px = 1.0f, fy_px = 1.0f, cx_px = 0.0f, cy_px = 0.0f;
  Distortion<float> distortion{};
  float max_normalized_radius = 2.0f;  // |(x, y)| up to which the distortion model is trusted
};

// The camera of an intrinsics parameter block (shared/parameters.hpp), as this model takes it.
CameraIntrinsics camera_from_block(const shared::CameraIntrinsics& block) noexcept;

// OpenCV's distortion of a normalized point: written once, for any scalar.
template <class S>
Vector2<S> distort_normalized(const Distortion<S>& k, const Vector2<S>& xy) noexcept {
  const S x = xy.x(), y = xy.y();
  const S r2 = x * x + y * y;
  const S radial = S(1) + r2 * (k.k1 + r2 * (k.k2 + r2 * k.k3));
  const S two_xy = S(2) * x * y;
  return Vector2<S>(x * radial + k.p1 * two_xy + k.p2 * (r2 + S(2) * x * x),
                    y * radial + k.p1 * (r2 + S(2) * y * y) + k.p2 * two_xy);
}

// d(x_d, y_d)/d(x, y) of distort_normalized: pixel_to_normalized's Newton steps and
// planar_pose.hpp's Gauss-Newton Jacobian.
template <class S>
Eigen::Matrix<S, 2, 2> distortion_jacobian(const Distortion<S>& k, const S& x, const S& y) noexcept {
  const S r2 = x * x + y * y;
  const S radial = S(1) + r2 * (k.k1 + r2 * (k.k2 + r2 * k.k3));
  const S dradial_dr2 = k.k1 + r2 * (S(2) * k.k2 + S(3) * r2 * k.k3);
  Eigen::Matrix<S, 2, 2> j;
  j(0, 0) = radial + S(2) * x * x * dradial_dr2 + S(2) * k.p1 * y + S(6) * k.p2 * x;
  j(0, 1) = S(2) * x * y * dradial_dr2 + S(2) * k.p1 * x + S(2) * k.p2 * y;
  j(1, 0) = j(0, 1);
  j(1, 1) = radial + S(2) * y * y * dradial_dr2 + S(6) * k.p1 * y + S(2) * k.p2 * x;
  return j;
}

// A pixel turned into a ray: normalized (x, y) (the ray is (x, y, 1)), and d(x, y)/d(u, v),
// which carries pixel noise to the ray (stereo.hpp's depth uncertainty uses it).
struct NormalizedPoint {
  Vector2<float> xy{};
  Eigen::Matrix<float, 2, 2> xy_per_px{};
};

CameraStatus project_point(const CameraIntrinsics& camera, const Vector3<float>& point_camera_m,
                           Vector2<float>& pixel) noexcept;

CameraStatus pixel_to_normalized(const CameraIntrinsics& camera, const Vector2<float>& pixel,
                                 NormalizedPoint& normalized) noexcept;

// The camera-frame point where the ray (x, y, 1) meets the plane.
CameraStatus point_on_plane(const CalibrationPlane& plane, const Vector2<float>& normalized_xy,
                            Vector3<float>& point_camera_m) noexcept;

// pixel_to_normalized, then point_on_plane: a fiducial centroid to its camera-frame point.
CameraStatus pixel_to_plane_point(const CameraIntrinsics& camera, const CalibrationPlane& plane,
                                  const Vector2<float>& pixel, Vector3<float>& point_camera_m) noexcept;

}  // namespace kincal::core

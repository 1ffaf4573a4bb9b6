#include "firmware/core/camera_model.hpp"

#include <cmath>

namespace kincal::core {

namespace {

bool intrinsics_ok(const CameraIntrinsics& c) {
  const Distortion<float>& k = c.distortion;
  return std::isfinite(c.fx_px) && std::isfinite(c.fy_px) && c.fx_px > 0.0f && c.fy_px > 0.0f &&
         std::isfinite(c.cx_px) && std::isfinite(c.cy_px) && std::isfinite(k.k1) && std::isfinite(k.k2) &&
         std::isfinite(k.p1) && std::isfinite(k.p2) && std::isfinite(k.k3) && c.max_normalized_radius > 0.0f;
}

}  // namespace

CameraIntrinsics camera_from_block(const shared::CameraIntrinsics& block) noexcept {
  CameraIntrinsics c;
  c.fx_px = block.fx_px;
  c.fy_px = block.fy_px;
  c.cx_px = block.cx_px;
  c.cy_px = block.cy_px;
  c.distortion = {block.k1, block.k2, block.p1, block.p2, block.k3};
  return c;
}

CameraStatus project_point(const CameraIntrinsics& camera, const Vector3<float>& point_camera_m,
                           Vector2<float>& pixel) noexcept {
  if (!intrinsics_ok(camera)) return CameraStatus::bad_intrinsics;
  if (!(point_camera_m.z() > 0.0f)) return CameraStatus::behind_camera;
  const Vector2<float> xy = point_camera_m.head<2>() / point_camera_m.z();
  if (!(xy.norm() <= camera.max_normalized_radius)) return CameraStatus::outside_model_domain;
  const Vector2<float> d = distort_normalized(camera.distortion, xy);
  pixel = Vector2<float>(camera.fx_px * d.x() + camera.cx_px, camera.fy_px * d.y() + camera.cy_px);
  return CameraStatus::ok;
}

CameraStatus pixel_to_normalized(const CameraIntrinsics& camera, const Vector2<float>& pixel,
                                 NormalizedPoint& normalized) noexcept {
  if (!intrinsics_ok(camera)) return CameraStatus::bad_intrinsics;
  // Scalars rather than Eigen vectors in the loop: at -Os that halves the stack frame.
  const float target_x = (pixel.x() - camera.cx_px) / camera.fx_px;
  const float target_y = (pixel.y() - camera.cy_px) / camera.fy_px;
  if (!std::isfinite(target_x) || !std::isfinite(target_y)) return CameraStatus::outside_model_domain;
  const float radius2_max = camera.max_normalized_radius * camera.max_normalized_radius;
  const Distortion<float>& k = camera.distortion;

  float x = target_x, y = target_y;
  Vector2<float> distorted = distort_normalized(k, Vector2<float>(x, y));
  float rx = distorted.x() - target_x, ry = distorted.y() - target_y;
  float residual2 = rx * rx + ry * ry;
  for (int iteration = 0; iteration < kUndistortMaxIterations; ++iteration) {
    if (std::fabs(rx) <= 0.25f * kUndistortTolerance && std::fabs(ry) <= 0.25f * kUndistortTolerance) break;
    const Eigen::Matrix2f j = distortion_jacobian(k, x, y);
    const float det = j(0, 0) * j(1, 1) - j(0, 1) * j(1, 0);
    if (!(det > 0.0f)) return CameraStatus::outside_model_domain;
    // Newton step -J^-1 r, then halve it until the residual drops.
    const float step_x = (j(0, 1) * ry - j(1, 1) * rx) / det;
    const float step_y = (j(1, 0) * rx - j(0, 0) * ry) / det;
    float fraction = 1.0f;
    bool accepted = false;
    for (int halving = 0; halving <= kUndistortMaxHalvings && !accepted; ++halving, fraction *= 0.5f) {
      const float trial_x = x + fraction * step_x, trial_y = y + fraction * step_y;
      if (!(trial_x * trial_x + trial_y * trial_y <= radius2_max)) continue;
      distorted = distort_normalized(k, Vector2<float>(trial_x, trial_y));
      const float trial_rx = distorted.x() - target_x, trial_ry = distorted.y() - target_y;
      const float trial_residual2 = trial_rx * trial_rx + trial_ry * trial_ry;
      if (trial_residual2 < residual2) {
        x = trial_x;
        y = trial_y;
        rx = trial_rx;
        ry = trial_ry;
        residual2 = trial_residual2;
        accepted = true;
      }
    }
    if (!accepted) break;  // no descent left: at the rounding floor, or stuck (checked below)
  }
  if (!(x * x + y * y <= radius2_max)) return CameraStatus::outside_model_domain;
  if (!(std::fabs(rx) <= kUndistortTolerance && std::fabs(ry) <= kUndistortTolerance)) {
    return CameraStatus::not_converged;
  }

  const Eigen::Matrix2f j = distortion_jacobian(k, x, y);
  const float det = j(0, 0) * j(1, 1) - j(0, 1) * j(1, 0);
  if (!(det > 0.0f)) return CameraStatus::outside_model_domain;
  // d(x, y)/d(u, v) = J^-1 diag(1/fx, 1/fy)
  normalized.xy = Vector2<float>(x, y);
  normalized.xy_per_px(0, 0) = j(1, 1) / (det * camera.fx_px);
  normalized.xy_per_px(1, 0) = -j(1, 0) / (det * camera.fx_px);
  normalized.xy_per_px(0, 1) = -j(0, 1) / (det * camera.fy_px);
  normalized.xy_per_px(1, 1) = j(0, 0) / (det * camera.fy_px);
  return CameraStatus::ok;
}

CameraStatus point_on_plane(const CalibrationPlane& plane, const Vector2<float>& normalized_xy,
                            Vector3<float>& point_camera_m) noexcept {
  const Vector3<float> ray(normalized_xy.x(), normalized_xy.y(), 1.0f);
  const float along_normal = plane.normal.dot(ray);
  if (!(along_normal > kMinRayPlaneCosine * ray.norm())) return CameraStatus::ray_misses_plane;
  point_camera_m = ray * (plane.distance_m / along_normal);
  return CameraStatus::ok;
}

CameraStatus pixel_to_plane_point(const CameraIntrinsics& camera, const CalibrationPlane& plane,
                                  const Vector2<float>& pixel, Vector3<float>& point_camera_m) noexcept {
  NormalizedPoint normalized;
  const CameraStatus status = pixel_to_normalized(camera, pixel, normalized);
  if (status != CameraStatus::ok) return status;
  return point_on_plane(plane, normalized.xy, point_camera_m);
}

}  // namespace kincal::core

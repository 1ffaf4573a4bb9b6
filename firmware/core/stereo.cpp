#include "firmware/core/stereo.hpp"

#include <cmath>

namespace kincal::core {

namespace {

bool positive_finite(float v) { return std::isfinite(v) && v > 0.0f; }

// The midpoint triangulation and its derivatives, for rays d_L from the left camera centre (the
// origin) and d_R from the right camera centre t: s = n.(t x d_R)/|n|^2 and u = n.(t x d_L)/|n|^2
// with n = d_L x d_R are the ray parameters of the closest points.
struct Midpoint {
  Vector3<float> d_left, d_right, t, n, t_cross_right, t_cross_left;
  float nn, s, u;

  // dz/d(perturbation) of the midpoint's z, for a change of d_L (left == true) or d_R.
  float depth_derivative(const Vector3<float>& delta, bool left) const {
    const Vector3<float> dn = left ? Vector3<float>(delta.cross(d_right)) : Vector3<float>(d_left.cross(delta));
    const float dnn = 2.0f * n.dot(dn);
    const Vector3<float> t_cross_delta = t.cross(delta);
    const float dns = dn.dot(t_cross_right) + (left ? 0.0f : n.dot(t_cross_delta));
    const float dnu = dn.dot(t_cross_left) + (left ? n.dot(t_cross_delta) : 0.0f);
    const float ds = (dns - s * dnn) / nn;
    const float du = (dnu - u * dnn) / nn;
    // z of (s d_L + t + u d_R) / 2
    return 0.5f * (ds * d_left.z() + du * d_right.z() + (left ? s : u) * delta.z());
  }
};

// First-order depth variance per unit pixel variance: the sum over the four pixel coordinates
// of (dz/dpixel)^2. Not inlined, so that its frame does not add to triangulate_pair's.
[[gnu::noinline]] float depth_variance_per_px2(const Midpoint& m, const NormalizedPoint& left,
                                               const NormalizedPoint& right, const Matrix3<float>& left_R_right) {
  float variance = 0.0f;
  for (int k = 0; k < 2; ++k) {
    const Vector3<float> delta_left(left.xy_per_px(0, k), left.xy_per_px(1, k), 0.0f);
    const float dz_left = m.depth_derivative(delta_left, true);
    const Vector3<float> delta_right =
        left_R_right * Vector3<float>(right.xy_per_px(0, k), right.xy_per_px(1, k), 0.0f);
    const float dz_right = m.depth_derivative(delta_right, false);
    variance += dz_left * dz_left + dz_right * dz_right;
  }
  return variance;
}

}  // namespace

StereoStatus triangulate_parallel(const ParallelStereoRig& rig, const Vector2<float>& left_px,
                                  const Vector2<float>& right_px, float pixel_sigma_px, StereoPoint& point) noexcept {
  if (!positive_finite(rig.focal_x_px) || !positive_finite(rig.focal_y_px) || !positive_finite(rig.baseline_m) ||
      !(pixel_sigma_px >= 0.0f) || !std::isfinite(pixel_sigma_px)) {
    return StereoStatus::bad_rig;
  }
  const Vector2<float> left = left_px - rig.principal_left_px;
  const Vector2<float> right = right_px - rig.principal_right_px;
  if (!left.allFinite() || !right.allFinite()) return StereoStatus::bad_rig;
  if (!(std::fabs(left.y() - right.y()) <= rig.max_row_difference_px)) return StereoStatus::rows_mismatch;
  const float disparity_px = left.x() - right.x();
  if (disparity_px < -rig.min_disparity_px) return StereoStatus::behind_camera;
  if (!(disparity_px > rig.min_disparity_px)) return StereoStatus::zero_disparity;

  const float depth_m = rig.focal_x_px * rig.baseline_m / disparity_px;
  StereoPoint result;
  result.point_left_m = Vector3<float>(left.x() * depth_m / rig.focal_x_px,
                                       0.5f * (left.y() + right.y()) * depth_m / rig.focal_y_px, depth_m);
  result.depth_sigma_m = depth_m * depth_m / (rig.focal_x_px * rig.baseline_m) * 1.41421356f * pixel_sigma_px;
  result.ray_gap_px = std::fabs(left.y() - right.y());
  point = result;
  return StereoStatus::ok;
}

StereoStatus triangulate_pair(const StereoPair& pair, const Vector2<float>& left_px, const Vector2<float>& right_px,
                              float pixel_sigma_px, StereoPoint& point) noexcept {
  if (!(pixel_sigma_px >= 0.0f) || !std::isfinite(pixel_sigma_px) || !pair.left_T_right.translation.allFinite() ||
      !pair.left_T_right.rotation.allFinite() || !positive_finite(pair.left_T_right.translation.norm())) {
    return StereoStatus::bad_rig;
  }
  NormalizedPoint left, right;
  const CameraStatus left_status = pixel_to_normalized(pair.left, left_px, left);
  const CameraStatus right_status = pixel_to_normalized(pair.right, right_px, right);
  if (left_status == CameraStatus::bad_intrinsics || right_status == CameraStatus::bad_intrinsics) {
    return StereoStatus::bad_rig;
  }
  if (left_status != CameraStatus::ok || right_status != CameraStatus::ok) return StereoStatus::undistortion_failed;

  Midpoint m;
  m.d_left = Vector3<float>(left.xy.x(), left.xy.y(), 1.0f);
  m.d_right = pair.left_T_right.rotation * Vector3<float>(right.xy.x(), right.xy.y(), 1.0f);
  m.t = pair.left_T_right.translation;
  m.n = m.d_left.cross(m.d_right);
  m.nn = m.n.squaredNorm();
  const float sin_limit = pair.min_ray_angle_rad;
  if (!(m.nn > sin_limit * sin_limit * m.d_left.squaredNorm() * m.d_right.squaredNorm())) {
    return StereoStatus::zero_disparity;
  }
  m.t_cross_right = m.t.cross(m.d_right);
  m.t_cross_left = m.t.cross(m.d_left);
  m.s = m.n.dot(m.t_cross_right) / m.nn;
  m.u = m.n.dot(m.t_cross_left) / m.nn;
  if (!(m.s > 0.0f) || !(m.u > 0.0f)) return StereoStatus::behind_camera;

  const Vector3<float> on_left = m.s * m.d_left;
  const Vector3<float> on_right = m.t + m.u * m.d_right;
  const float gap_px = (on_left - on_right).norm() / on_left.norm() * pair.left.fx_px;
  if (!(gap_px <= pair.max_ray_gap_px)) return StereoStatus::rays_miss;

  const float variance = depth_variance_per_px2(m, left, right, pair.left_T_right.rotation);

  point.point_left_m = 0.5f * (on_left + on_right);
  point.depth_sigma_m = std::sqrt(variance) * pixel_sigma_px;
  point.ray_gap_px = gap_px;
  return StereoStatus::ok;
}

}  // namespace kincal::core

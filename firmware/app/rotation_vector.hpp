// Rotation vectors (axis * angle, radians) and rotation matrices: the form in which the protocol
// carries orientations (the measurement report's pose, the correction block's tool offset).
//
// rotation_from_vector(r)   exp: the rotation by |r| about r / |r| (Rodrigues' formula),
//                           templated on the scalar: float in the firmware, double on the host,
//                           which must read the correction block exactly as the platform does.
//                           Below |r| = 1e-4 rad the series to second order (error < 1e-13).
// rotation_vector(R)        log, float: r with exp(r) = R and |r| in [0, pi]. R must be a proper
//                           rotation (det +1, orthonormal to float rounding; pose_from_points
//                           gives one). Quaternion by Shepperd's method (square roots only), then
//                           the angle 2 atan2(|v|, w) from a rational first guess (error below
//                           5e-3 rad) and two Newton steps on sin/cos (core::sin_cos; each step
//                           cubes the error), so no library atan2 enters the firmware (the stack
//                           check cannot bound libm). Error within 2e-6 rad of the exact vector
//                           for angles up to pi - 1e-3 (tests/firmware/app/rotation_vector_test.cpp);
//                           at pi exactly the sign of the axis is arbitrary, as for any log.
// Cost: exp one sin_cos and ~30 flops; log ~3 sin_cos, one square root per quaternion and
// ~60 flops. Pure, no state, cannot fail.
#pragma once

#include "firmware/core/rigid_transform.hpp"
#include "firmware/core/sin_cos.hpp"

namespace kincal::app {

template <class S>
core::Matrix3<S> rotation_from_vector(const core::Vector3<S>& r) noexcept {
  using std::sqrt;
  const S angle2 = r.squaredNorm();
  S a, b;  // R = I + a [r]x + b [r]x^2
  if (angle2 < S(1e-8)) {
    a = S(1) - angle2 / S(6);
    b = S(0.5) - angle2 / S(24);
  } else {
    const S angle = sqrt(angle2);
    const core::SinCos<S> sc = core::sin_cos(angle);
    a = sc.sin / angle;
    b = (S(1) - sc.cos) / angle2;
  }
  // Entry by entry: [r]x^2 = r r^T - |r|^2 I. (Eigen's expressions of the same do not unroll at
  // -Os and cost the stack a few hundred bytes.)
  const S x = r.x(), y = r.y(), z = r.z();
  core::Matrix3<S> rotation;
  rotation << S(1) + b * (x * x - angle2), b * x * y - a * z, b * x * z + a * y,  //
      b * x * y + a * z, S(1) + b * (y * y - angle2), b * y * z - a * x,          //
      b * x * z - a * y, b * y * z + a * x, S(1) + b * (z * z - angle2);
  return rotation;
}

core::Vector3<float> rotation_vector(const core::Matrix3<float>& rotation) noexcept;

}  // namespace kincal::app

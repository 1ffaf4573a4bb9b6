// Sine and cosine of one angle, computed together: the trigonometry of the geometry modules.
//
// Why our own: newlib's sinf/cosf on the Cortex-M4 go through double precision, which the M4F
// computes in software (hundreds of instructions per call); the correction runs a sine and a
// cosine per revolute joint at the control rate. sin_cos(float) below is float only, has no
// table and no library call. Its multiply-adds are fused explicitly (mul_add.hpp), so it gives
// the same bits natively and on the M4 (tests/firmware/core/geometry_digest.cpp).
//
// sin_cos(float angle_rad), |angle_rad| <= kSinCosMaxArgumentRad:
//   error   |sin - sin_exact| and |cos - cos_exact| <= kSinCosMaxAbsError (= 1.2e-7, about one
//           ULP of 1.0), asserted against double precision over random angles by
//           tests/firmware/core/sin_cos_test.cpp; sin^2 + cos^2 = 1 within 3e-7.
//   method  Cody-Waite reduction by pi/2 (three-part constant, exact products for |k| < 2^15),
//           then Cephes' minimax polynomials on [-pi/4, pi/4] (degree 7 sine, degree 8 cosine).
//   outside |angle_rad| > kSinCosMaxArgumentRad, or NaN: returns NaN for both (no undefined
//           behaviour, and the NaN propagates to whatever the caller computes with it).
//   cost    about 40 instructions on the M4F, constant time, no branches on data beyond the
//           quadrant selection; stack: a few words.
//
// sin_cos(const S&) for any other scalar (double on the host, ceres::Jet for automatic
// differentiation) calls sin and cos found by argument-dependent lookup or in std, so geometry
// templated on the scalar calls sin_cos() once and gets the right one for each type.
#pragma once

#include <cmath>

#include "firmware/core/mul_add.hpp"

namespace kincal::core {

template <class S>
struct SinCos {
  S sin;
  S cos;
};

inline constexpr float kSinCosMaxArgumentRad = 8192.0f;
inline constexpr float kSinCosMaxAbsError = 1.2e-7f;

SinCos<float> sin_cos(float angle_rad) noexcept;

template <class S>
SinCos<S> sin_cos(const S& angle_rad) noexcept {
  using std::cos;
  using std::sin;
  return {sin(angle_rad), cos(angle_rad)};
}

// sin and cos of a small angle, |angle_rad| <= kSmallAngleMaxRad, by the Taylor series to the
// fifth (sine) and sixth (cosine) power: truncation below 1e-9, so the error is float rounding
// (within kSinCosMaxAbsError). About ten instructions: for the small joint increments of the
// online correction (correction.hpp), combined with angle_sum.
inline constexpr float kSmallAngleMaxRad = 0.0625f;

template <class S>
SinCos<S> small_angle_sin_cos(const S& angle_rad) noexcept {
  const S x2 = angle_rad * angle_rad;
  return {angle_rad - angle_rad * x2 * (S(1) / S(6) - x2 / S(120)),
          S(1) - x2 * (S(0.5) - x2 * (S(1) / S(24) - x2 / S(720)))};
}

// sin and cos of (a + b) from those of a and b: two products and a sum each, exact up to a
// few rounding errors. Used to add a joint position to a constant offset without a second
// sin_cos call.
template <class S>
SinCos<S> angle_sum(const SinCos<S>& a, const SinCos<S>& b) noexcept {
  return {mul_add(a.sin, b.cos, a.cos * b.sin), mul_add(a.cos, b.cos, -(a.sin * b.sin))};
}

}  // namespace kincal::core

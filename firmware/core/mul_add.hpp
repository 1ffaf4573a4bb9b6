// a * b + c for the geometry's hot loops: fused where that gives the same bits on every target.
//
// The project builds with -ffp-contract=off (toolchain/KincalTargets.cmake): left to itself GCC
// fuses a * b + c into the M4F's VFMA but cannot on x86-64's baseline, and the float geometry
// then differs between the targets by rounding. mul_add() asks for the fusion explicitly where it
// pays:
//   float          the correctly rounded fused multiply-add, so the same bits natively and on
//                  the M4 (m4.geometry_digest_matches_native): one VFMA where the FPU has one
//                  (__FP_FAST_FMAF: the M4F); elsewhere computed exactly in double without
//                  touching the rounding mode (fused_multiply_add_exact below), because glibc's
//                  fmaf without an FMA unit switches rounding modes per call: a native 6-joint
//                  correction took 8.5 us with it against 2.2 us unfused.
//   other scalars  (double and ceres::Jet on the host) the plain a * b + c, two roundings, as
//                  before: host results do not change.
// Cannot fail; no state. Cost: one instruction on the M4F; natively about ten double operations.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>

namespace kincal::core {

// fmaf(a, b, c) with double arithmetic only (Boldo & Melquiond's rounding to odd): a * b is exact
// in double (24 + 24 bits); the sum is rounded to nearest and its exact error found (TwoSum);
// where the error is not zero the sum is moved to the neighbouring double with an odd last bit,
// which rounds to float exactly as the exact sum does. Infinities and NaNs pass through.
inline float fused_multiply_add_exact(float a, float b, float c) noexcept {
  const double product = static_cast<double>(a) * static_cast<double>(b);
  const double addend = static_cast<double>(c);
  const double sum = product + addend;
  const double addend_part = sum - product;
  const double error = (product - (sum - addend_part)) + (addend - addend_part);
  auto bits = std::bit_cast<std::uint64_t>(sum);
  constexpr std::uint64_t kExponent = 0x7FF0000000000000u;
  if ((bits & kExponent) != kExponent && error != 0.0 && (bits & 1u) == 0) {
    const bool away_from_zero = (error > 0.0) == (sum > 0.0);
    bits = away_from_zero ? bits + 1u : bits - 1u;
  }
  return static_cast<float>(std::bit_cast<double>(bits));
}

template <class S>
S mul_add(const S& a, const S& b, const S& c) noexcept {
  return a * b + c;
}

inline float mul_add(float a, float b, float c) noexcept {
#if defined(__FP_FAST_FMAF)
  return std::fma(a, b, c);
#else
  return fused_multiply_add_exact(a, b, c);
#endif
}

}  // namespace kincal::core

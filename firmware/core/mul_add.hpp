// a * b + c for the geometry's hot loops: fused where that gives the same bits on every target.
//
// The project builds with -ffp-contract=off (toolchain/KincalTargets.cmake): left to itself GCC
// fuses a * b + c into the M4F's VFMA but cannot on x86-64's baseline, and the float geometry
// then differs between the targets by rounding. mul_add() asks for the fusion explicitly where it
// pays:
//   float          std::fma: one rounding, correctly rounded on every target (one VFMA on the
//                  M4F; glibc's fmaf natively, which uses the CPU's FMA where it has one), so
//                  the same bits natively and on the M4 (m4.geometry_digest_matches_native).
//   other scalars  (double and ceres::Jet on the host) the plain a * b + c, two roundings, as
//                  before: host results do not change.
// Cannot fail; no state. Cost: one instruction on the M4F; natively a call into libm.
#pragma once

#include <cmath>

namespace kincal::core {

template <class S>
S mul_add(const S& a, const S& b, const S& c) noexcept {
  return a * b + c;
}

inline float mul_add(float a, float b, float c) noexcept { return std::fma(a, b, c); }

}  // namespace kincal::core

#include "firmware/core/sin_cos.hpp"

#include <cstdint>
#include <limits>

namespace kincal::core {

namespace {

// pi/2 = kPio2Hi + kPio2Mid + kPio2Lo: the first two have 8 and 11 significant bits, so k times
// each is exact for |k| < 2^13 (|angle| <= 8192 rad gives |k| <= 5216).
constexpr float kPio2Hi = 1.5703125f;
constexpr float kPio2Mid = 4.837512969970703125e-4f;
constexpr float kPio2Lo = 7.54978995489188216e-8f;
constexpr float kTwoOverPi = 0.636619772367581343f;

// Cephes sinf/cosf minimax coefficients for |r| <= pi/4.
// Horner's scheme in fused multiply-adds (mul_add.hpp): the same bits on both targets.
float sin_kernel(float r) {
  const float z = r * r;
  const float p = mul_add(mul_add(-1.9515295891e-4f, z, 8.3321608736e-3f), z, -1.6666654611e-1f);
  return mul_add(p * z, r, r);
}

float cos_kernel(float r) {
  const float z = r * r;
  const float p = mul_add(mul_add(2.443315711809948e-5f, z, -1.388731625493765e-3f), z, 4.166664568298827e-2f);
  return mul_add(p * z, z, -0.5f * z) + 1.0f;
}

}  // namespace

SinCos<float> sin_cos(float angle_rad) noexcept {
  if (!(std::fabs(angle_rad) <= kSinCosMaxArgumentRad)) {
    constexpr float nan = std::numeric_limits<float>::quiet_NaN();
    return {nan, nan};
  }
  const float scaled = angle_rad * kTwoOverPi;
  const auto k = static_cast<std::int32_t>(scaled + (scaled >= 0.0f ? 0.5f : -0.5f));
  const auto kf = static_cast<float>(k);
  // The first two products are exact, so fusing them changes nothing; the third gains a rounding.
  const float r = mul_add(-kf, kPio2Lo, mul_add(-kf, kPio2Mid, mul_add(-kf, kPio2Hi, angle_rad)));
  const float s = sin_kernel(r);
  const float c = cos_kernel(r);
  switch (static_cast<std::uint32_t>(k) & 3u) {
    case 0u:
      return {s, c};
    case 1u:
      return {c, -s};
    case 2u:
      return {-s, -c};
    default:
      return {-c, s};
  }
}

}  // namespace kincal::core

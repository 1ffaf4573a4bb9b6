// mul_add's float fusion without an FMA unit (fused_multiply_add_exact) against the correctly
// rounded std::fma (the M4F's VFMA, glibc's fmaf natively): bit for bit, on random operands of
// every exponent and sign, on cancellations where the product's low bits decide the rounding,
// and on the specials.
#include <doctest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>

#include "firmware/core/mul_add.hpp"
#include "tests/firmware/core/splitmix64.hpp"

using kincal::core::fused_multiply_add_exact;

namespace {

bool same_bits(float a, float b) {
  if (std::isnan(a) && std::isnan(b)) return true;
  return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}

float random_float(kincal::test::Splitmix64& r, int max_exponent) {
  const auto mantissa = static_cast<std::uint32_t>(r.next() & 0x7FFFFFu);
  const auto exponent = static_cast<std::uint32_t>(127 - max_exponent + r.below(2 * max_exponent));
  const auto sign = static_cast<std::uint32_t>(r.next() & 1u) << 31;
  return std::bit_cast<float>(sign | exponent << 23 | mantissa);
}

}  // namespace

TEST_CASE("fused_multiply_add_exact equals the correctly rounded fma, bit for bit") {
  kincal::test::Splitmix64 r(0xF4A);
  int mismatches = 0;
  for (int i = 0; i < 20000; ++i) {
    const float a = random_float(r, 20), b = random_float(r, 20);
    // Half the addends near -a*b: cancellation, where double rounding would show.
    const float c = (i % 2) ? random_float(r, 40) : -(a * b) * (1.0f + static_cast<float>(r.below(64) - 32) * 0x1p-23f);
    if (!same_bits(fused_multiply_add_exact(a, b, c), std::fma(a, b, c))) {
      ++mismatches;
      INFO("a ", a, " b ", b, " c ", c);
      CHECK(same_bits(fused_multiply_add_exact(a, b, c), std::fma(a, b, c)));
    }
  }
  CHECK(mismatches == 0);
  // Double rounding traps: c plus a product just off half an ulp of c (a b = ulp/2 (1 - 2^-46)),
  // which rounding the exact sum to double would put exactly on the midpoint.
  for (int i = 0; i < 2000; ++i) {
    const float c = random_float(r, 30);
    const float half_ulp = std::ldexp(1.0f, std::ilogb(c) - 24);
    const float a = (i % 2 ? 1.0f : -1.0f) * (1.0f + 0x1p-23f), b = (1.0f - 0x1p-23f) * half_ulp;
    INFO("a ", a, " b ", b, " c ", c);
    CHECK(same_bits(fused_multiply_add_exact(a, b, c), std::fma(a, b, c)));
  }
  const float inf = std::numeric_limits<float>::infinity(), big = std::numeric_limits<float>::max();
  const float tiny = std::numeric_limits<float>::denorm_min();
  for (const float a : {0.0f, -0.0f, 1.0f, -3.5f, big, tiny, inf, -inf})
    for (const float b : {0.0f, -0.0f, 2.0f, big, tiny, -inf})
      for (const float c : {0.0f, -0.0f, 1.0f, -big, tiny, inf}) {
        INFO("a ", a, " b ", b, " c ", c);
        CHECK(same_bits(fused_multiply_add_exact(a, b, c), std::fma(a, b, c)));
      }
}

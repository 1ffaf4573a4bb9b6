#include "firmware/core/auto_threshold.hpp"

namespace kincal::core {

ThresholdStatus GreyHistogram::add_row(std::span<const std::uint8_t> row, std::uint32_t step) noexcept {
  if (step == 0) return ThresholdStatus::kBadStep;
  const std::size_t samples = (row.size() + step - 1) / step;
  if (samples > kMaxHistogramSamples - total) return ThresholdStatus::kTooManySamples;
  for (std::size_t x = 0; x < row.size(); x += step) ++counts[row[x]];
  total += static_cast<std::uint32_t>(samples);
  return ThresholdStatus::kOk;
}

namespace {

struct U128 {
  std::uint64_t hi, lo;
};

U128 mul64(std::uint64_t a, std::uint64_t b) {
  const std::uint64_t a0 = a & 0xFFFFFFFFu, a1 = a >> 32, b0 = b & 0xFFFFFFFFu, b1 = b >> 32;
  const std::uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
  const std::uint64_t middle = (p00 >> 32) + (p01 & 0xFFFFFFFFu) + (p10 & 0xFFFFFFFFu);
  return {p11 + (p01 >> 32) + (p10 >> 32) + (middle >> 32), (middle << 32) | (p00 & 0xFFFFFFFFu)};
}

// a * m for a product known to fit 128 bits.
U128 mul128(U128 a, std::uint64_t m) {
  U128 r = mul64(a.lo, m);
  r.hi += a.hi * m;
  return r;
}

bool greater(U128 a, U128 b) { return a.hi != b.hi ? a.hi > b.hi : a.lo > b.lo; }

int bit_length(std::uint64_t v) {
  int n = 0;
  while (v != 0 && n < 64) {
    v >>= 1;
    ++n;
  }
  return n;
}

}  // namespace

ThresholdStatus otsu_threshold(const GreyHistogram& histogram, std::uint8_t& threshold) noexcept {
  std::uint64_t n = 0, sum = 0;
  for (std::uint32_t i = 0; i < 256; ++i) {
    n += histogram.counts[i];
    sum += std::uint64_t{histogram.counts[i]} * i;
  }
  if (n == 0) return ThresholdStatus::kEmpty;
  // Between-class variance times n^2: d^2 / (n0 n1) with d = sum n0 - n s0 = n0 n1 (mu1 - mu0).
  // Candidates compare exactly as d_a^2 (n0 n1)_b against d_b^2 (n0 n1)_a in 128 bits while
  // d < 2^44 and n0 n1 < 2^36 (n <= 2^19 samples, e.g. a VGA frame); larger histograms drop
  // the same low bits from every candidate (relative 2^-44).
  const int d_shift = bit_length((n / 2) * (n / 2 + 1) * 255) > 44 ? bit_length((n / 2) * (n / 2 + 1) * 255) - 44 : 0;
  const int p_shift = bit_length((n / 2) * (n / 2 + 1)) > 36 ? bit_length((n / 2) * (n / 2 + 1)) - 36 : 0;
  std::uint64_t n0 = 0, s0 = 0, best_d = 0, best_p = 1;
  bool found = false;
  for (std::uint32_t t = 0; t < 255; ++t) {
    n0 += histogram.counts[t];
    s0 += std::uint64_t{histogram.counts[t]} * t;
    const std::uint64_t n1 = n - n0;
    if (n0 == 0 || n1 == 0) continue;
    const std::uint64_t d = (sum * n0 - n * s0) >> d_shift;  // >= 0: the upper class has the larger mean
    const std::uint64_t p = (n0 * n1) >> p_shift;
    if (!found || greater(mul128(mul64(d, d), best_p), mul128(mul64(best_d, best_d), p))) {
      best_d = d;
      best_p = p == 0 ? 1 : p;
      threshold = static_cast<std::uint8_t>(t);
      found = true;
    }
  }
  return found ? ThresholdStatus::kOk : ThresholdStatus::kUniform;
}

}  // namespace kincal::core

#include "firmware/core/fixed_point.hpp"

namespace kincal::core {

std::uint64_t isqrt_round(std::uint64_t n) noexcept {
  // Digit-by-digit square root, two bits of n per step: 32 steps, no division, no float.
  std::uint64_t root = 0;
  std::uint64_t rest = n;
  std::uint64_t bit = std::uint64_t{1} << 62;
  while (bit > rest) bit >>= 2;
  while (bit != 0) {
    if (rest >= root + bit) {
      rest -= root + bit;
      root = (root >> 1) + bit;
    } else {
      root >>= 1;
    }
    bit >>= 2;
  }
  // root = floor(sqrt(n)) and rest = n - root^2. Round up when n > root^2 + root, i.e. when
  // sqrt(n) > root + 1/2 (n is an integer, so a tie cannot occur).
  return rest > root ? root + 1 : root;
}

}  // namespace kincal::core

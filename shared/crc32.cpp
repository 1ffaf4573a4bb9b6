#include "shared/crc32.hpp"

#include <array>

namespace kincal::shared {

namespace {

constexpr std::array<std::uint32_t, 16> make_nibble_table() {
  std::array<std::uint32_t, 16> table{};
  for (std::uint32_t n = 0; n < 16; ++n) {
    std::uint32_t c = n;
    for (int k = 0; k < 4; ++k) c = (c & 1u) ? (c >> 1) ^ 0xEDB88320u : c >> 1;
    table[n] = c;
  }
  return table;
}
constexpr std::array<std::uint32_t, 16> kNibbleTable = make_nibble_table();

}  // namespace

std::uint32_t crc32_update(std::uint32_t state, std::span<const std::uint8_t> bytes) {
  for (const std::uint8_t b : bytes) {
    state ^= b;
    state = (state >> 4) ^ kNibbleTable[state & 0xFu];
    state = (state >> 4) ^ kNibbleTable[state & 0xFu];
  }
  return state;
}

}  // namespace kincal::shared

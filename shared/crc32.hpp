// CRC-32 as in IEEE 802.3, zlib and Python's zlib.crc32 (reflected polynomial 0xEDB88320,
// initial value and final XOR 0xFFFFFFFF; check value of "123456789" is 0xCBF43926).
//
// Why this CRC: any host tool computes it with a standard library call, and it detects every
// burst error up to 32 bits in the parameter blocks and storage slots it guards.
// Cost: a 16-entry nibble table (64 bytes of flash), two lookups per byte; no heap.
// Thread/ISR safety: pure and reentrant. Failure modes: none.
// Incremental use: crc = crc32_update(crc32_update(kCrc32Init, a), b); final = crc32_finish(crc).
#pragma once

#include <cstdint>
#include <span>

namespace kincal::shared {

inline constexpr std::uint32_t kCrc32Init = 0xFFFFFFFFu;

std::uint32_t crc32_update(std::uint32_t state, std::span<const std::uint8_t> bytes);
constexpr std::uint32_t crc32_finish(std::uint32_t state) { return state ^ 0xFFFFFFFFu; }
inline std::uint32_t crc32(std::span<const std::uint8_t> bytes) {
  return crc32_finish(crc32_update(kCrc32Init, bytes));
}
// The CRC of text: the bytes of a std::string or std::string_view as they are.
inline std::uint32_t crc32_text(std::span<const char> text) {
  return crc32(std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

}  // namespace kincal::shared

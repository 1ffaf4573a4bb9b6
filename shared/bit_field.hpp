// Bit fields in a byte buffer, in the order DBC files call Intel (little-endian, `@1+`): bit i
// of the buffer is bit (i % 8) of byte i / 8, and a field's start bit is its least significant
// bit. Every protocol layout in shared/protocol.hpp is written in these terms, so the DBC file
// generated from the catalogue describes exactly the bits the codecs write.
//
// Cost: O(width) byte operations per field, no heap, no tables. Thread/ISR safety: pure
// functions over caller-owned buffers; BitWriter/BitReader are plain values (one per thread).
// Failure modes: a field reaching past the buffer is never written or read out of bounds:
// put_bits/get_bits touch only the bits inside the buffer (the rest reads as 0), and
// BitWriter/BitReader latch `overflow()` so a codec reports the short buffer as a status.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace kincal::shared {

// Writes the low `width` (1..64) bits of `value` at `start_bit`.
constexpr void put_bits(std::span<std::uint8_t> bytes, std::size_t start_bit, unsigned width, std::uint64_t value) {
  for (unsigned i = 0; i < width && i < 64; ++i) {
    const std::size_t bit = start_bit + i;
    const std::size_t byte = bit / 8;
    if (byte >= bytes.size()) return;
    const auto mask = static_cast<std::uint8_t>(1u << (bit % 8));
    if ((value >> i) & 1u)
      bytes[byte] = static_cast<std::uint8_t>(bytes[byte] | mask);
    else
      bytes[byte] = static_cast<std::uint8_t>(bytes[byte] & ~mask);
  }
}

// Reads `width` (1..64) bits at `start_bit` as an unsigned value.
constexpr std::uint64_t get_bits(std::span<const std::uint8_t> bytes, std::size_t start_bit, unsigned width) {
  std::uint64_t value = 0;
  for (unsigned i = 0; i < width && i < 64; ++i) {
    const std::size_t bit = start_bit + i;
    const std::size_t byte = bit / 8;
    if (byte >= bytes.size()) break;
    if ((static_cast<unsigned>(bytes[byte]) >> (bit % 8)) & 1u) value |= std::uint64_t{1} << i;
  }
  return value;
}

// Two's complement `width`-bit value to int64_t.
constexpr std::int64_t sign_extend(std::uint64_t value, unsigned width) {
  if (width == 0 || width >= 64) return static_cast<std::int64_t>(value);
  const std::uint64_t sign = std::uint64_t{1} << (width - 1);
  const std::uint64_t masked = value & ((sign << 1) - 1);
  return static_cast<std::int64_t>(masked ^ sign) - static_cast<std::int64_t>(sign);
}

// The raw range of a field: [min_raw(w, s), max_raw(w, s)].
constexpr std::int64_t min_raw(unsigned width, bool is_signed) {
  return is_signed ? -(std::int64_t{1} << (width - 1)) : 0;
}
constexpr std::int64_t max_raw(unsigned width, bool is_signed) {
  return is_signed ? (std::int64_t{1} << (width - 1)) - 1 : static_cast<std::int64_t>((std::uint64_t{1} << width) - 1);
}

// Sequential writer for variable-length messages; bits past the buffer set overflow().
class BitWriter {
 public:
  constexpr explicit BitWriter(std::span<std::uint8_t> bytes) : bytes_(bytes) {
    for (auto& b : bytes_) b = 0;
  }
  constexpr void put(unsigned width, std::uint64_t value) {
    if (position_ + width > bytes_.size() * 8) overflow_ = true;
    put_bits(bytes_, position_, width, value);
    position_ += width;
  }
  constexpr void put_signed(unsigned width, std::int64_t value) { put(width, static_cast<std::uint64_t>(value)); }
  constexpr std::size_t bit_position() const { return position_; }
  // Whole bytes written so far (the last one zero-padded).
  constexpr std::size_t bytes_used() const { return (position_ + 7) / 8; }
  constexpr bool overflow() const { return overflow_; }

 private:
  std::span<std::uint8_t> bytes_;
  std::size_t position_ = 0;
  bool overflow_ = false;
};

// Sequential reader; reading past the buffer yields zeros and sets overrun().
class BitReader {
 public:
  constexpr explicit BitReader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  constexpr std::uint64_t get(unsigned width) {
    if (position_ + width > bytes_.size() * 8) overrun_ = true;
    const std::uint64_t v = get_bits(bytes_, position_, width);
    position_ += width;
    return v;
  }
  constexpr std::int64_t get_signed(unsigned width) { return sign_extend(get(width), width); }
  constexpr std::size_t bit_position() const { return position_; }
  constexpr std::size_t bits_left() const { return position_ >= bytes_.size() * 8 ? 0 : bytes_.size() * 8 - position_; }
  constexpr bool overrun() const { return overrun_; }

 private:
  std::span<const std::uint8_t> bytes_;
  std::size_t position_ = 0;
  bool overrun_ = false;
};

}  // namespace kincal::shared

// One CAN or CAN FD frame, as the firmware and the host tools exchange it.
//
// What: the frame value type every layer agrees on (drivers, ISO-TP, protocol codecs, the host's
// SocketCAN and loopback buses, candump logs), plus the CAN FD length <-> DLC rules.
// Why here: shared/ is the one place both halves compile; a frame is the unit of the protocol.
// Cost: 72 bytes of storage per frame, no heap; every function is O(1) or O(length).
// Thread/ISR safety: plain value type; the functions are pure and reentrant.
// Failure modes: none at run time. A frame whose `length` is not a valid length for its format
// (classic: 0..8; FD: 0..8, 12, 16, 20, 24, 32, 48, 64) is rejected by every decoder with a
// status (is_valid_length() says which lengths are valid), never read past `data`.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace kincal::shared {

struct CanFrame {
  static constexpr std::size_t kMaxClassicBytes = 8;
  static constexpr std::size_t kMaxFdBytes = 64;
  static constexpr std::uint32_t kMaxStandardId = 0x7FFu;
  static constexpr std::uint32_t kMaxExtendedId = 0x1FFFFFFFu;

  std::uint32_t id = 0;     // 11-bit standard identifier unless `extended`
  bool extended = false;    // 29-bit identifier (the protocol itself uses only 11-bit ones)
  bool fd = false;          // CAN FD frame (FDF bit); otherwise classic CAN 2.0
  bool brs = false;         // CAN FD bit-rate switch: data phase at the data bit rate
  std::uint8_t length = 0;  // payload bytes in `data`
  std::array<std::uint8_t, kMaxFdBytes> data{};
};

// The payload lengths a CAN FD frame can carry, by DLC 0..15.
inline constexpr std::array<std::uint8_t, 16> kFdLengthByDlc{0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64};

// Whether `length` bytes is a payload a frame of that format can carry.
constexpr bool is_valid_length(bool fd, std::size_t length) {
  if (!fd) return length <= CanFrame::kMaxClassicBytes;
  for (const std::uint8_t l : kFdLengthByDlc)
    if (l == length) return true;
  return false;
}

// The smallest CAN FD payload length >= `bytes` (64 for anything larger).
constexpr std::uint8_t fd_length_at_least(std::size_t bytes) {
  for (const std::uint8_t l : kFdLengthByDlc)
    if (l >= bytes) return l;
  return 64;
}

// DLC of a valid payload length (classic: the length itself).
constexpr std::uint8_t dlc_of_length(std::size_t length) {
  for (std::uint8_t dlc = 0; dlc < kFdLengthByDlc.size(); ++dlc)
    if (kFdLengthByDlc[dlc] >= length) return dlc;
  return 15;
}

}  // namespace kincal::shared

// Parameter blocks in non-volatile storage that survive a power cut at any moment of a write.
//
// Scheme: each block has two slots (A and B) of StoragePort::kSlotBytes. A slot holds
//   magic u32 "KCP1" | sequence u32 | block u8 | 0 u8 | format version u16 | length u32 |
//   crc32 u32 (over the 16 bytes before it and the payload) | payload
// Loading reads both slots and takes the valid one with the newer sequence number (serial
// arithmetic, so wrap-around is harmless). Saving writes the slot that does NOT hold the newest
// valid copy: erase, payload, then the header (written last), then reads it back and checks the
// CRC. A cut during any of these leaves that slot invalid (its CRC cannot match) and the other
// slot untouched, so the next load returns the previous copy; a completed save is returned from
// then on. tests/firmware/app/parameter_store_test.cpp cuts the power at every byte of a save.
//
// Memory: a 20-byte header and a 64-byte read chunk on the stack; payloads are the caller's.
// Cost: a load reads two headers and at most both payloads (CRC at two table lookups per byte);
// a save erases one slot and writes and reads back header + payload.
// Thread/ISR safety: one caller at a time (the main loop).
// Failure modes: kMissing (no valid copy), kTooLarge (payload over the slot or the caller's
// buffer), kStorageFailed (the port failed, or the read-back did not verify).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "firmware/app/ports.hpp"
#include "shared/crc32.hpp"
#include "shared/protocol.hpp"

namespace kincal::app {

enum class [[nodiscard]] StoreStatus : std::uint8_t{kOk, kMissing, kTooLarge, kStorageFailed};

namespace slot_format {

inline constexpr std::uint32_t kMagic = 0x3150434Bu;  // "KCP1" little-endian
inline constexpr std::size_t kHeaderBytes = 20;

struct Header {
  std::uint32_t sequence = 0;
  std::uint8_t block = 0;
  std::uint16_t version = 0;
  std::uint32_t length = 0;
  std::uint32_t crc32 = 0;
};

// The header bytes for `payload` (CRC included). Inline: it calls into kincal_protocol, whose
// call graph the library's own stack check cannot see (the images' checks do).
inline std::array<std::uint8_t, kHeaderBytes> make_header(std::uint32_t sequence, std::uint8_t block,
                                                          std::uint16_t version,
                                                          std::span<const std::uint8_t> payload) {
  std::array<std::uint8_t, kHeaderBytes> h{};
  const auto put_u32 = [&h](std::size_t at, std::uint32_t v) {
    for (std::size_t i = 0; i < 4; ++i) h[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
  };
  put_u32(0, kMagic);
  put_u32(4, sequence);
  h[8] = block;
  h[9] = 0;
  h[10] = static_cast<std::uint8_t>(version);
  h[11] = static_cast<std::uint8_t>(version >> 8);
  put_u32(12, static_cast<std::uint32_t>(payload.size()));
  std::uint32_t crc = shared::crc32_update(shared::kCrc32Init, std::span<const std::uint8_t>(h).first(16));
  crc = shared::crc32_update(crc, payload);
  put_u32(16, shared::crc32_finish(crc));
  return h;
}
// Parses a header; false if the magic is wrong or the length exceeds `max_payload`.
bool parse_header(std::span<const std::uint8_t, kHeaderBytes> bytes, std::size_t max_payload, Header& out);
// Whether sequence a is newer than b (serial number arithmetic, RFC 1982 style).
constexpr bool newer(std::uint32_t a, std::uint32_t b) { return static_cast<std::int32_t>(a - b) > 0; }
// Slot index of a block's copy (0 = A, 1 = B).
constexpr std::uint8_t slot_of(shared::ParameterBlock block, std::uint8_t copy) {
  return static_cast<std::uint8_t>((static_cast<std::uint8_t>(block) - 1u) * 2u + copy);
}
inline constexpr std::uint8_t kSlotCount = shared::kParameterBlockCount * 2;

}  // namespace slot_format

struct LoadResult {
  StoreStatus status = StoreStatus::kMissing;
  std::uint32_t sequence = 0;
  std::size_t length = 0;
  std::uint16_t version = 0;  // the block's format version as stored
};

template <StoragePort Storage>
class ParameterStore {
 public:
  static_assert(Storage::kSlotBytes >= slot_format::kHeaderBytes + shared::kMaxBlockBytes,
                "a storage slot must hold the largest parameter block and its header");

  explicit ParameterStore(Storage& storage) : storage_(storage) {}

  // The newest valid copy of `block`, its payload copied into `out`.
  LoadResult load(shared::ParameterBlock block, std::span<std::uint8_t> out) {
    LoadResult best;
    int best_copy = -1;
    for (std::uint8_t copy = 0; copy < 2; ++copy) {
      slot_format::Header h;
      if (!valid(slot_format::slot_of(block, copy), block, h)) continue;
      if (best_copy < 0 || slot_format::newer(h.sequence, best.sequence)) {
        best = {StoreStatus::kOk, h.sequence, h.length, h.version};
        best_copy = copy;
      }
    }
    if (best_copy < 0) return {StoreStatus::kMissing, 0, 0, 0};
    if (best.length > out.size()) return {StoreStatus::kTooLarge, best.sequence, best.length, best.version};
    const std::uint8_t slot = slot_format::slot_of(block, static_cast<std::uint8_t>(best_copy));
    if (storage_.read(slot, slot_format::kHeaderBytes, out.first(best.length)) != StorageStatus::kOk)
      return {StoreStatus::kStorageFailed, 0, 0, 0};
    return best;
  }

  // Saves a fresh copy; on success `sequence` is its sequence number.
  StoreStatus save(shared::ParameterBlock block, std::uint16_t version, std::span<const std::uint8_t> payload,
                   std::uint32_t& sequence) {
    if (payload.size() + slot_format::kHeaderBytes > Storage::kSlotBytes) return StoreStatus::kTooLarge;
    // Target the copy that is not the newest valid one.
    slot_format::Header a, b;
    const bool a_ok = valid(slot_format::slot_of(block, 0), block, a);
    const bool b_ok = valid(slot_format::slot_of(block, 1), block, b);
    std::uint8_t target = 0;
    std::uint32_t next = 1;
    if (a_ok && (!b_ok || slot_format::newer(a.sequence, b.sequence))) {
      target = 1;
      next = a.sequence + 1;
    } else if (b_ok) {
      target = 0;
      next = b.sequence + 1;
    }
    const std::uint8_t slot = slot_format::slot_of(block, target);
    const auto header = slot_format::make_header(next, static_cast<std::uint8_t>(block), version, payload);
    if (storage_.erase(slot) != StorageStatus::kOk ||
        storage_.write(slot, slot_format::kHeaderBytes, payload) != StorageStatus::kOk ||
        storage_.write(slot, 0, header) != StorageStatus::kOk)
      return StoreStatus::kStorageFailed;
    slot_format::Header check;
    if (!valid(slot, block, check) || check.sequence != next) return StoreStatus::kStorageFailed;
    sequence = next;
    return StoreStatus::kOk;
  }

 private:
  // Reads a slot's header and checks magic, block, length and the CRC over header and payload.
  bool valid(std::uint8_t slot, shared::ParameterBlock block, slot_format::Header& h) {
    std::array<std::uint8_t, slot_format::kHeaderBytes> header{};
    if (storage_.read(slot, 0, header) != StorageStatus::kOk) return false;
    if (!slot_format::parse_header(header, Storage::kSlotBytes - slot_format::kHeaderBytes, h)) return false;
    if (h.block != static_cast<std::uint8_t>(block)) return false;
    std::uint32_t crc = shared::crc32_update(shared::kCrc32Init, std::span<const std::uint8_t>(header).first(16));
    std::array<std::uint8_t, 64> chunk{};
    for (std::uint32_t done = 0; done < h.length;) {
      const std::uint32_t n =
          h.length - done < chunk.size() ? h.length - done : static_cast<std::uint32_t>(chunk.size());
      if (storage_.read(slot, static_cast<std::uint32_t>(slot_format::kHeaderBytes) + done,
                        std::span<std::uint8_t>(chunk).first(n)) != StorageStatus::kOk)
        return false;
      crc = shared::crc32_update(crc, std::span<const std::uint8_t>(chunk).first(n));
      done += n;
    }
    return shared::crc32_finish(crc) == h.crc32;
  }

  Storage& storage_;
};

}  // namespace kincal::app

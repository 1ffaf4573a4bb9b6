// Test doubles of the platform's ports (firmware/app/ports.hpp), without heap, so the same
// tests run natively and on the M4: a CAN port that records frames, RAM storage that can lose
// power after any number of byte operations, rangers with settable readings.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "firmware/app/ports.hpp"
#include "firmware/app/ranger_measurement.hpp"

namespace kincal::test {

struct FakeCan {
  std::array<shared::CanFrame, 256> sent{};
  std::size_t count = 0;
  std::size_t capacity = 256;  // frames accepted before try_send reports "full"
  app::CanHealth health_now;

  bool try_send(const shared::CanFrame& frame) {
    if (count >= capacity || count >= sent.size()) return false;
    sent[count++] = frame;
    return true;
  }
  app::CanHealth health() { return health_now; }
};

// Storage that fails once `budget` byte operations are spent (a power cut): the operation in
// progress stops where it is, an interrupted erase leaves garbage behind it, and every later
// operation fails until power_on().
struct FakeStorage {
  static constexpr std::size_t kSlotBytes = 2560;
  static constexpr std::size_t kSlots = 8;
  std::array<std::array<std::uint8_t, kSlotBytes>, kSlots> slots{};
  std::int64_t budget = -1;  // < 0: unlimited
  bool powered = true;
  std::size_t operations = 0;

  FakeStorage() {
    for (auto& s : slots) s.fill(0xFF);
  }
  bool spend() {
    if (!powered) return false;
    if (budget == 0) {
      powered = false;
      return false;
    }
    if (budget > 0) --budget;
    ++operations;
    return true;
  }
  void power_on() {
    powered = true;
    budget = -1;
  }
  app::StorageStatus read(std::uint8_t slot, std::uint32_t offset, std::span<std::uint8_t> out) {
    if (!powered || slot >= kSlots || offset + out.size() > kSlotBytes) return app::StorageStatus::kFailed;
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = slots[slot][offset + i];
    return app::StorageStatus::kOk;
  }
  app::StorageStatus erase(std::uint8_t slot) {
    if (slot >= kSlots) return app::StorageStatus::kFailed;
    for (std::size_t i = 0; i < kSlotBytes; ++i) {
      if (!spend()) {
        for (std::size_t j = i; j < kSlotBytes && j < i + 64; ++j) slots[slot][j] ^= 0x5A;  // half-erased cells
        return app::StorageStatus::kFailed;
      }
      slots[slot][i] = 0xFF;
    }
    return app::StorageStatus::kOk;
  }
  app::StorageStatus write(std::uint8_t slot, std::uint32_t offset, std::span<const std::uint8_t> in) {
    if (slot >= kSlots || offset + in.size() > kSlotBytes) return app::StorageStatus::kFailed;
    for (std::size_t i = 0; i < in.size(); ++i) {
      if (!spend()) return app::StorageStatus::kFailed;
      slots[slot][offset + i] &= in[i];  // flash programming only clears bits
    }
    return app::StorageStatus::kOk;
  }
};

struct FakeRangers {
  std::array<std::uint32_t, shared::kRangers> ranges_um{200000, 210000, 190000, app::kNoEchoUm};
  std::uint64_t time_us = 0;
  bool fail = false;
  app::RangerStatus read(std::array<std::uint32_t, shared::kRangers>& out, std::uint64_t& t) {
    if (fail) return app::RangerStatus::kFailed;
    out = ranges_um;
    t = time_us;
    return app::RangerStatus::kOk;
  }
};

}  // namespace kincal::test

// Test doubles of the platform's ports (firmware/app/ports.hpp), without heap, so the same
// tests run natively and on the M4: a CAN port that records frames, RAM storage that can lose
// power after any number of byte operations, rangers with settable readings, a camera serving
// an in-memory grey image with settable failures.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "firmware/app/ports.hpp"

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

// Serves `image` (width x height, row-major) for every frame, like a camera looking at a still
// scene; counts the frames and remembers what each was for.
struct FakeCamera {
  std::span<const std::uint8_t> image;
  std::uint16_t width = 0, height = 0;
  std::uint64_t exposure_us = 0;  // reported by begin_frame
  bool fail_begin = false;
  int fail_at_row = -1;     // read_row of this row of the measurement frame reports kFailed
  int pending_at_row = -1;  // from this row of the measurement frame on, rows never arrive
  int frames = 0;
  app::FrameUse last_use = app::FrameUse::kMetering;
  int row = 0;
  bool active = false;

  std::uint16_t width_px() const { return width; }
  std::uint16_t height_px() const { return height; }
  app::CaptureStatus begin_frame(app::FrameUse use, std::uint64_t& exposure) {
    if (fail_begin) return app::CaptureStatus::kFailed;
    ++frames;
    last_use = use;
    row = 0;
    active = true;
    exposure = exposure_us;
    return app::CaptureStatus::kOk;
  }
  app::CaptureStatus read_row(std::span<std::uint8_t> out) {
    const bool measuring = last_use == app::FrameUse::kMeasurement;
    if (!active || row >= height || out.size() != width || (measuring && row == fail_at_row)) {
      active = false;
      return app::CaptureStatus::kFailed;
    }
    if (measuring && pending_at_row >= 0 && row >= pending_at_row) return app::CaptureStatus::kPending;
    const std::size_t offset = static_cast<std::size_t>(row) * width;
    for (std::size_t x = 0; x < width; ++x) out[x] = image[offset + x];
    ++row;
    return app::CaptureStatus::kOk;
  }
};

static_assert(app::CameraPort<FakeCamera>);
static_assert(app::RangerPort<FakeRangers>);

}  // namespace kincal::test

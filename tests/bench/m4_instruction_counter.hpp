// Counts instructions on the Cortex-M4 under `qemu-system-arm -M mps2-an386 -icount shift=0`,
// where every instruction takes 1 ns of virtual time and SysTick, on the 25 MHz processor
// clock, ticks once per 40 instructions. Resolution is therefore 40 instructions: time
// many repetitions of short code and divide. Intervals must stay under 2^24 ticks.
#pragma once

#include <cstdint>

namespace kincal::bench {

class M4InstructionCounter {
 public:
  static constexpr std::uint32_t kInstructionsPerTick = 40;

  M4InstructionCounter() {
    reg(kReload) = 0xFFFFFFu;
    reg(kCurrent) = 0;
    reg(kControl) = kEnable | kProcessorClock;
  }
  // SysTick counts down; the difference of two readings is the ticks in between.
  void start() { start_ = reg(kCurrent); }
  std::uint64_t stop_instructions() const {
    const std::uint32_t now = reg(kCurrent);
    return std::uint64_t{(start_ - now) & 0xFFFFFFu} * kInstructionsPerTick;
  }

 private:
  static constexpr std::uintptr_t kControl = 0xE000E010u, kReload = 0xE000E014u, kCurrent = 0xE000E018u;
  static constexpr std::uint32_t kEnable = 1u << 0, kProcessorClock = 1u << 2;
  static volatile std::uint32_t& reg(std::uintptr_t address) {
    return *reinterpret_cast<volatile std::uint32_t*>(address);
  }
  std::uint32_t start_ = 0;
};

}  // namespace kincal::bench

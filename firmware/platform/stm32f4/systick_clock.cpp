#include "firmware/platform/stm32f4/systick_clock.hpp"

#include "firmware/platform/stm32f4/mmio.hpp"

namespace kincal::stm32f4::systick {

static_assert(micros(0, 167999, 167999, 168) == 0 && micros(2, 167999, 0, 168) == 2999);
static_assert(micros(1, 15999, 15999 - 160, 16) == 1010 && micros(5, 15999, 20000, 16) == 5000);

namespace {

using mmio::reg;

// SysTick and the system control block (ARMv7-M B3.3, B3.2).
constexpr std::uintptr_t kSystCsr = 0xE000E010u, kSystRvr = 0xE000E014u, kSystCvr = 0xE000E018u;
constexpr std::uintptr_t kScbIcsr = 0xE000ED04u;
constexpr std::uintptr_t kScbShpr3SysTick = 0xE000ED23u;  // SHPR3[31:24]: SysTick's priority
constexpr std::uint32_t kCsrEnable = 1u << 0, kCsrTickInt = 1u << 1, kCsrProcessorClock = 1u << 2;
constexpr std::uint32_t kIcsrPendStSet = 1u << 26;

// The millisecond count as two words: the handler writes them, readers retry on a change.
constinit volatile std::uint32_t ms_low = 0;
constinit volatile std::uint32_t ms_high = 0;
constinit std::uint32_t reload = 0;
constinit std::uint32_t cycles_per_us = 1;
constinit std::uint64_t last_us = 0;

}  // namespace

void start(std::uint32_t core_hz) {
  cycles_per_us = core_hz / 1000000u;
  reload = core_hz / 1000u - 1u;
  mmio::reg8(kScbShpr3SysTick) = mmio::kIrqPriority;
  reg(kSystRvr) = reload;
  reg(kSystCvr) = 0;
  reg(kSystCsr) = kCsrEnable | kCsrTickInt | kCsrProcessorClock;
}

std::uint64_t now_us() {
  // The handler runs at most once per millisecond and the window below is a few cycles long, so
  // a second attempt always succeeds unless something preempts this caller for over 1 ms twice.
  for (int attempt = 0; attempt < 3; ++attempt) {
    const std::uint32_t high = ms_high, low = ms_low;
    std::uint32_t current = reg(kSystCvr);
    std::uint64_t ms = (std::uint64_t{high} << 32) | low;
    if ((reg(kScbIcsr) & kIcsrPendStSet) != 0) {
      // The counter wrapped and the handler has not counted it: re-read after the wrap.
      current = reg(kSystCvr);
      ++ms;
    }
    if (low != ms_low || high != ms_high) continue;
    const std::uint64_t us = micros(ms, reload, current, cycles_per_us);
    if (us > last_us) last_us = us;
    return last_us;
  }
  return last_us;
}

}  // namespace kincal::stm32f4::systick

extern "C" void SysTick_Handler() {
  using kincal::stm32f4::systick::ms_high;
  using kincal::stm32f4::systick::ms_low;
  const std::uint32_t low = ms_low + 1u;
  ms_low = low;
  if (low == 0) ms_high = ms_high + 1u;
}

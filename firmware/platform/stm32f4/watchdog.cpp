#include "firmware/platform/stm32f4/watchdog.hpp"

#include "firmware/platform/stm32f4/mmio.hpp"

namespace kincal::stm32f4::watchdog {

// About 100 ms: 68..188 ms over the LSI's range, always far above a main-loop pass (<= 1 ms idle).
static_assert(timeout_us(kNormalTimeout, kLsiNominalHz) == 100000);
static_assert(timeout_us(kNormalTimeout, kLsiMaxHz) >= 68000 && timeout_us(kNormalTimeout, kLsiMinHz) <= 189000);
// The long timeout outlasts flash_storage.cpp's bound on an erase (4.4 s) at the fastest LSI.
static_assert(timeout_us(kStallTimeout, kLsiMaxHz) >= 4400000);
static_assert(kNormalTimeout.reload <= 0xFFFu && kStallTimeout.reload <= 0xFFFu && kStallTimeout.prescaler <= 6u);

namespace {

using mmio::reg;

// IWDG (RM0090 21.4) and the debug freeze (RM0090 38.16.4).
constexpr std::uintptr_t kIwdgKr = 0x40003000u, kIwdgPr = 0x40003004u, kIwdgRlr = 0x40003008u, kIwdgSr = 0x4000300Cu;
constexpr std::uint32_t kKeyStart = 0xCCCCu, kKeyReload = 0xAAAAu, kKeyUnlock = 0x5555u;
constexpr std::uint32_t kSrPvu = 1u << 0, kSrRvu = 1u << 1;
constexpr std::uintptr_t kDbgmcuApb1Fz = 0xE0042008u;
constexpr std::uint32_t kDbgIwdgStop = 1u << 12;

// PVU/RVU clear within 5 LSI periods (<= 0.3 ms at 17 kHz); each poll takes at least 5 cycles,
// so this bound is >= 3 ms at 168 MHz and >= 30 ms at the 16 MHz fall-back.
constexpr std::uint32_t kUpdateWaitLimit = 100000;

constinit bool started = false;

}  // namespace

WatchdogStatus set_timeout(const Timeout& timeout) {
  if (!started) return WatchdogStatus::kNotStarted;
  reg(kIwdgKr) = kKeyUnlock;
  reg(kIwdgPr) = timeout.prescaler;
  reg(kIwdgRlr) = timeout.reload;
  bool updated = false;
  for (std::uint32_t i = 0; i < kUpdateWaitLimit && !updated; ++i) updated = (reg(kIwdgSr) & (kSrPvu | kSrRvu)) == 0;
  reg(kIwdgKr) = kKeyReload;  // also locks PR and RLR again
  return updated ? WatchdogStatus::kRunning : WatchdogStatus::kUpdateTimedOut;
}

WatchdogStatus start() {
  mmio::set_bits(kDbgmcuApb1Fz, kDbgIwdgStop);
  reg(kIwdgKr) = kKeyStart;  // starts the LSI and the countdown from 4095 at divider 4 (512 ms)
  started = true;
  return set_timeout(kNormalTimeout);
}

void refresh() { reg(kIwdgKr) = kKeyReload; }

}  // namespace kincal::stm32f4::watchdog

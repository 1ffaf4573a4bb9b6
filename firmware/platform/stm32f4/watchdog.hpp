// The independent watchdog (IWDG, RM0090 section 21): resets the STM32F407 when the main loop
// stops coming round.
//
// What it protects against: firmware that hangs or runs away -- an endless loop, a deadlock on a
// flag an interrupt never sets, a fault handler spinning (Default_Handler), corrupted control
// flow -- and a main loop so late that the correction stream stops. The IWDG counts on the
// internal 32 kHz RC oscillator (LSI), not on the core clock, so it also fires when the clock
// tree has failed; once started, nothing but a reset stops it. It does not protect against
// wrong results computed on time, nor against an interrupt storm that still lets the main loop
// through, nor does it report a reset after the fact (no protocol flag says so yet).
//
// Use: start() once in firmware_main(), then refresh() once per main-loop pass. The main loop
// passes at least once per millisecond (SysTick wakes it from WFI), so the nominal 100 ms leaves
// two orders of magnitude of headroom. Flash erase and programming stall the CPU (one flash
// bank) for up to 2 s per sector: reach the flash through StallGuardedStorage, which lengthens
// the timeout to kStallTimeout around each erase and write and restores it after.
//
// Timing: timeout = divider * (reload + 1) / f_LSI. The LSI is 32 kHz nominal but anywhere in
// 17..47 kHz (datasheet DS8626, LSI characteristics), so the normal timeout of nominally 100 ms
// fires after 68..188 ms, and the long one after 5.6..15.4 s (>= 4.4 s, flash_storage.cpp's own
// bound on an erase). The arithmetic is checked at compile time (static_assert, watchdog.cpp).
// While a debugger halts the core the watchdog is frozen (DBGMCU_APB1_FZ.DBG_IWDG_STOP).
//
// ISR safety: main loop only (start, refresh and the guarded storage calls). Cost: refresh() is
// one register store; a timeout change writes three registers and waits for the IWDG to take
// them (up to 5 LSI periods, about 0.3 ms).
// Failure modes: kUpdateTimedOut when the IWDG did not confirm the changed prescaler and reload values
// within the bounded wait (the LSI does not run): the watchdog then runs with whatever it last
// accepted, or not at all if the LSI is dead. kNotStarted from set_timeout() before start() (the
// application loads its parameters before the watchdog runs).
//
// Proven by execution (tests/target/stm32f4_boot, QEMU's STM32F405 model, which has no IWDG and
// logs the writes): start() writes the start key and the normal timeout, and the main loop
// reloads once per pass. Proven only by compilation (no board here): that the IWDG accepts the
// update sequence (RM0090 21.3-21.4), the LSI start on the start key, the debug freeze, the reset
// itself, and that no main-loop pass or guarded flash operation outlasts its timeout on real
// hardware. The arithmetic of the timeouts is checked at compile time.
#pragma once

#include <cstdint>
#include <span>

#include "firmware/app/ports.hpp"

namespace kincal::stm32f4::watchdog {

// LSI frequency, nominal and datasheet extremes.
inline constexpr std::uint32_t kLsiNominalHz = 32000, kLsiMinHz = 17000, kLsiMaxHz = 47000;

// A prescaler setting (PR register: divider 4 << pr) and reload value (12 bits).
struct Timeout {
  std::uint32_t prescaler;  // PR: 0..6 for dividers 4..256
  std::uint32_t reload;     // RLR: 0..4095
};

constexpr std::uint32_t divider(const Timeout& t) { return 4u << t.prescaler; }
// Microseconds until the reset at a given LSI frequency.
constexpr std::uint64_t timeout_us(const Timeout& t, std::uint32_t lsi_hz) {
  return std::uint64_t{divider(t)} * (t.reload + 1u) * 1000000u / lsi_hz;
}

inline constexpr Timeout kNormalTimeout{0, kLsiNominalHz / 4u / 10u - 1u};  // 100 ms at 32 kHz
inline constexpr Timeout kStallTimeout{4, 4095};                            // 8.2 s at 32 kHz

enum class [[nodiscard]] WatchdogStatus : std::uint8_t{kRunning, kUpdateTimedOut, kNotStarted};

// Starts the IWDG (and with it the LSI) with kNormalTimeout. Cannot be undone.
WatchdogStatus start();

// Reloads the counter: the next reset is one full timeout away.
void refresh();

// Sets another timeout and reloads the counter with it; before start(), does nothing (kNotStarted).
WatchdogStatus set_timeout(const Timeout& timeout);

// A StoragePort that runs each erase and write of `Storage` under kStallTimeout and returns to
// kNormalTimeout afterwards; reads pass straight through (memory-mapped, quick).
template <app::StoragePort Storage>
class StallGuardedStorage {
 public:
  static constexpr std::size_t kSlotBytes = Storage::kSlotBytes;

  explicit StallGuardedStorage(Storage& storage) : storage_(storage) {}

  app::StorageStatus read(std::uint8_t slot, std::uint32_t offset, std::span<std::uint8_t> out) {
    return storage_.read(slot, offset, out);
  }
  app::StorageStatus erase(std::uint8_t slot) {
    (void)set_timeout(kStallTimeout);  // on failure the normal timeout stays: nothing better to do
    const app::StorageStatus status = storage_.erase(slot);
    (void)set_timeout(kNormalTimeout);
    return status;
  }
  app::StorageStatus write(std::uint8_t slot, std::uint32_t offset, std::span<const std::uint8_t> in) {
    (void)set_timeout(kStallTimeout);
    const app::StorageStatus status = storage_.write(slot, offset, in);
    (void)set_timeout(kNormalTimeout);
    return status;
  }

 private:
  Storage& storage_;
};

}  // namespace kincal::stm32f4::watchdog

// The platform's monotonic microsecond clock: SysTick interrupting at 1 kHz from the processor
// clock counts milliseconds in 64 bits; now_us() adds the microseconds elapsed in the current
// millisecond from SysTick's down-counter. The time base of the application (ISO-TP timeouts,
// heartbeat, report time stamps).
//
// Why SysTick: it is in every Cortex-M, needs no peripheral clock and its interrupt also wakes
// the main loop from WFI at least every millisecond, which bounds the latency of timed work.
// Resolution 1 us; accuracy that of the core clock (the crystal's 30-50 ppm on the PLL, the HSI's
// +-1 % on the fall-back). 64 bits of microseconds do not wrap in 500,000 years.
// ISR safety: SysTick_Handler is the only writer of the millisecond count. now_us() is for the
// main loop (thread mode), with interrupts masked or not (it accounts a tick that is pending); it
// keeps the last value it returned, so it is not for ISRs. It never returns less than before.
// Cost: SysTick_Handler about 12 cycles; now_us() about 30 cycles (one division by the core
// clock in MHz).
// Failure modes: the clock does not advance while the CPU cannot take the SysTick interrupt for
// more than 1 ms: during a flash erase (up to 2 s, flash_storage.hpp) every millisecond but the
// first is lost. Time stays monotonic; it runs late by the stall. (A free-running 32-bit timer or
// the DWT cycle counter would keep counting; see the README's "what is left".)
#pragma once

#include <cstdint>

namespace kincal::stm32f4::systick {

// Microseconds from a millisecond count and SysTick's state: `reload` = LOAD (cycles per ms - 1),
// `current` = VAL (counts down from reload to 0), `cycles_per_us` = core clock in MHz.
constexpr std::uint64_t micros(std::uint64_t ms, std::uint32_t reload, std::uint32_t current,
                               std::uint32_t cycles_per_us) {
  const std::uint32_t elapsed = current > reload ? 0u : reload - current;
  const std::uint32_t us = elapsed / cycles_per_us;
  return ms * 1000u + (us > 999u ? 999u : us);
}

// Starts the 1 kHz tick at `core_hz` (168 MHz on the PLL, 16 MHz on the HSI; a multiple of 1 MHz,
// at most 16.7 GHz). Call once, before anything reads the clock.
void start(std::uint32_t core_hz);

// Microseconds since start().
std::uint64_t now_us();

}  // namespace kincal::stm32f4::systick

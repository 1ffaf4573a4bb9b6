// Clock tree of the STM32F407: 8 MHz HSE crystal -> PLL -> 168 MHz SYSCLK, 42 MHz APB1 (bxCAN),
// 84 MHz APB2, 48 MHz for USB. Register-level (RM0090 section 6), no vendor HAL.
#pragma once

#include <cstdint>

namespace kincal::stm32f4 {

enum class ClockStatus : std::uint8_t {
  kPll168MHz,       // running from the PLL at 168 MHz
  kHseFailedOnHsi,  // the crystal did not start: still on the 16 MHz internal oscillator
  kPllFailedOnHsi,  // the PLL did not lock: still on the 16 MHz internal oscillator
};

// Set once by Reset_Handler before main(); the application reports it in its status.
extern ClockStatus clock_status;

// Grants the FPU (CP10/CP11) full access; must run before any floating-point instruction.
void enable_fpu();

// Switches SYSCLK to the PLL. Each wait is bounded; on a timeout the MCU stays on the HSI.
[[nodiscard]] ClockStatus configure_clock_168mhz();

}  // namespace kincal::stm32f4

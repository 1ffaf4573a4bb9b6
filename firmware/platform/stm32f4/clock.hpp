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

// The clocks the buses run at, as the RCC registers say now (not as configure_clock_168mhz()
// meant them): 168 / 42 / 84 MHz on the PLL; 16 MHz everywhere when the set-up gave up before the
// prescalers. Assumes the 8 MHz crystal when the HSE drives SYSCLK or the PLL.
struct ClockRates {
  std::uint32_t core_hz;
  std::uint32_t apb1_hz;  // bxCAN
  std::uint32_t apb2_hz;  // ADC
};
// From the register values: RCC_CFGR (SWS, HPRE, PPRE1, PPRE2) and RCC_PLLCFGR.
constexpr ClockRates clock_rates(std::uint32_t cfgr, std::uint32_t pllcfgr) {
  constexpr std::uint32_t hsi_hz = 16000000, hse_hz = 8000000;
  std::uint32_t sysclk = hsi_hz;
  const std::uint32_t sws = (cfgr >> 2) & 3u;
  if (sws == 1) sysclk = hse_hz;
  if (sws == 2) {
    const std::uint32_t input = (pllcfgr & (1u << 22)) != 0 ? hse_hz : hsi_hz;
    const std::uint32_t m = pllcfgr & 0x3Fu, n = (pllcfgr >> 6) & 0x1FFu, p = 2u * (((pllcfgr >> 16) & 3u) + 1u);
    sysclk = m == 0 ? 0 : input / m * n / p;
  }
  const std::uint32_t hpre = (cfgr >> 4) & 0xFu;
  constexpr std::uint32_t ahb_shift[8] = {1, 2, 3, 4, 6, 7, 8, 9};  // HPRE 1000..1111: /2../512
  const std::uint32_t hclk = hpre < 8 ? sysclk : sysclk >> ahb_shift[hpre - 8];
  const auto apb = [hclk](std::uint32_t ppre) { return ppre < 4 ? hclk : hclk >> (ppre - 3u); };  // 100: /2 .. 111: /16
  return {hclk, apb((cfgr >> 10) & 7u), apb((cfgr >> 13) & 7u)};
}
ClockRates clock_rates();

// Grants the FPU (CP10/CP11) full access; must run before any floating-point instruction.
void enable_fpu();

// Switches SYSCLK to the PLL. Each wait is bounded; on a timeout the MCU stays on the HSI.
[[nodiscard]] ClockStatus configure_clock_168mhz();

}  // namespace kincal::stm32f4

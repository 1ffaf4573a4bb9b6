#include "firmware/platform/stm32f4/clock.hpp"

namespace kincal::stm32f4 {

ClockStatus clock_status = ClockStatus::kHseFailedOnHsi;

namespace {

// Peripheral registers (RM0090 memory map).
inline volatile std::uint32_t& reg(std::uintptr_t address) {
  return *reinterpret_cast<volatile std::uint32_t*>(address);
}
constexpr std::uintptr_t kScbCpacr = 0xE000ED88u;
constexpr std::uintptr_t kRccCr = 0x40023800u;
constexpr std::uintptr_t kRccPllcfgr = 0x40023804u;
constexpr std::uintptr_t kRccCfgr = 0x40023808u;
constexpr std::uintptr_t kRccApb1enr = 0x40023840u;
constexpr std::uintptr_t kFlashAcr = 0x40023C00u;
constexpr std::uintptr_t kPwrCr = 0x40007000u;

constexpr std::uint32_t kHseOn = 1u << 16, kHseRdy = 1u << 17, kPllOn = 1u << 24, kPllRdy = 1u << 25;
constexpr std::uint32_t kPwrEn = 1u << 28, kVosScale1 = 1u << 14;

// About 50 ms at the 16 MHz HSI: far longer than a crystal (2 ms) or the PLL (0.2 ms) needs.
constexpr std::uint32_t kWaitLimit = 200000;

bool wait_for(std::uintptr_t address, std::uint32_t mask, std::uint32_t value) {
  for (std::uint32_t i = 0; i < kWaitLimit; ++i)
    if ((reg(address) & mask) == value) return true;
  return false;
}

}  // namespace

static_assert(clock_rates(0x940Au, 0x07405408u).core_hz == 168000000);  // the PLL set-up below
static_assert(clock_rates(0x940Au, 0x07405408u).apb1_hz == 42000000);
static_assert(clock_rates(0x940Au, 0x07405408u).apb2_hz == 84000000);
static_assert(clock_rates(0, 0x07405408u).apb1_hz == 16000000 && clock_rates(0x1400u, 0).apb1_hz == 4000000);

ClockRates clock_rates() { return clock_rates(reg(kRccCfgr), reg(kRccPllcfgr)); }

void enable_fpu() {
  reg(kScbCpacr) = reg(kScbCpacr) | (0xFu << 20);
  __asm volatile("dsb\n\tisb" ::: "memory");
}

ClockStatus configure_clock_168mhz() {
  reg(kRccCr) = reg(kRccCr) | kHseOn;
  if (!wait_for(kRccCr, kHseRdy, kHseRdy)) return ClockStatus::kHseFailedOnHsi;

  // Voltage scale 1 is required above 144 MHz.
  reg(kRccApb1enr) = reg(kRccApb1enr) | kPwrEn;
  reg(kPwrCr) = reg(kPwrCr) | kVosScale1;

  // VCO = 8 MHz / M(8) * N(336) = 336 MHz; SYSCLK = VCO / P(2) = 168 MHz; USB = VCO / Q(7) = 48 MHz.
  constexpr std::uint32_t m = 8, n = 336, p_bits = 0 /* P = 2 */, q = 7, src_hse = 1u << 22;
  reg(kRccPllcfgr) = m | (n << 6) | (p_bits << 16) | src_hse | (q << 24);
  reg(kRccCr) = reg(kRccCr) | kPllOn;
  if (!wait_for(kRccCr, kPllRdy, kPllRdy)) return ClockStatus::kPllFailedOnHsi;

  // 5 flash wait states at 168 MHz and 3.3 V, with prefetch and both caches.
  constexpr std::uint32_t latency_5ws = 5, prefetch = 1u << 8, icache = 1u << 9, dcache = 1u << 10;
  reg(kFlashAcr) = latency_5ws | prefetch | icache | dcache;
  if (!wait_for(kFlashAcr, 0xFu, latency_5ws)) return ClockStatus::kPllFailedOnHsi;

  // AHB /1, APB1 /4 (42 MHz, its maximum), APB2 /2 (84 MHz); then switch SYSCLK to the PLL.
  constexpr std::uint32_t ppre1_div4 = 0x5u << 10, ppre2_div2 = 0x4u << 13, sw_pll = 0x2u;
  reg(kRccCfgr) = ppre1_div4 | ppre2_div2 | sw_pll;
  if (!wait_for(kRccCfgr, 0xCu, sw_pll << 2)) return ClockStatus::kPllFailedOnHsi;
  return ClockStatus::kPll168MHz;
}

}  // namespace kincal::stm32f4

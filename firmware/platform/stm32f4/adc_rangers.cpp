#include "firmware/platform/stm32f4/adc_rangers.hpp"

#include "firmware/platform/stm32f4/mmio.hpp"
#include "firmware/platform/stm32f4/systick_clock.hpp"

namespace kincal::stm32f4 {

static_assert(range_um_from_counts(79) == app::kNoEchoUm && range_um_from_counts(80) == 200000);
static_assert(range_um_from_counts(400) == 1000000 && range_um_from_counts(3059) == 7647500);
static_assert(range_um_from_counts(3060) == app::kNoEchoUm && range_um_from_counts(4095) == app::kNoEchoUm);

namespace {

using mmio::reg;

// ADC1 and the ADC common registers (RM0090 13.13).
constexpr std::uintptr_t kAdc1 = 0x40012000u;
constexpr std::uintptr_t kSr = kAdc1 + 0x00u, kCr1 = kAdc1 + 0x04u, kCr2 = kAdc1 + 0x08u;
constexpr std::uintptr_t kSmpr2 = kAdc1 + 0x10u, kSqr1 = kAdc1 + 0x2Cu, kSqr3 = kAdc1 + 0x34u, kDr = kAdc1 + 0x4Cu;
constexpr std::uintptr_t kCcr = 0x40012304u;
constexpr std::uint32_t kSrEoc = 1u << 1, kSrOvr = 1u << 5;
constexpr std::uint32_t kCr2Adon = 1u << 0, kCr2Swstart = 1u << 30;
constexpr std::uint32_t kCcrAdcpreDiv4 = 1u << 16;
constexpr std::uint32_t kSample480Cycles = 7;
constexpr std::uint32_t kAdcMaxHz = 36000000;

// After ADON the ADC needs tSTAB = 3 us before converting: 2,000 APB2 reads are more than that.
constexpr std::uint32_t kStabilisationReads = 2000;

}  // namespace

AdcStatus AdcRangers::start(std::uint32_t apb2_hz) {
  started_ = false;
  if (apb2_hz / 4u > kAdcMaxHz) return AdcStatus::kUnsupportedClock;
  mmio::enable_clock(mmio::kRccAhb1enr, mmio::kAhb1GpioA | mmio::kAhb1GpioB);
  mmio::enable_clock(mmio::kRccApb2enr, mmio::kApb2Adc1);
  for (const unsigned pin : {1u, 2u, 3u})
    mmio::configure_pin(mmio::kGpioA, pin, mmio::PinMode::kAnalog, mmio::Pull::kNone);
  mmio::configure_pin(mmio::kGpioB, 0, mmio::PinMode::kAnalog, mmio::Pull::kNone);

  mmio::modify(kCcr, 3u << 16, kCcrAdcpreDiv4);
  reg(kCr1) = 0;         // 12 bits, no scan, no interrupts
  reg(kCr2) = kCr2Adon;  // right-aligned, single conversion, software start
  reg(kSqr1) = 0;        // one conversion per sequence
  std::uint32_t smpr2 = 0;
  for (const std::uint8_t channel : kRangerAdcChannels) smpr2 |= kSample480Cycles << (3u * channel);
  reg(kSmpr2) = smpr2;
  for (std::uint32_t i = 0; i < kStabilisationReads; ++i) {
    const std::uint32_t status = reg(kSr);
    static_cast<void>(status);
  }
  started_ = true;
  return AdcStatus::kOk;
}

app::RangerStatus AdcRangers::read(std::array<std::uint32_t, shared::kRangers>& ranges_um, std::uint64_t& time_us) {
  if (!started_) return app::RangerStatus::kFailed;
  for (std::size_t beam = 0; beam < shared::kRangers; ++beam) {
    reg(kSqr3) = kRangerAdcChannels[beam];
    reg(kSr) = ~(kSrEoc | kSrOvr);  // the flags clear by writing 0
    mmio::set_bits(kCr2, kCr2Swstart);
    if (!wait_adc_end_of_conversion()) return app::RangerStatus::kFailed;
    ranges_um[beam] = range_um_from_counts(reg(kDr) & 0xFFFu);  // reading DR clears EOC
  }
  time_us = systick::now_us();
  return app::RangerStatus::kOk;
}

}  // namespace kincal::stm32f4

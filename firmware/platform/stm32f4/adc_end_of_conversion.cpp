// The end-of-conversion wait of adc_rangers.cpp, alone in its translation unit so that an image
// for a model without the EOC flag can replace it at link time (adc_rangers.hpp).
#include "firmware/platform/stm32f4/adc_rangers.hpp"
#include "firmware/platform/stm32f4/mmio.hpp"

namespace kincal::stm32f4 {

namespace {

constexpr std::uintptr_t kAdc1Sr = 0x40012000u;  // ADC1_SR (RM0090 13.13.1)
constexpr std::uint32_t kSrEoc = 1u << 1;
// One conversion takes 492 ADC cycles (23 us at 21 MHz, 123 us at the 4 MHz of the fall-back
// clock); 100,000 polls of the status register are >= 1 ms.
constexpr std::uint32_t kConversionWaitLimit = 100000;

}  // namespace

bool wait_adc_end_of_conversion() {
  for (std::uint32_t i = 0; i < kConversionWaitLimit; ++i)
    if ((mmio::reg(kAdc1Sr) & kSrEoc) != 0) return true;
  return false;
}

}  // namespace kincal::stm32f4

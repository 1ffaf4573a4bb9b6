// The platform's four range sensors read through ADC1 (RM0090 section 13): the RangerPort of
// firmware/app/ports.hpp.
//
// Sensor family assumed: MaxBotix XL-MaxSonar-EZ MB1240-class ultrasonic rangers, whose analog
// output is (Vcc / 1024) per centimetre, 20 cm to 765 cm, updated every 100 ms (the sensor's own
// cycle). With the sensors powered from the same supply as the ADC reference (VDDA = VREF+ = Vcc,
// as on the STM32F4-Discovery), one centimetre is exactly 4 counts of the 12-bit ADC, whatever Vcc
// is: range = counts x 2.5 mm. The sensor resolves 1 cm; the ADC's 2.5 mm steps add quantisation
// below that. Another sensor family (laser time-of-flight over I2C, PWM-output sonars) is another
// RangerPort behind the same concept.
// Pins (ADC1, analog mode), in the order of the geometry's beams 0..3:
//   beam 0  PA1 = ADC1_IN1    beam 1  PA2 = ADC1_IN2    beam 2  PA3 = ADC1_IN3    beam 3  PB0 = ADC1_IN8
// chosen clear of the camera interface (DCMI HSYNC PA4, PIXCLK PA6, data on PC6-PC11/PE0-PE6,
// VSYNC PB7, D5 PB6), of CAN1 (PB8/PB9) and of the Discovery board's user button (PA0) and
// accelerometer SPI (PA5-PA7).
// Conversion: ADC clock = APB2 / 4 (21 MHz from 84 MHz; 36 MHz is the limit), 12 bits, 480-cycle
// sample time (the longest: the sensor's output impedance is not specified), one channel at a time
// by software start, so no conversion can overrun an unread result.
// Out of range -> app::kNoEchoUm: below 20 cm (the sensor never reports less; a lower reading
// means a loose wire or a short) or at 765 cm and above (the sensor's "no target" reading).
//
// ISR safety: main loop only. Memory: one flag. Cost: one scan per read(): 4 x (480 + 12) ADC
// cycles = 94 us at 21 MHz, busy-waiting, bounded.
// Failure modes: read() returns kFailed if start() did not succeed or a conversion did not end
// within its bounded wait (>= 1 ms); the application then reports kRangerFailure.
#pragma once

#include <array>
#include <cstdint>

#include "firmware/app/ports.hpp"
#include "shared/measurement_report.hpp"

namespace kincal::stm32f4 {

inline constexpr std::array<std::uint8_t, shared::kRangers> kRangerAdcChannels{1, 2, 3, 8};

// MB1240-class analog output, ratiometric to the ADC reference: 4 counts per centimetre.
inline constexpr std::uint32_t kUmPerCount = 2500;
inline constexpr std::uint32_t kMinRangeCounts = 20 * 4;   // 20 cm
inline constexpr std::uint32_t kMaxRangeCounts = 765 * 4;  // 765 cm: no target
constexpr std::uint32_t range_um_from_counts(std::uint32_t counts) {
  if (counts < kMinRangeCounts || counts >= kMaxRangeCounts) return app::kNoEchoUm;
  return counts * kUmPerCount;
}

enum class [[nodiscard]] AdcStatus : std::uint8_t{
    kOk,
    kUnsupportedClock,  // APB2 / 4 would exceed the ADC's 36 MHz
};

class AdcRangers {
 public:
  // Clocks, pins and ADC1 set-up, with the APB2 clock clock.hpp reports.
  AdcStatus start(std::uint32_t apb2_hz);

  // app::RangerPort: one scan of the four channels; time_us = when the scan ended.
  app::RangerStatus read(std::array<std::uint32_t, shared::kRangers>& ranges_um, std::uint64_t& time_us);

 private:
  bool started_ = false;
};

static_assert(app::RangerPort<AdcRangers>);

// Waits for the end of ADC1's conversion (SR.EOC), at least 1 ms; false when it did not end.
// Its own translation unit (adc_end_of_conversion.cpp), called by read(): QEMU's STM32F4 model
// never sets EOC (its data register yields a value on the read itself), so the boot test's image
// for that model replaces this one function at link time (--wrap, tests/target/stm32f4_boot).
[[nodiscard]] bool wait_adc_end_of_conversion();

}  // namespace kincal::stm32f4

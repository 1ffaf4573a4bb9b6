// The sensor platform's firmware on the STM32F407: firmware/app bound to this board's ports, as
// firmware/platform/native binds the same application to Linux's.
//   CAN          Bxcan (bxcan.hpp): CAN1 at 1 Mbit/s, classic frames only (AppConfig::fd = false)
//   storage      FlashStorage (flash_storage.hpp): eight flash sectors, one per slot, under the
//                watchdog's long timeout (StallGuardedStorage, watchdog.hpp)
//   measurement  PlatformMeasurement (firmware/app/platform_measurement.hpp) over the DCMI camera
//                (dcmi_camera.hpp) and AdcRangers (adc_rangers.hpp): four analog rangers on ADC1
//   correction   KinematicCorrection (firmware/app/kinematic_correction.hpp)
// Start-up (Reset_Handler has set the clock tree): SysTick clock, rangers, camera, CAN1, then the
// application, which loads its parameter blocks from flash, then the independent watchdog
// (watchdog.hpp), refreshed once per main-loop pass.
// Main loop: every received frame to on_frame() (at most one ring's worth per pass, so poll()
// runs at least once per 64 frames), a drop in the receive path to note_rx_overflow(), then
// poll(). When the application has nothing due and no frame waits, the core sleeps (WFI) until
// the next interrupt: a received frame or the 1 ms SysTick, so timed work runs at most 1 ms late.
// The check for pending work and the WFI happen with interrupts masked, so a frame arriving
// between them still wakes the core (WFI wakes on a pending interrupt even when masked).
//
// Memory: the application object (11 KiB) and the two steps (22 KiB and 3.5 KiB) are
// built by placement-construction into static storage in CCM RAM, beside the stack: no heap, and
// no static constructor (stm32f407vg.ld forbids them). The small ports are in firmware_main's
// frame, which never returns; the camera (`board::camera`, its line buffers in SRAM where the DMA
// reaches them) is a static object like CAN1. Failure modes: a CAN controller
// that does not start leaves the platform mute (nothing can report it); rangers that do not start
// make every measurement report kRangerFailure; a camera whose lines never come makes the camera
// sections report kCameraFailure (after the step's 1 s timeout); the clock fall-back sets
// kClockFallback.
#include <cstddef>
#include <new>

#include "firmware/app/kinematic_correction.hpp"
#include "firmware/app/platform_app.hpp"
#include "firmware/app/platform_measurement.hpp"
#include "firmware/platform/stm32f4/adc_rangers.hpp"
#include "firmware/platform/stm32f4/bxcan.hpp"
#include "firmware/platform/stm32f4/clock.hpp"
#include "firmware/platform/stm32f4/dcmi_camera.hpp"
#include "firmware/platform/stm32f4/flash_storage.hpp"
#include "firmware/platform/stm32f4/systick_clock.hpp"
#include "firmware/platform/stm32f4/watchdog.hpp"

namespace {

namespace board = kincal::stm32f4;
using Measure = kincal::app::PlatformMeasurement<board::DcmiCamera, board::AdcRangers>;
using Correct = kincal::app::KinematicCorrection;
// Flash erases and writes stall the core beyond the watchdog's 100 ms: run them under its long timeout.
using Storage = board::watchdog::StallGuardedStorage<board::FlashStorage>;
using App = kincal::app::PlatformApp<board::Bxcan, Storage, Measure, Correct>;

// NOLOAD: the constructors initialise the objects, so the bytes need no zeroing at reset.
alignas(App) __attribute__((section(".ccm_noinit.app"))) std::byte app_storage[sizeof(App)];
alignas(Measure) __attribute__((section(".ccm_noinit.measure"))) std::byte measure_storage[sizeof(Measure)];
alignas(Correct) __attribute__((section(".ccm_noinit.correct"))) std::byte correct_storage[sizeof(Correct)];

}  // namespace

extern "C" [[noreturn]] void firmware_main() {
  const board::ClockRates rates = board::clock_rates();
  board::systick::start(rates.core_hz);

  board::FlashStorage flash;
  Storage storage(flash);
  board::AdcRangers rangers;
  // On failure every read reports kFailed, so every measurement reports kRangerFailure.
  (void)rangers.start(rates.apb2_hz);
  board::camera.start();
  Measure& measure = *::new (static_cast<void*>(measure_storage)) Measure(board::camera, rangers);
  Correct& correct = *::new (static_cast<void*>(correct_storage)) Correct();

  kincal::app::AppConfig config;
  config.fd = false;  // bxCAN: classic CAN only
  if (board::clock_status != board::ClockStatus::kPll168MHz)
    config.board_error_flags |= kincal::shared::error_flag::kClockFallback;

  // kWaitingForBus is normal with an idle-less bus at start; the controller then joins by itself.
  // Any other failure leaves CAN off, and with it the only way to report anything.
  (void)board::can1.start(rates.apb1_hz);

  App& app = *::new (static_cast<void*>(app_storage)) App(config, board::can1, storage, measure, correct);
  app.start(board::systick::now_us());

  // Started last, so that start-up (parameter loading included) is not timed; it cannot be
  // stopped. On kUpdateTimedOut the LSI does not run and there is no watchdog: nothing can say so.
  (void)board::watchdog::start();
  std::uint32_t rx_dropped_seen = 0;
  for (;;) {
    board::watchdog::refresh();  // once per pass: a pass that hangs for ~100 ms resets the MCU
    kincal::shared::CanFrame frame;
    for (std::size_t i = 0; i < board::Bxcan::kRxRingFrames && board::can1.try_receive(frame); ++i)
      app.on_frame(frame, board::systick::now_us());
    const std::uint32_t rx_dropped = board::can1.rx_dropped_frames();
    if (rx_dropped != rx_dropped_seen) {
      rx_dropped_seen = rx_dropped;
      app.note_rx_overflow();
    }
    app.poll(board::systick::now_us());

    __asm volatile("cpsid i" ::: "memory");
    if (!board::can1.rx_pending() && app.next_deadline_us() > board::systick::now_us()) __asm volatile("wfi");
    __asm volatile("cpsie i" ::: "memory");
  }
}

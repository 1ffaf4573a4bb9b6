// The platform camera on the STM32F407's DCMI (RM0090 section 15), register level: the
// app::CameraPort (firmware/app/ports.hpp) of the STM32 image. Proven by compilation only: no
// board or sensor was at hand, and QEMU has no DCMI.
//
// Sensor assumed: a monochrome parallel sensor delivering 8-bit grey pixels (one byte per pixel),
// kWidthPx x kHeightPx, with hardware HSYNC/VSYNC (e.g. an MT9V034-class global-shutter sensor
// cropped to VGA). Its own set-up (I2C/SCCB registers: resolution, Y8 output, exposure, pixel
// clock) is the sensor's business and is not done here. A YUV422 or RGB565 sensor needs the row
// converted to luma (firmware/core/pixel_formats) in read_row, and lines of 2 bytes per pixel.
// Wiring (all AF13): HSYNC PA4, PIXCLK PA6, VSYNC PB7, D0-D3 PC6-PC9, D4 PC11, D5 PB6, D6 PE5,
// D7 PE6 -- clear of CAN1 (PB8/PB9) and the rangers' ADC pins (PA1-PA3, PB0).
// Signal polarities (DCMI_CR): pixel data sampled on PIXCLK's rising edge, HSYNC and VSYNC
// active low (the data valid while they are high); change kCr* below for another sensor.
//
// Capture: snapshot mode (DCMI_CR.CM): begin_frame arms one frame; the DCMI delivers it into DMA2
// stream 1 (channel 1), double-buffer mode, one line per transfer (kWidthPx / 4 words), into a
// ring of kLineSlots line buffers in SRAM (the DMA cannot reach the CCM RAM). The stream's
// transfer-complete interrupt (DMA2_Stream1_IRQHandler, at mmio::kIrqPriority with CAN and
// SysTick, so none nests on another) counts the line and points the buffer register the DMA has
// just left at the slot after next. read_row copies the oldest unread line, so the main loop may
// fall behind by up to kLineSlots - 2 lines (at 168 MHz the labeler needs ~13 us per VGA line,
// a 25 MHz pixel clock delivers one every ~32 us: it keeps up on average, and the ring absorbs a
// CAN burst or a correction).
// Exposure time: the sensor exposes during the frame period before readout; exposure_us =
// begin_frame's clock + kExposureToMidReadoutUs, an estimate for a sensor running at
// kFramePeriodUs: set both for the sensor's configuration.
//
// ISR safety: begin_frame/read_row are for the main loop; the ISR writes lines_done_ and
// overrun_ (32-bit, single writer), the main loop lines_read_. Memory: kLineSlots x kWidthPx
// bytes (10 KiB) of line buffers plus a few words; the one instance is `camera` (below), which
// the interrupt handler serves. Cost: read_row one 640-byte copy; the ISR ~30 cycles per line.
// Failure modes (every one ends the frame; begin_frame starts the next one):
//   - start(): none it can detect (a missing sensor shows as rows that never come).
//   - begin_frame(): kFailed if start() was not called or the stream did not stop within its
//     bounded wait.
//   - read_row(): kPending while the next line has not arrived; kFailed on a DMA transfer or
//     FIFO error, a DCMI overrun or synchronisation error, a ring overrun (the main loop fell
//     kLineSlots - 2 lines behind), or a read past the last line. The measurement step turns a
//     line that never comes into kCameraFailure after its own timeout.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "firmware/app/ports.hpp"

namespace kincal::stm32f4 {

class DcmiCamera {
 public:
  static constexpr std::uint16_t kWidthPx = 640;
  static constexpr std::uint16_t kHeightPx = 480;
  static constexpr std::size_t kLineSlots = 16;
  static constexpr std::uint32_t kFramePeriodUs = 33333;  // 30 frames per second
  static constexpr std::uint32_t kExposureToMidReadoutUs = kFramePeriodUs;
  static_assert(kWidthPx % 4 == 0, "the DMA moves whole 32-bit words of four pixels");
  static_assert(kLineSlots >= 4 && (kLineSlots & (kLineSlots - 1)) == 0, "a power of two: slot = line % slots");

  constexpr DcmiCamera() = default;

  // Clocks, pins, the DCMI (snapshot, 8-bit, hardware synchronisation) and the DMA stream's
  // fixed settings; enables the interrupt. Call once, before the first frame.
  void start();

  std::uint16_t width_px() const { return kWidthPx; }
  std::uint16_t height_px() const { return kHeightPx; }
  app::CaptureStatus begin_frame(app::FrameUse use, std::uint64_t& exposure_us);
  app::CaptureStatus read_row(std::span<std::uint8_t> row);

  // From DMA2_Stream1_IRQHandler only.
  void on_dma_interrupt();

 private:
  bool started_ = false;
  bool frame_armed_ = false;
  volatile std::uint32_t lines_done_ = 0;  // written by the ISR
  volatile bool overrun_ = false;          // written by the ISR: a DMA error or an unread slot reused
  volatile std::uint32_t lines_read_ = 0;  // written by the main loop, read by the ISR
  alignas(4) std::array<std::array<std::uint8_t, kWidthPx>, kLineSlots> lines_{};
};

extern DcmiCamera camera;

static_assert(app::CameraPort<DcmiCamera>);

}  // namespace kincal::stm32f4

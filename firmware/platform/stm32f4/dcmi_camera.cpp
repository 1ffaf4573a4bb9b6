#include "firmware/platform/stm32f4/dcmi_camera.hpp"

#include "firmware/platform/stm32f4/mmio.hpp"
#include "firmware/platform/stm32f4/systick_clock.hpp"

namespace kincal::stm32f4 {

constinit DcmiCamera camera;

namespace {

using mmio::reg;

// DCMI (RM0090 15.8).
constexpr std::uintptr_t kDcmi = 0x50050000u;
constexpr std::uintptr_t kDcmiCr = kDcmi + 0x00u, kDcmiRis = kDcmi + 0x08u, kDcmiIcr = kDcmi + 0x14u;
constexpr std::uintptr_t kDcmiDr = kDcmi + 0x28u;
constexpr std::uint32_t kCrCapture = 1u << 0, kCrSnapshot = 1u << 1, kCrPckpolRising = 1u << 5;
constexpr std::uint32_t kCrHspolHigh = 0, kCrVspolHigh = 0;  // HSYNC/VSYNC low = blanking: data while high
constexpr std::uint32_t kCrEnable = 1u << 14;                // EDM = 00: 8-bit data; FCRC = 00: every frame
constexpr std::uint32_t kRisOverrun = 1u << 1, kRisSyncError = 1u << 2;
constexpr std::uint32_t kIcrAll = 0x1Fu;

// DMA2 stream 1 (RM0090 10.5): channel 1 is the DCMI.
constexpr std::uintptr_t kDma2 = 0x40026400u;
constexpr std::uintptr_t kLisr = kDma2 + 0x00u, kLifcr = kDma2 + 0x08u;
constexpr std::uintptr_t kS1cr = kDma2 + 0x28u, kS1ndtr = kDma2 + 0x2Cu, kS1par = kDma2 + 0x30u;
constexpr std::uintptr_t kS1m0ar = kDma2 + 0x34u, kS1m1ar = kDma2 + 0x38u, kS1fcr = kDma2 + 0x3Cu;
constexpr std::uint32_t kS1FlagFifoError = 1u << 6, kS1FlagDirectError = 1u << 8, kS1FlagTransferError = 1u << 9;
constexpr std::uint32_t kS1FlagHalf = 1u << 10, kS1FlagComplete = 1u << 11;
constexpr std::uint32_t kS1FlagsAll =
    kS1FlagFifoError | kS1FlagDirectError | kS1FlagTransferError | kS1FlagHalf | kS1FlagComplete;
constexpr std::uint32_t kSxcrEnable = 1u << 0, kSxcrDirectErrorIe = 1u << 1, kSxcrTransferErrorIe = 1u << 2;
constexpr std::uint32_t kSxcrCompleteIe = 1u << 4, kSxcrCircular = 1u << 8, kSxcrMemoryIncrement = 1u << 10;
constexpr std::uint32_t kSxcrPeripheralWord = 2u << 11, kSxcrMemoryWord = 2u << 13, kSxcrPriorityHigh = 2u << 16;
constexpr std::uint32_t kSxcrDoubleBuffer = 1u << 18, kSxcrCurrentTarget = 1u << 19, kSxcrChannel1 = 1u << 25;
constexpr std::uint32_t kSxcrSettings = kSxcrDirectErrorIe | kSxcrTransferErrorIe | kSxcrCompleteIe | kSxcrCircular |
                                        kSxcrMemoryIncrement | kSxcrPeripheralWord | kSxcrMemoryWord |
                                        kSxcrPriorityHigh | kSxcrDoubleBuffer | kSxcrChannel1;
constexpr std::uint32_t kSxfcrFifoMode = 1u << 2, kSxfcrThresholdFull = 3u;

constexpr std::uintptr_t kRccAhb2enr = 0x40023834u;
constexpr std::uint32_t kAhb1GpioC = 1u << 2, kAhb1GpioE = 1u << 4, kAhb1Dma2 = 1u << 22, kAhb2Dcmi = 1u << 0;
constexpr std::uintptr_t kGpioC = 0x40020800u, kGpioE = 0x40021000u;
constexpr std::uint32_t kAfDcmi = 13;
constexpr unsigned kIrqDma2Stream1 = 57;

// A stream being disabled finishes its current beat first; 10,000 reads are far more than that.
constexpr std::uint32_t kStreamStopReads = 10000;

std::uint32_t slot_address(const std::array<std::uint8_t, DcmiCamera::kWidthPx>& slot) {
  return static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(slot.data()));
}

}  // namespace

void DcmiCamera::start() {
  mmio::enable_clock(mmio::kRccAhb1enr, mmio::kAhb1GpioA | mmio::kAhb1GpioB | kAhb1GpioC | kAhb1GpioE | kAhb1Dma2);
  mmio::enable_clock(kRccAhb2enr, kAhb2Dcmi);
  const auto af = [](std::uintptr_t port, unsigned pin) {
    mmio::configure_pin(port, pin, mmio::PinMode::kAlternate, mmio::Pull::kNone, kAfDcmi);
  };
  af(mmio::kGpioA, 4);                                               // HSYNC
  af(mmio::kGpioA, 6);                                               // PIXCLK
  af(mmio::kGpioB, 7);                                               // VSYNC
  for (const unsigned pin : {6u, 7u, 8u, 9u, 11u}) af(kGpioC, pin);  // D0-D4
  af(mmio::kGpioB, 6);                                               // D5
  af(kGpioE, 5);                                                     // D6
  af(kGpioE, 6);                                                     // D7

  reg(kDcmiCr) = 0;
  reg(kDcmiCr) = kCrSnapshot | kCrPckpolRising | kCrHspolHigh | kCrVspolHigh;
  reg(kDcmiCr) = reg(kDcmiCr) | kCrEnable;
  reg(kS1cr) = 0;
  reg(kS1par) = static_cast<std::uint32_t>(kDcmiDr);
  reg(kS1fcr) = kSxfcrFifoMode | kSxfcrThresholdFull;
  mmio::enable_irq(kIrqDma2Stream1, mmio::kIrqPriority);
  started_ = true;
}

app::CaptureStatus DcmiCamera::begin_frame(app::FrameUse, std::uint64_t& exposure_us) {
  frame_armed_ = false;
  if (!started_) return app::CaptureStatus::kFailed;
  reg(kDcmiCr) = reg(kDcmiCr) & ~kCrCapture;
  reg(kS1cr) = reg(kS1cr) & ~kSxcrEnable;
  bool stopped = false;
  for (std::uint32_t i = 0; i < kStreamStopReads && !stopped; ++i) stopped = (reg(kS1cr) & kSxcrEnable) == 0;
  if (!stopped) return app::CaptureStatus::kFailed;
  reg(kLifcr) = kS1FlagsAll;
  reg(kDcmiIcr) = kIcrAll;
  lines_done_ = 0;
  lines_read_ = 0;
  overrun_ = false;
  reg(kS1ndtr) = kWidthPx / 4u;
  reg(kS1m0ar) = slot_address(lines_[0]);
  reg(kS1m1ar) = slot_address(lines_[1]);
  reg(kS1cr) = kSxcrSettings;
  reg(kS1cr) = kSxcrSettings | kSxcrEnable;
  reg(kDcmiCr) = reg(kDcmiCr) | kCrCapture;  // snapshot: the DCMI clears it after one frame
  exposure_us = systick::now_us() + kExposureToMidReadoutUs;
  frame_armed_ = true;
  return app::CaptureStatus::kOk;
}

app::CaptureStatus DcmiCamera::read_row(std::span<std::uint8_t> row) {
  if (!frame_armed_ || overrun_ || lines_read_ >= kHeightPx || row.size() != kWidthPx ||
      (reg(kDcmiRis) & (kRisOverrun | kRisSyncError)) != 0) {
    frame_armed_ = false;
    return app::CaptureStatus::kFailed;
  }
  if (lines_read_ >= lines_done_) return app::CaptureStatus::kPending;
  const auto& slot = lines_[lines_read_ % kLineSlots];
  for (std::size_t i = 0; i < kWidthPx; ++i) row[i] = slot[i];
  // The ISR marks an overrun before it points the DMA at a slot not yet read; checking after the
  // copy catches one that happened during it.
  if (overrun_) {
    frame_armed_ = false;
    return app::CaptureStatus::kFailed;
  }
  lines_read_ = lines_read_ + 1;
  return app::CaptureStatus::kOk;
}

void DcmiCamera::on_dma_interrupt() {
  const std::uint32_t flags = reg(kLisr) & kS1FlagsAll;
  reg(kLifcr) = flags;
  if ((flags & (kS1FlagTransferError | kS1FlagDirectError | kS1FlagFifoError)) != 0) overrun_ = true;
  if ((flags & kS1FlagComplete) == 0) return;
  const std::uint32_t done = lines_done_ + 1;  // line `done - 1` has landed; the DMA now fills line `done`
  // The buffer register the DMA just left gets line done + 1, whose slot must have been read.
  const std::uint32_t next = done + 1;
  if (next - lines_read_ >= kLineSlots) overrun_ = true;
  const std::uint32_t address = slot_address(lines_[next % kLineSlots]);
  if ((reg(kS1cr) & kSxcrCurrentTarget) != 0) {
    reg(kS1m0ar) = address;  // the DMA writes through M1AR now
  } else {
    reg(kS1m1ar) = address;
  }
  lines_done_ = done;
}

}  // namespace kincal::stm32f4

extern "C" void DMA2_Stream1_IRQHandler() { kincal::stm32f4::camera.on_dma_interrupt(); }

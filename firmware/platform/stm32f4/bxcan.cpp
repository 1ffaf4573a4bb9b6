#include "firmware/platform/stm32f4/bxcan.hpp"

#include "firmware/platform/stm32f4/mmio.hpp"

namespace kincal::stm32f4 {

constinit Bxcan can1;

// The timings the header states, checked.
static_assert(kBitTiming42MHz.prescaler * tq_per_bit(kBitTiming42MHz) * kCanBitRate == 42000000u);
static_assert(kBitTiming16MHz.prescaler * tq_per_bit(kBitTiming16MHz) * kCanBitRate == 16000000u);
static_assert(btr_of(kBitTiming42MHz) == 0x001A0002u && sample_point_permille(kBitTiming42MHz) == 857u);
static_assert(sample_point_permille(kBitTiming16MHz) == 875u);
static_assert(kFilterId == 0x20000000u && kFilterMask == 0xF0000004u);

// Mailbox packing round-trips, and what it refuses.
constexpr bool round_trips(std::uint32_t id, bool extended, std::uint8_t length) {
  shared::CanFrame sent;
  sent.id = id;
  sent.extended = extended;
  sent.length = length;
  for (std::size_t i = 0; i < length; ++i) sent.data[i] = static_cast<std::uint8_t>(0x11u * (i + 1u));
  MailboxWords words;
  if (!encode_tx(sent, words)) return false;
  shared::CanFrame received;
  decode_rx(words, received);
  return received.id == sent.id && received.extended == sent.extended && received.length == sent.length &&
         received.data == sent.data && !received.fd;
}
static_assert(round_trips(0x100, false, 8) && round_trips(0x7FF, false, 0) && round_trips(0x1ABCDEF0, true, 5));
static_assert(!round_trips(0x800, false, 1) && !round_trips(0x20000000, true, 1) && !round_trips(0x100, false, 9));
constexpr bool refuses_fd() {
  shared::CanFrame frame;
  frame.fd = true;
  MailboxWords words;
  return !encode_tx(frame, words);
}
static_assert(refuses_fd());

namespace {

using mmio::reg;

// CAN1 registers (RM0090 32.9).
constexpr std::uintptr_t kCan1 = 0x40006400u;
constexpr std::uintptr_t kMcr = kCan1 + 0x000u, kMsr = kCan1 + 0x004u, kTsr = kCan1 + 0x008u;
constexpr std::uintptr_t kRf0r = kCan1 + 0x00Cu, kIer = kCan1 + 0x014u, kEsr = kCan1 + 0x018u;
constexpr std::uintptr_t kBtr = kCan1 + 0x01Cu;
constexpr std::uintptr_t kRx0Mailbox = kCan1 + 0x1B0u;
constexpr std::uintptr_t kFmr = kCan1 + 0x200u, kFm1r = kCan1 + 0x204u, kFs1r = kCan1 + 0x20Cu;
constexpr std::uintptr_t kFfa1r = kCan1 + 0x214u, kFa1r = kCan1 + 0x21Cu;
constexpr std::uintptr_t kF0r1 = kCan1 + 0x240u, kF0r2 = kCan1 + 0x244u;
constexpr std::uintptr_t tx_mailbox(std::uint32_t n) { return kCan1 + 0x180u + 0x10u * n; }

constexpr std::uint32_t kMcrInrq = 1u << 0, kMcrTxfp = 1u << 2, kMcrRflm = 1u << 3, kMcrAbom = 1u << 6;
constexpr std::uint32_t kMcrDbf = 1u << 16;
constexpr std::uint32_t kMsrInak = 1u << 0, kMsrSlak = 1u << 1, kMsrErri = 1u << 2;
constexpr std::uint32_t kTsrTmeAll = 7u << 26;
constexpr std::uint32_t kTirTxrq = 1u << 0;
constexpr std::uint32_t kRf0rFmp0 = 3u << 0, kRf0rFovr0 = 1u << 4, kRf0rRfom0 = 1u << 5;
constexpr std::uint32_t kIerFmpie0 = 1u << 1, kIerFovie0 = 1u << 3, kIerEpvie = 1u << 9, kIerBofie = 1u << 10;
constexpr std::uint32_t kIerErrie = 1u << 15;
constexpr std::uint32_t kEsrEpvf = 1u << 1, kEsrBoff = 1u << 2;
constexpr std::uint32_t kFmrFinit = 1u << 0;
constexpr std::uint32_t kBank0 = 1u << 0;

// Mode changes take effect after the frame on the bus ends, or once the bus shows 11 recessive
// bits: at most ~135 us at 1 Mbit/s. 200,000 polls are >= 4 ms at 168 MHz, longer on the HSI.
constexpr std::uint32_t kModeWaitLimit = 200000;
// RFOM0 clears once the FIFO output mailbox is released: a few APB1 cycles.
constexpr std::uint32_t kReleaseWaitLimit = 64;

bool wait_for(std::uintptr_t address, std::uint32_t mask, std::uint32_t value, std::uint32_t limit) {
  for (std::uint32_t i = 0; i < limit; ++i)
    if ((reg(address) & mask) == value) return true;
  return false;
}

}  // namespace

BxcanStatus Bxcan::start(std::uint32_t apb1_hz) {
  const BitTiming* timing = bit_timing_for(apb1_hz);
  if (timing == nullptr) return BxcanStatus::kUnsupportedClock;

  mmio::enable_clock(mmio::kRccAhb1enr, mmio::kAhb1GpioB);
  mmio::enable_clock(mmio::kRccApb1enr, mmio::kApb1Can1);
  mmio::configure_pin(mmio::kGpioB, 8, mmio::PinMode::kAlternate, mmio::Pull::kUp, 9);    // CAN1_RX
  mmio::configure_pin(mmio::kGpioB, 9, mmio::PinMode::kAlternate, mmio::Pull::kNone, 9);  // CAN1_TX

  // Out of sleep (the reset state), into initialisation: only there is BTR writable.
  reg(kMcr) = kMcrInrq | kMcrDbf;
  if (!wait_for(kMsr, kMsrInak | kMsrSlak, kMsrInak, kModeWaitLimit)) return BxcanStatus::kNoInitMode;
  reg(kBtr) = btr_of(*timing);
  reg(kMcr) = kMcrInrq | kMcrDbf | kMcrAbom | kMcrTxfp | kMcrRflm;

  // Filter bank 0: 32-bit identifier/mask, to FIFO 0. The filter registers belong to CAN1.
  mmio::set_bits(kFmr, kFmrFinit);
  mmio::clear_bits(kFa1r, kBank0);
  mmio::clear_bits(kFm1r, kBank0);   // mask mode
  mmio::set_bits(kFs1r, kBank0);     // 32-bit scale
  mmio::clear_bits(kFfa1r, kBank0);  // FIFO 0
  reg(kF0r1) = kFilterId;
  reg(kF0r2) = kFilterMask;
  mmio::set_bits(kFa1r, kBank0);
  mmio::clear_bits(kFmr, kFmrFinit);

  reg(kIer) = kIerFmpie0 | kIerFovie0 | kIerEpvie | kIerBofie | kIerErrie;
  mmio::enable_irq(mmio::kIrqCan1Rx0, mmio::kIrqPriority);
  mmio::enable_irq(mmio::kIrqCan1Sce, mmio::kIrqPriority);

  mmio::clear_bits(kMcr, kMcrInrq);
  if (!wait_for(kMsr, kMsrInak, 0, kModeWaitLimit)) return BxcanStatus::kWaitingForBus;
  return BxcanStatus::kOk;
}

bool Bxcan::try_send(const shared::CanFrame& frame) {
  MailboxWords words;
  if (!encode_tx(frame, words)) {
    ++refused_tx_;
    return true;  // consumed: see the header, "refused for good"
  }
  const std::uint32_t tsr = reg(kTsr);
  if ((tsr & kTsrTmeAll) == 0) return false;
  // With a mailbox free, CODE[25:24] names the next free one.
  const std::uint32_t box = (tsr >> 24) & 3u;
  if (box > 2) return false;
  const std::uintptr_t mailbox = tx_mailbox(box);
  reg(mailbox + 0x4u) = words.dtr;
  reg(mailbox + 0x8u) = words.dlr;
  reg(mailbox + 0xCu) = words.dhr;
  reg(mailbox) = words.ir | kTirTxrq;  // last: requests the transmission
  return true;
}

app::CanHealth Bxcan::health() const {
  const std::uint32_t esr = reg(kEsr);
  app::CanHealth h;
  h.bus_off = (esr & kEsrBoff) != 0;
  h.error_passive = h.bus_off || (esr & kEsrEpvf) != 0;
  h.tx_error_count = h.bus_off ? std::uint8_t{255} : static_cast<std::uint8_t>(esr >> 16);
  h.bus_off_events = bus_off_events_.load(std::memory_order_relaxed);
  return h;
}

bool Bxcan::try_receive(shared::CanFrame& out) {
  MailboxWords words;
  if (!rx_.pop(words)) return false;
  decode_rx(words, out);
  return true;
}

void Bxcan::on_rx0_interrupt() {
  for (std::size_t i = 0; i < kHardwareFifoFrames && (reg(kRf0r) & kRf0rFmp0) != 0; ++i) {
    MailboxWords words;
    words.ir = reg(kRx0Mailbox + 0x0u);
    words.dtr = reg(kRx0Mailbox + 0x4u);
    words.dlr = reg(kRx0Mailbox + 0x8u);
    words.dhr = reg(kRx0Mailbox + 0xCu);
    (void)rx_.push(words);    // a full ring drops and counts the frame
    reg(kRf0r) = kRf0rRfom0;  // release the output mailbox (the other bits are write-1-to-clear)
    if (!wait_for(kRf0r, kRf0rRfom0, 0, kReleaseWaitLimit)) break;
  }
  if ((reg(kRf0r) & kRf0rFovr0) != 0) {
    reg(kRf0r) = kRf0rFovr0;
    fifo_overruns_.store(fifo_overruns_.load(std::memory_order_relaxed) + 1u, std::memory_order_relaxed);
  }
}

void Bxcan::on_sce_interrupt() {
  // Acknowledge first, then read: a state change after the read raises the interrupt again.
  reg(kMsr) = kMsrErri;
  const bool bus_off = (reg(kEsr) & kEsrBoff) != 0;
  // A fresh bus-off always passes through error passive first (recovery resets TEC to 0), and
  // that entry interrupts with BOFF clear, so a transition seen here is one bus-off event.
  if (bus_off && !in_bus_off_)
    bus_off_events_.store(bus_off_events_.load(std::memory_order_relaxed) + 1u, std::memory_order_relaxed);
  in_bus_off_ = bus_off;
}

}  // namespace kincal::stm32f4

extern "C" void CAN1_RX0_IRQHandler() { kincal::stm32f4::can1.on_rx0_interrupt(); }
extern "C" void CAN1_SCE_IRQHandler() { kincal::stm32f4::can1.on_sce_interrupt(); }

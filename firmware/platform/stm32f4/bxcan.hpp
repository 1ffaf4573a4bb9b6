// CAN1 of the STM32F407 (bxCAN, RM0090 section 32), register level and interrupt driven: the
// platform's app::CanPort (firmware/app/ports.hpp) plus try_receive() for the main loop.
//
// Wiring: PB8 = CAN1_RX, PB9 = CAN1_TX, alternate function AF9, to a 3.3 V transceiver (e.g. an
// SN65HVD230). PB8 gets the internal pull-up, so an unconnected RX reads recessive.
// Bit timing, 1 Mbit/s classic CAN (bxCAN has no CAN FD):
//   APB1 = 42 MHz (the PLL clock of clock.cpp): BRP = 3 -> tq = 71.4 ns, 14 tq per bit =
//     1 (sync) + TS1 11 + TS2 2, SJW 1 tq; sample point 12/14 = 85.7 % (CiA 301 asks 75-90 %
//     at 1 Mbit/s, 87.5 % nominal: 14 tq cannot place it nearer). BTR = 0x001A0002.
//   APB1 = 16 MHz (clock.cpp fell back to the HSI): BRP = 1, 16 tq = 1 + 13 + 2, SJW 1 tq,
//     sample point 87.5 %. The HSI's +-1 % is outside CAN's oscillator tolerance at 1 Mbit/s
//     (about 0.3 % for SJW = 1 tq at this bit length): on the fall-back clock the platform may not
//     hold the bus; the heartbeat's kClockFallback flag says so, if it gets through.
// Controller set-up: automatic bus-off management (ABOM: after bus-off the controller rejoins by
// itself after 128 x 11 recessive bits, >= 1.4 ms at 1 Mbit/s), automatic retransmission,
// transmit priority by request order (TXFP: the three mailboxes leave in the order try_send()
// filled them, so ISO-TP consecutive frames never overtake each other), receive FIFO locked on
// overrun (RFLM: the oldest three frames are kept, newer ones are dropped and counted), frozen
// while a debugger halts the core (DBF).
// Filter: bank 0, 32-bit mask mode, to FIFO 0: standard data or remote frames whose 11-bit ID is
// in the protocol block shared::can_id::kBlockFirst..kBlockLast (0x100..0x17F: ID 0x100, mask
// 0x780, IDE must be 0). Everything else never reaches the CPU. A remote frame is delivered as a
// frame of length 0 (as the native SocketCAN port does), which the application rejects with an
// ErrorReport like any wrong-length frame.
// Interrupts (both at mmio::kIrqPriority, the same as SysTick, so neither nests on the other):
//   CAN1_RX0_IRQHandler   FIFO 0 pending or overrun: moves up to 3 frames into the RX ring.
//   CAN1_SCE_IRQHandler   entry into error passive or bus-off: counts bus-off entries.
//
// ISR safety: try_send(), health(), try_receive(), rx_pending() and the counters are for the main
// loop. The RX ring is single-producer (RX0 ISR) / single-consumer (main loop), lock-free
// (spsc_ring.hpp); the counters are 32-bit atomics written by one side each. try_send() is the only
// writer of the TX mailboxes; no ISR touches them.
// Memory: the RX ring, kRxRingFrames x 16 bytes (the raw mailbox words), plus 16 bytes. The one
// instance is `can1` (below): the interrupt handlers serve it and only it.
// Cost: RX0 ISR about 40 cycles per frame plus entry; SCE ISR about 20 cycles; try_send() 6
// register accesses; try_receive() one ring pop and the unpacking of one frame.
// Failure modes (each defined, none blocks):
//   - start(): kUnsupportedClock (no bit timing for that APB1 clock: the controller stays off),
//     kNoInitMode (the controller never acknowledged initialisation), kWaitingForBus (configured,
//     but the bus has not shown 11 recessive bits within the bounded wait: the controller joins by
//     itself as soon as it does; the port works normally from then on).
//   - try_send(): false when all three mailboxes are busy (the application keeps the frame and
//     retries). A frame this controller cannot send -- CAN FD, more than 8 bytes, an identifier
//     out of range -- is refused for good: try_send() returns TRUE (consumed) without sending and
//     counts it in refused_tx_frames(). Returning false would make the application retry it
//     forever and stall everything queued behind it; the application configured for classic CAN
//     (AppConfig::fd = false) never produces such a frame.
//   - No other node acknowledging (alone on the bus): the controller retransmits, goes error
//     passive and keeps the three oldest frames in its mailboxes; try_send() then returns false
//     and the application's queue fills (its kTxOverflow flag).
//   - Received frames beyond the ring (the main loop stalled) or beyond the 3-frame hardware FIFO
//     (the RX0 ISR could not run, e.g. the CPU stalled on a flash erase, see flash_storage.hpp)
//     are dropped and counted in rx_dropped_frames() (at least one per hardware overrun event).
//   - Bus-off: counted on entry by the SCE interrupt; recovery is automatic (ABOM). Frames already
//     in the mailboxes go out after recovery. A bus-off that begins and ends while the CPU cannot
//     take interrupts (flash erase) is not counted.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>

#include "firmware/app/ports.hpp"
#include "firmware/platform/stm32f4/spsc_ring.hpp"
#include "shared/can_frame.hpp"
#include "shared/protocol.hpp"

namespace kincal::stm32f4 {

// One bit time in time quanta (tq): 1 sync tq + TS1 + TS2; the sample point is after TS1.
struct BitTiming {
  std::uint16_t prescaler = 1;  // BRP + 1: APB1 clocks per tq
  std::uint8_t ts1_tq = 1;      // time segment 1 (propagation + phase 1), 1..16
  std::uint8_t ts2_tq = 1;      // time segment 2 (phase 2), 1..8
  std::uint8_t sjw_tq = 1;      // resynchronisation jump width, 1..4, <= ts2_tq
};

inline constexpr std::uint32_t kCanBitRate = 1000000;
inline constexpr BitTiming kBitTiming42MHz{3, 11, 2, 1};
inline constexpr BitTiming kBitTiming16MHz{1, 13, 2, 1};

constexpr std::uint32_t tq_per_bit(const BitTiming& t) { return 1u + t.ts1_tq + t.ts2_tq; }
constexpr std::uint32_t sample_point_permille(const BitTiming& t) { return 1000u * (1u + t.ts1_tq) / tq_per_bit(t); }
// CAN_BTR (RM0090 32.9.2): SJW[25:24], TS2[22:20], TS1[19:16], BRP[9:0], each field "value - 1";
// loop-back and silent mode off.
constexpr std::uint32_t btr_of(const BitTiming& t) {
  return (std::uint32_t{t.sjw_tq} - 1u) << 24 | (std::uint32_t{t.ts2_tq} - 1u) << 20 |
         (std::uint32_t{t.ts1_tq} - 1u) << 16 | (std::uint32_t{t.prescaler} - 1u);
}
// The timing for an APB1 clock, or nullptr if there is none (the controller then stays off).
constexpr const BitTiming* bit_timing_for(std::uint32_t apb1_hz) {
  if (apb1_hz == 42000000) return &kBitTiming42MHz;
  if (apb1_hz == 16000000) return &kBitTiming16MHz;
  return nullptr;
}

// The four words of a bxCAN mailbox: TIxR/TDTxR/TDLxR/TDHxR for transmit, RIxR/RDTxR/RDLxR/RDHxR
// for receive (RM0090 32.9.3); the ring stores received frames in this raw form so the RX ISR
// only copies four words.
struct MailboxWords {
  std::uint32_t ir = 0;   // identifier: STID[31:21] or EXID[31:3], IDE[2], RTR[1] (TXRQ[0] on TX)
  std::uint32_t dtr = 0;  // DLC[3:0] (and on RX the filter match index and time stamp)
  std::uint32_t dlr = 0;  // data bytes 0..3, byte 0 in bits 7:0
  std::uint32_t dhr = 0;  // data bytes 4..7
};

inline constexpr std::uint32_t kMailboxIde = 1u << 2;
inline constexpr std::uint32_t kMailboxRtr = 1u << 1;

// Packs a frame for a transmit mailbox (without TXRQ); false if bxCAN cannot send it (CAN FD,
// more than 8 bytes, an identifier beyond 11 or 29 bits).
constexpr bool encode_tx(const shared::CanFrame& frame, MailboxWords& out) {
  if (frame.fd || frame.length > shared::CanFrame::kMaxClassicBytes) return false;
  if (frame.id > (frame.extended ? shared::CanFrame::kMaxExtendedId : shared::CanFrame::kMaxStandardId)) return false;
  out.ir = frame.extended ? (frame.id << 3) | kMailboxIde : frame.id << 21;
  out.dtr = frame.length;
  out.dlr = out.dhr = 0;
  for (std::size_t i = 0; i < frame.length; ++i) {
    std::uint32_t& word = i < 4 ? out.dlr : out.dhr;
    word |= std::uint32_t{frame.data[i]} << (8u * (i % 4u));
  }
  return true;
}

// Unpacks a received mailbox. A DLC of 9..15 carries 8 bytes (ISO 11898-1); a remote frame
// becomes a frame of length 0.
constexpr void decode_rx(const MailboxWords& in, shared::CanFrame& out) {
  out = shared::CanFrame{};
  out.extended = (in.ir & kMailboxIde) != 0;
  out.id = out.extended ? in.ir >> 3 : in.ir >> 21;
  const std::uint32_t dlc = in.dtr & 0xFu;
  out.length = (in.ir & kMailboxRtr) != 0 ? 0 : static_cast<std::uint8_t>(dlc > 8 ? 8 : dlc);
  for (std::size_t i = 0; i < out.length; ++i)
    out.data[i] = static_cast<std::uint8_t>((i < 4 ? in.dlr : in.dhr) >> (8u * (i % 4u)));
}

// Filter bank 0 (32-bit mask mode): the protocol block as identifier + mask over CAN_FiR1/FiR2,
// whose layout is that of RIxR. The block must be a power-of-two-sized, aligned range of IDs.
inline constexpr std::uint32_t kProtocolIdSpan = shared::can_id::kBlockLast - shared::can_id::kBlockFirst + 1u;
static_assert((kProtocolIdSpan & (kProtocolIdSpan - 1u)) == 0 && shared::can_id::kBlockFirst % kProtocolIdSpan == 0,
              "one mask filter covers the protocol block only if it is an aligned power-of-two range");
inline constexpr std::uint32_t kFilterId = shared::can_id::kBlockFirst << 21;
inline constexpr std::uint32_t kFilterMask =
    ((~(kProtocolIdSpan - 1u) & shared::CanFrame::kMaxStandardId) << 21) | kMailboxIde;

enum class [[nodiscard]] BxcanStatus : std::uint8_t{
    kOk,                // on the bus
    kWaitingForBus,     // configured; joins when the bus shows 11 recessive bits
    kNoInitMode,        // the controller did not acknowledge initialisation mode: left off
    kUnsupportedClock,  // no bit timing for this APB1 clock: left off
};

class Bxcan {
 public:
  static constexpr std::size_t kRxRingFrames = 64;  // ~8.6 ms of a saturated 1 Mbit/s bus
  static constexpr std::size_t kHardwareFifoFrames = 3;

  constexpr Bxcan() = default;
  Bxcan(const Bxcan&) = delete;
  Bxcan& operator=(const Bxcan&) = delete;

  // Clocks, pins, bit timing, filter and interrupts; then leaves initialisation mode. Call once,
  // from the main loop, with the APB1 clock clock.hpp reports.
  BxcanStatus start(std::uint32_t apb1_hz);

  // app::CanPort.
  bool try_send(const shared::CanFrame& frame);
  app::CanHealth health() const;

  // The oldest received frame, if any.
  bool try_receive(shared::CanFrame& out);
  bool rx_pending() const { return !rx_.empty(); }

  // Frames lost on reception: dropped by a full ring, plus one per hardware FIFO overrun event.
  std::uint32_t rx_dropped_frames() const { return rx_.overflows() + fifo_overruns_.load(std::memory_order_relaxed); }
  // Frames try_send() refused for good (CAN FD, > 8 bytes, bad identifier).
  std::uint32_t refused_tx_frames() const { return refused_tx_; }

  // Interrupt bodies: called by CAN1_RX0_IRQHandler and CAN1_SCE_IRQHandler only.
  void on_rx0_interrupt();
  void on_sce_interrupt();

 private:
  SpscRing<MailboxWords, kRxRingFrames> rx_;
  std::atomic<std::uint32_t> fifo_overruns_{0};   // written by the RX0 ISR only
  std::atomic<std::uint32_t> bus_off_events_{0};  // written by the SCE ISR only
  bool in_bus_off_ = false;                       // SCE ISR only
  std::uint32_t refused_tx_ = 0;                  // main loop only
};

static_assert(app::CanPort<Bxcan>);

// The controller: zero-initialised at load time (no constructor runs), started by start().
extern Bxcan can1;

}  // namespace kincal::stm32f4

// ISO 15765-2 (ISO-TP) transport over CAN and CAN FD: one endpoint of a normal-addressing,
// 11- or 29-bit ID pair, full duplex (one message in each direction at a time).
//
// What: segmentation (single, first, consecutive frames), reassembly, flow control (block size
// BS and separation time STmin, both announced and obeyed, FC WAIT and OVERFLOW), sequence-number
// checks, the N_Bs / N_Cr timeouts, classic frames (8 bytes, FF_DL up to 4095) and CAN FD frames
// (TX_DL up to 64, escape SF_DL and 32-bit FF_DL), optional padding (0xCC by default, as Linux
// can-isotp's CAN_ISOTP_TX_PADDING). It interoperates with the Linux kernel's can-isotp and
// can-utils' isotpsend/isotprecv (tested on a real kernel by tests/vm).
// Why in the core: pure protocol logic with no I/O, so the firmware, the host's loopback bus and
// the host's passive monitor run the very same code.
//
// Use: the owner moves frames. on_frame() takes every frame received on rx_id; next_frame()
// hands out the next frame to transmit on tx_id when one is due (call it whenever the CAN
// controller has room, and at least every STmin); check_timeouts() aborts stalled transfers;
// start_send() queues a message. Time is the caller's monotonic clock in microseconds.
//
// Memory: the two buffers are the owner's (IsoTpBuffers<kRx, kTx>, sizes fixed at compile time);
// the endpoint itself is ~100 bytes. No heap. A received message stays in message() until the
// next on_frame() call that starts another reception.
// Cost: on_frame/next_frame copy at most one frame's payload (<= 64 bytes); everything else O(1).
// Thread/ISR safety: not reentrant; one owner (e.g. the main loop) calls every member. Feed it
// from an ISR-filled queue, not from the ISR itself.
// Failure modes (IsoTpEvent, each also counted in stats()): malformed PCI or length (frame
// dropped), wrong sequence number (reception aborted), message longer than the receive buffer
// (FC OVERFLOW sent, reception aborted), N_Cr/N_Bs timeout, peer's FC OVERFLOW, more FC WAITs
// than max_wait_frames (transmission aborted). A fresh SF or FF during a reception restarts it, as
// the standard says. No input makes it read or write outside its buffers.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "shared/can_frame.hpp"

namespace kincal::core {

using shared::CanFrame;

struct IsoTpConfig {
  std::uint32_t tx_id = 0;                  // ID of our data frames and of our flow control
  std::uint32_t rx_id = 0;                  // ID of the peer's data frames and flow control
  bool extended_ids = false;                // 29-bit IDs
  std::uint8_t tx_dl = 8;                   // payload bytes per frame we send: 8, or a CAN FD length 12..64
  bool fd = false;                          // send CAN FD frames (required when tx_dl > 8)
  bool brs = false;                         // CAN FD bit-rate switch on our frames
  bool padding = false;                     // pad our frames to at least 8 bytes with pad_byte
  std::uint8_t pad_byte = 0xCC;             // Linux can-isotp's default pad content
  std::uint8_t block_size = 0;              // BS we announce: CFs between our FCs (0 = all at once)
  std::uint8_t st_min_raw = 0;              // STmin we announce, ISO encoding (0x00..0x7F ms, 0xF1..0xF9 x100 us)
  std::uint32_t n_bs_timeout_us = 1000000;  // how long we wait for the peer's FC
  std::uint32_t n_cr_timeout_us = 1000000;  // how long we wait for the peer's next CF
  std::uint8_t max_wait_frames = 8;         // FC WAIT frames tolerated in a row
  bool listen_only = false;                 // never send flow control (a passive bus monitor)
};

template <std::size_t kRxBytes, std::size_t kTxBytes>
struct IsoTpBuffers {
  static_assert(kRxBytes >= 8 && kTxBytes >= 8, "ISO-TP buffers must hold at least one frame");
  static_assert(kRxBytes <= 0xFFFFFFFFu && kTxBytes <= 0xFFFFFFFFu, "ISO-TP lengths are 32-bit");
  std::array<std::uint8_t, kRxBytes> rx{};
  std::array<std::uint8_t, kTxBytes> tx{};
};

enum class IsoTpEvent : std::uint8_t {
  kNone,            // frame consumed (part of a transfer, or flow control acted on)
  kRxComplete,      // a whole message is in message()
  kIgnored,         // not for this endpoint, or not expected now (CF without reception, stray FC)
  kBadFrame,        // malformed PCI, reserved frame type or impossible length: dropped
  kSequenceError,   // consecutive frame out of order: reception aborted
  kRxOverflow,      // announced length exceeds the receive buffer: FC OVERFLOW sent, aborted
  kRxTimeout,       // N_Cr expired: reception aborted
  kTxTimeout,       // N_Bs expired: transmission aborted
  kRemoteOverflow,  // the peer answered FC OVERFLOW: transmission aborted
  kWaitLimit,       // too many FC WAIT: transmission aborted
};

enum class [[nodiscard]] IsoTpSendStatus : std::uint8_t{
    kOk,
    kBusy,     // a transmission is in progress
    kTooLong,  // longer than the transmit buffer (or than 2^32 - 1)
    kEmpty,    // zero-length messages do not exist in ISO-TP
};

struct IsoTpStats {
  std::uint32_t rx_messages = 0, tx_messages = 0;
  std::uint32_t bad_frames = 0, sequence_errors = 0, rx_overflows = 0, rx_timeouts = 0;
  std::uint32_t tx_timeouts = 0, remote_overflows = 0, wait_limits = 0, rx_restarts = 0;
};

class IsoTpEndpoint {
 public:
  template <std::size_t kRx, std::size_t kTx>
  IsoTpEndpoint(const IsoTpConfig& config, IsoTpBuffers<kRx, kTx>& buffers)
      : IsoTpEndpoint(config, buffers.rx, buffers.tx) {}
  IsoTpEndpoint(const IsoTpConfig& config, std::span<std::uint8_t> rx_buffer, std::span<std::uint8_t> tx_buffer)
      : config_(sanitized(config)), rx_buffer_(rx_buffer), tx_buffer_(tx_buffer) {}

  // A frame received on the bus. Frames with another ID return kIgnored.
  IsoTpEvent on_frame(const CanFrame& frame, std::uint64_t now_us);
  // The next frame to transmit now, if any (flow control first, then data respecting BS/STmin).
  bool next_frame(std::uint64_t now_us, CanFrame& out);
  // Aborts a transfer whose timer expired; kNone if nothing expired.
  IsoTpEvent check_timeouts(std::uint64_t now_us);
  // Queues a message for transmission (copied into the transmit buffer).
  IsoTpSendStatus start_send(std::span<const std::uint8_t> message, std::uint64_t now_us);

  // The last complete message (valid after kRxComplete until the next reception starts).
  std::span<const std::uint8_t> message() const { return rx_buffer_.first(rx_complete_length_); }
  bool tx_busy() const { return tx_state_ != TxState::kIdle; }
  bool rx_busy() const { return rx_active_; }
  // Earliest time at which next_frame() or check_timeouts() may have work; UINT64_MAX if none.
  std::uint64_t next_deadline_us() const;
  const IsoTpStats& stats() const { return stats_; }
  const IsoTpConfig& config() const { return config_; }
  void abort_all();

  // Separation time in microseconds for an ISO STmin byte (reserved values mean 127 ms).
  static std::uint32_t st_min_us(std::uint8_t raw);
  // The configuration as used: a TX_DL that is not a CAN FD length, or an FD length without
  // `fd`, falls back to classic frames of 8 bytes.
  static IsoTpConfig sanitized(const IsoTpConfig& config);

 private:
  enum class TxState : std::uint8_t { kIdle, kSendSingle, kSendFirst, kWaitFlowControl, kSendConsecutive };
  enum class FlowStatus : std::uint8_t { kContinue = 0, kWait = 1, kOverflow = 2 };

  IsoTpEvent on_single(const CanFrame& frame);
  IsoTpEvent on_first(const CanFrame& frame, std::uint64_t now_us);
  IsoTpEvent on_consecutive(const CanFrame& frame, std::uint64_t now_us);
  IsoTpEvent on_flow_control(const CanFrame& frame, std::uint64_t now_us);
  void queue_flow_control(FlowStatus status);
  void start_frame(CanFrame& out) const;
  void finish_frame(CanFrame& out, std::size_t used) const;

  IsoTpConfig config_;
  std::span<std::uint8_t> rx_buffer_;
  std::span<std::uint8_t> tx_buffer_;

  // Reception.
  bool rx_active_ = false;
  std::uint32_t rx_length_ = 0;           // announced message length
  std::uint32_t rx_received_ = 0;         // bytes so far
  std::uint32_t rx_complete_length_ = 0;  // length of message()
  std::uint8_t rx_dl_ = 8;                // the sender's frame length (from its FF)
  std::uint8_t rx_next_sn_ = 1;
  std::uint8_t rx_block_count_ = 0;
  std::uint64_t rx_deadline_us_ = 0;
  bool fc_pending_ = false;
  FlowStatus fc_status_ = FlowStatus::kContinue;

  // Transmission.
  TxState tx_state_ = TxState::kIdle;
  std::uint32_t tx_length_ = 0;
  std::uint32_t tx_sent_ = 0;
  std::uint8_t tx_next_sn_ = 1;
  std::uint8_t tx_block_size_ = 0;  // the peer's BS
  std::uint8_t tx_block_count_ = 0;
  std::uint8_t tx_waits_ = 0;
  std::uint32_t tx_st_min_us_ = 0;  // the peer's STmin
  std::uint64_t tx_next_cf_us_ = 0;
  std::uint64_t tx_deadline_us_ = 0;

  IsoTpStats stats_;
};

}  // namespace kincal::core

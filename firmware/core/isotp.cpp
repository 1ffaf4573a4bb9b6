#include "firmware/core/isotp.hpp"

namespace kincal::core {

namespace {

constexpr std::uint8_t kPciSingle = 0x0, kPciFirst = 0x1, kPciConsecutive = 0x2, kPciFlowControl = 0x3;
constexpr std::uint32_t kMaxShortFfLength = 0xFFF;  // 12-bit FF_DL; longer lengths use the escape
constexpr std::uint64_t kNever = ~std::uint64_t{0};

void copy_bytes(std::span<std::uint8_t> to, const std::uint8_t* from, std::size_t n) {
  for (std::size_t i = 0; i < n && i < to.size(); ++i) to[i] = from[i];
}

}  // namespace

IsoTpConfig IsoTpEndpoint::sanitized(const IsoTpConfig& config) {
  IsoTpConfig c = config;
  if (c.tx_dl <= 8 || !c.fd || !shared::is_valid_length(true, c.tx_dl)) c.tx_dl = 8;
  return c;
}

std::uint32_t IsoTpEndpoint::st_min_us(std::uint8_t raw) {
  if (raw <= 0x7F) return std::uint32_t{raw} * 1000u;
  if (raw >= 0xF1 && raw <= 0xF9) return std::uint32_t{raw - 0xF0u} * 100u;
  return 127000u;
}

void IsoTpEndpoint::abort_all() {
  rx_active_ = false;
  fc_pending_ = false;
  tx_state_ = TxState::kIdle;
}

IsoTpEvent IsoTpEndpoint::on_frame(const CanFrame& frame, std::uint64_t now_us) {
  if (frame.id != config_.rx_id || frame.extended != config_.extended_ids) return IsoTpEvent::kIgnored;
  if (frame.length == 0 || !shared::is_valid_length(frame.fd, frame.length)) {
    ++stats_.bad_frames;
    return IsoTpEvent::kBadFrame;
  }
  switch (frame.data[0] >> 4) {
    case kPciSingle:
      return on_single(frame);
    case kPciFirst:
      return on_first(frame, now_us);
    case kPciConsecutive:
      return on_consecutive(frame, now_us);
    case kPciFlowControl:
      return on_flow_control(frame, now_us);
    default:
      ++stats_.bad_frames;
      return IsoTpEvent::kBadFrame;
  }
}

IsoTpEvent IsoTpEndpoint::on_single(const CanFrame& frame) {
  std::size_t length = frame.data[0] & 0xFu;
  std::size_t offset = 1;
  if (length == 0) {
    // CAN FD escape: SF_DL in the second byte, only in frames longer than 8 bytes.
    if (frame.length <= 8) {
      ++stats_.bad_frames;
      return IsoTpEvent::kBadFrame;
    }
    length = frame.data[1];
    offset = 2;
  }
  if (length == 0 || offset + length > frame.length) {
    ++stats_.bad_frames;
    return IsoTpEvent::kBadFrame;
  }
  if (rx_active_) ++stats_.rx_restarts;
  rx_active_ = false;
  if (length > rx_buffer_.size()) {
    ++stats_.rx_overflows;
    return IsoTpEvent::kRxOverflow;
  }
  copy_bytes(rx_buffer_, &frame.data[offset], length);
  rx_complete_length_ = static_cast<std::uint32_t>(length);
  ++stats_.rx_messages;
  return IsoTpEvent::kRxComplete;
}

IsoTpEvent IsoTpEndpoint::on_first(const CanFrame& frame, std::uint64_t now_us) {
  // The first frame sets the sender's frame length: 8 for classic CAN, 8..64 for CAN FD.
  if (frame.length < 8) {
    ++stats_.bad_frames;
    return IsoTpEvent::kBadFrame;
  }
  std::uint32_t length = (std::uint32_t{frame.data[0] & 0xFu} << 8) | frame.data[1];
  std::size_t offset = 2;
  if (length == 0) {
    length = (std::uint32_t{frame.data[2]} << 24) | (std::uint32_t{frame.data[3]} << 16) |
             (std::uint32_t{frame.data[4]} << 8) | frame.data[5];
    offset = 6;
    if (length <= kMaxShortFfLength) {  // the escape is only for lengths 12 bits cannot hold
      ++stats_.bad_frames;
      return IsoTpEvent::kBadFrame;
    }
  }
  // A message that fits one single frame of this size must not be segmented.
  const std::uint32_t max_single = frame.length <= 8 ? 7u : frame.length - 2u;
  if (length <= max_single) {
    ++stats_.bad_frames;
    return IsoTpEvent::kBadFrame;
  }
  if (rx_active_) ++stats_.rx_restarts;
  rx_active_ = false;
  if (length > rx_buffer_.size()) {
    ++stats_.rx_overflows;
    queue_flow_control(FlowStatus::kOverflow);
    return IsoTpEvent::kRxOverflow;
  }
  const std::size_t first = frame.length - offset;
  copy_bytes(rx_buffer_, &frame.data[offset], first);
  rx_active_ = true;
  rx_length_ = length;
  rx_received_ = static_cast<std::uint32_t>(first);
  rx_dl_ = frame.length;
  rx_next_sn_ = 1;
  rx_block_count_ = 0;
  rx_deadline_us_ = now_us + config_.n_cr_timeout_us;
  queue_flow_control(FlowStatus::kContinue);
  return IsoTpEvent::kNone;
}

IsoTpEvent IsoTpEndpoint::on_consecutive(const CanFrame& frame, std::uint64_t now_us) {
  if (!rx_active_) return IsoTpEvent::kIgnored;
  const std::uint8_t sn = frame.data[0] & 0xFu;
  if (sn != rx_next_sn_) {
    rx_active_ = false;
    ++stats_.sequence_errors;
    return IsoTpEvent::kSequenceError;
  }
  const std::uint32_t remaining = rx_length_ - rx_received_;
  const std::uint32_t capacity = rx_dl_ - 1u;
  // Every CF but the last has the first frame's length; the last carries at least the rest.
  const bool last = remaining <= capacity;
  if ((!last && frame.length != rx_dl_) || (last && frame.length < remaining + 1u) || frame.length > rx_dl_) {
    rx_active_ = false;
    ++stats_.bad_frames;
    return IsoTpEvent::kBadFrame;
  }
  const std::uint32_t take = last ? remaining : capacity;
  copy_bytes(rx_buffer_.subspan(rx_received_), &frame.data[1], take);
  rx_received_ += take;
  rx_next_sn_ = static_cast<std::uint8_t>((rx_next_sn_ + 1u) & 0xFu);
  rx_deadline_us_ = now_us + config_.n_cr_timeout_us;
  if (rx_received_ == rx_length_) {
    rx_active_ = false;
    rx_complete_length_ = rx_length_;
    ++stats_.rx_messages;
    return IsoTpEvent::kRxComplete;
  }
  if (config_.block_size != 0 && ++rx_block_count_ == config_.block_size) {
    rx_block_count_ = 0;
    queue_flow_control(FlowStatus::kContinue);
  }
  return IsoTpEvent::kNone;
}

IsoTpEvent IsoTpEndpoint::on_flow_control(const CanFrame& frame, std::uint64_t now_us) {
  if (tx_state_ != TxState::kWaitFlowControl) return IsoTpEvent::kIgnored;
  if (frame.length < 3) {
    tx_state_ = TxState::kIdle;
    ++stats_.bad_frames;
    return IsoTpEvent::kBadFrame;
  }
  switch (frame.data[0] & 0xFu) {
    case static_cast<std::uint8_t>(FlowStatus::kContinue):
      tx_block_size_ = frame.data[1];
      tx_block_count_ = 0;
      tx_waits_ = 0;
      tx_st_min_us_ = st_min_us(frame.data[2]);
      tx_next_cf_us_ = now_us;
      tx_state_ = TxState::kSendConsecutive;
      return IsoTpEvent::kNone;
    case static_cast<std::uint8_t>(FlowStatus::kWait):
      if (++tx_waits_ > config_.max_wait_frames) {
        tx_state_ = TxState::kIdle;
        ++stats_.wait_limits;
        return IsoTpEvent::kWaitLimit;
      }
      tx_deadline_us_ = now_us + config_.n_bs_timeout_us;
      return IsoTpEvent::kNone;
    case static_cast<std::uint8_t>(FlowStatus::kOverflow):
      tx_state_ = TxState::kIdle;
      ++stats_.remote_overflows;
      return IsoTpEvent::kRemoteOverflow;
    default:
      tx_state_ = TxState::kIdle;
      ++stats_.bad_frames;
      return IsoTpEvent::kBadFrame;
  }
}

void IsoTpEndpoint::queue_flow_control(FlowStatus status) {
  if (config_.listen_only) return;
  fc_pending_ = true;
  fc_status_ = status;
}

IsoTpSendStatus IsoTpEndpoint::start_send(std::span<const std::uint8_t> message, std::uint64_t now_us) {
  if (tx_state_ != TxState::kIdle) return IsoTpSendStatus::kBusy;
  if (message.empty()) return IsoTpSendStatus::kEmpty;
  if (message.size() > tx_buffer_.size()) return IsoTpSendStatus::kTooLong;
  copy_bytes(tx_buffer_, message.data(), message.size());
  tx_length_ = static_cast<std::uint32_t>(message.size());
  tx_sent_ = 0;
  const std::size_t max_single = config_.tx_dl <= 8 ? 7u : config_.tx_dl - 2u;
  tx_state_ = message.size() <= max_single ? TxState::kSendSingle : TxState::kSendFirst;
  tx_next_cf_us_ = now_us;
  return IsoTpSendStatus::kOk;
}

void IsoTpEndpoint::start_frame(CanFrame& out) const {
  out = CanFrame{};
  out.id = config_.tx_id;
  out.extended = config_.extended_ids;
  out.fd = config_.fd;
  out.brs = config_.fd && config_.brs;
}

// Sets the frame length for `used` bytes: padded to 8 when asked, and always to a valid CAN FD
// length, with pad_byte in the unused bytes.
void IsoTpEndpoint::finish_frame(CanFrame& out, std::size_t used) const {
  std::size_t length = used;
  if (config_.padding && length < 8) length = 8;
  if (out.fd) length = shared::fd_length_at_least(length);
  for (std::size_t i = used; i < length; ++i) out.data[i] = config_.pad_byte;
  out.length = static_cast<std::uint8_t>(length);
}

bool IsoTpEndpoint::next_frame(std::uint64_t now_us, CanFrame& out) {
  if (fc_pending_) {
    fc_pending_ = false;
    start_frame(out);
    out.data[0] = static_cast<std::uint8_t>((kPciFlowControl << 4) | static_cast<std::uint8_t>(fc_status_));
    out.data[1] = config_.block_size;
    out.data[2] = config_.st_min_raw;
    finish_frame(out, 3);
    return true;
  }
  switch (tx_state_) {
    case TxState::kIdle:
    case TxState::kWaitFlowControl:
      return false;
    case TxState::kSendSingle: {
      start_frame(out);
      std::size_t offset = 1;
      if (tx_length_ <= 7) {
        out.data[0] = static_cast<std::uint8_t>(tx_length_);
      } else {
        out.data[0] = 0;
        out.data[1] = static_cast<std::uint8_t>(tx_length_);
        offset = 2;
      }
      copy_bytes(std::span<std::uint8_t>(out.data).subspan(offset), tx_buffer_.data(), tx_length_);
      finish_frame(out, offset + tx_length_);
      tx_state_ = TxState::kIdle;
      ++stats_.tx_messages;
      return true;
    }
    case TxState::kSendFirst: {
      start_frame(out);
      std::size_t offset = 2;
      if (tx_length_ <= kMaxShortFfLength) {
        out.data[0] = static_cast<std::uint8_t>((kPciFirst << 4) | (tx_length_ >> 8));
        out.data[1] = static_cast<std::uint8_t>(tx_length_);
      } else {
        out.data[0] = kPciFirst << 4;
        out.data[1] = 0;
        for (unsigned i = 0; i < 4; ++i) out.data[2 + i] = static_cast<std::uint8_t>(tx_length_ >> (24 - 8 * i));
        offset = 6;
      }
      const std::size_t take = config_.tx_dl - offset;
      copy_bytes(std::span<std::uint8_t>(out.data).subspan(offset), tx_buffer_.data(), take);
      finish_frame(out, config_.tx_dl);
      tx_sent_ = static_cast<std::uint32_t>(take);
      tx_next_sn_ = 1;
      tx_waits_ = 0;
      tx_state_ = TxState::kWaitFlowControl;
      tx_deadline_us_ = now_us + config_.n_bs_timeout_us;
      return true;
    }
    case TxState::kSendConsecutive: {
      if (now_us < tx_next_cf_us_) return false;
      start_frame(out);
      out.data[0] = static_cast<std::uint8_t>((kPciConsecutive << 4) | tx_next_sn_);
      const std::uint32_t remaining = tx_length_ - tx_sent_;
      const std::uint32_t capacity = config_.tx_dl - 1u;
      const std::uint32_t take = remaining < capacity ? remaining : capacity;
      copy_bytes(std::span<std::uint8_t>(out.data).subspan(1), tx_buffer_.data() + tx_sent_, take);
      finish_frame(out, 1u + take);
      tx_sent_ += take;
      tx_next_sn_ = static_cast<std::uint8_t>((tx_next_sn_ + 1u) & 0xFu);
      tx_next_cf_us_ = now_us + tx_st_min_us_;
      if (tx_sent_ == tx_length_) {
        tx_state_ = TxState::kIdle;
        ++stats_.tx_messages;
      } else if (tx_block_size_ != 0 && ++tx_block_count_ == tx_block_size_) {
        tx_state_ = TxState::kWaitFlowControl;
        tx_deadline_us_ = now_us + config_.n_bs_timeout_us;
      }
      return true;
    }
  }
  return false;
}

IsoTpEvent IsoTpEndpoint::check_timeouts(std::uint64_t now_us) {
  if (tx_state_ == TxState::kWaitFlowControl && now_us > tx_deadline_us_) {
    tx_state_ = TxState::kIdle;
    ++stats_.tx_timeouts;
    return IsoTpEvent::kTxTimeout;
  }
  if (rx_active_ && now_us > rx_deadline_us_) {
    rx_active_ = false;
    ++stats_.rx_timeouts;
    return IsoTpEvent::kRxTimeout;
  }
  return IsoTpEvent::kNone;
}

std::uint64_t IsoTpEndpoint::next_deadline_us() const {
  std::uint64_t next = kNever;
  if (fc_pending_ || tx_state_ == TxState::kSendSingle || tx_state_ == TxState::kSendFirst) return 0;
  if (tx_state_ == TxState::kSendConsecutive) next = tx_next_cf_us_;
  if (tx_state_ == TxState::kWaitFlowControl && tx_deadline_us_ + 1 < next) next = tx_deadline_us_ + 1;
  if (rx_active_ && rx_deadline_us_ + 1 < next) next = rx_deadline_us_ + 1;
  return next;
}

}  // namespace kincal::core

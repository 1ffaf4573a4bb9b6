#include "host/can/loopback.hpp"

#include "host/can/frame_filter.hpp"
#include "shared/protocol.hpp"

namespace kincal::can {

void LoopbackEndpoint::send(const CanFrame& frame) { bus_.broadcast(this, frame); }

void LoopbackEndpoint::deliver(const CanFrame& frame) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (queue_.size() >= kQueueFrames) {
      ++dropped_;
      return;
    }
    queue_.push_back(frame);
  }
  ready_.notify_one();
}

bool LoopbackEndpoint::receive(CanFrame& out, std::chrono::microseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (!ready_.wait_for(lock, timeout, [this] { return !queue_.empty(); })) return false;
  out = queue_.front();
  queue_.pop_front();
  return true;
}

std::size_t LoopbackEndpoint::dropped() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return dropped_;
}

std::shared_ptr<LoopbackEndpoint> LoopbackBus::attach() {
  std::lock_guard<std::mutex> lock(mutex_);
  endpoints_.push_back(std::shared_ptr<LoopbackEndpoint>(new LoopbackEndpoint(*this)));
  return endpoints_.back();
}

void LoopbackBus::log_to(const std::string& path) {
  std::lock_guard<std::mutex> lock(mutex_);
  log_ = std::make_unique<CandumpWriter>(path);
}

void LoopbackBus::broadcast(const LoopbackEndpoint* from, const CanFrame& frame) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (log_) log_->write(name_, frame);
  for (const auto& e : endpoints_)
    if (e.get() != from) e->deliver(frame);
}

namespace {

core::IsoTpConfig host_isotp_config(const LoopbackOptions& options) {
  core::IsoTpConfig c;
  c.tx_id = shared::can_id::kIsoTpRequest;
  c.rx_id = shared::can_id::kIsoTpResponse;
  c.fd = options.fd;
  c.brs = options.fd;
  c.tx_dl = options.fd ? 64 : 8;
  c.padding = options.padding;
  c.n_bs_timeout_us = static_cast<std::uint32_t>(options.isotp_timeout.count()) * 1000u;
  c.n_cr_timeout_us = c.n_bs_timeout_us;
  return c;
}

const char* isotp_error(core::IsoTpEvent e) {
  switch (e) {
    case core::IsoTpEvent::kBadFrame:
      return "malformed ISO-TP frame";
    case core::IsoTpEvent::kSequenceError:
      return "ISO-TP consecutive frame out of sequence";
    case core::IsoTpEvent::kRxOverflow:
      return "ISO-TP message longer than the receive buffer";
    case core::IsoTpEvent::kRxTimeout:
      return "ISO-TP reception timed out (N_Cr)";
    case core::IsoTpEvent::kTxTimeout:
      return "ISO-TP flow control timed out (N_Bs): is the platform there?";
    case core::IsoTpEvent::kRemoteOverflow:
      return "the platform refused the ISO-TP message as too long (FC overflow)";
    case core::IsoTpEvent::kWaitLimit:
      return "the platform kept answering ISO-TP flow control WAIT";
    case core::IsoTpEvent::kNone:
    case core::IsoTpEvent::kRxComplete:
    case core::IsoTpEvent::kIgnored:
      break;
  }
  return nullptr;
}

}  // namespace

LoopbackTransport::LoopbackTransport(std::shared_ptr<LoopbackEndpoint> endpoint, const LoopbackOptions& options)
    : endpoint_(std::move(endpoint)), isotp_(host_isotp_config(options), buffers_) {}

std::uint64_t LoopbackTransport::now_us() const {
  return static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - start_).count());
}

void LoopbackTransport::send_frame(const CanFrame& frame) { endpoint_->send(frame); }

void LoopbackTransport::flush_isotp() {
  CanFrame f;
  while (isotp_.next_frame(now_us(), f)) endpoint_->send(f);
}

bool LoopbackTransport::handle(const CanFrame& frame, Received& out) {
  if (frame.id == shared::can_id::kIsoTpResponse) {
    const core::IsoTpEvent e = isotp_.on_frame(frame, now_us());
    flush_isotp();
    if (e == core::IsoTpEvent::kRxComplete) {
      out.kind = Received::Kind::kMessage;
      out.message.assign(isotp_.message().begin(), isotp_.message().end());
      return true;
    }
    if (const char* error = isotp_error(e);
        error != nullptr && e != core::IsoTpEvent::kRemoteOverflow && e != core::IsoTpEvent::kWaitLimit)
      throw CanError(std::string("loopback: ") + error);
    return false;
  }
  if (!is_platform_frame(frame)) return false;
  out.kind = Received::Kind::kFrame;
  out.frame = frame;
  return true;
}

void LoopbackTransport::send_message(std::span<const std::uint8_t> message) {
  if (isotp_.start_send(message, now_us()) != core::IsoTpSendStatus::kOk)
    throw CanError("loopback: ISO-TP message of " + std::to_string(message.size()) + " bytes cannot be sent");
  while (isotp_.tx_busy()) {
    flush_isotp();
    if (!isotp_.tx_busy()) break;
    CanFrame f;
    const std::uint64_t deadline = isotp_.next_deadline_us();
    const std::uint64_t now = now_us();
    const auto wait = std::chrono::microseconds(deadline > now ? std::min<std::uint64_t>(deadline - now, 10000) : 0);
    if (endpoint_->receive(f, wait)) {
      if (f.id == shared::can_id::kIsoTpResponse) {
        const core::IsoTpEvent e = isotp_.on_frame(f, now_us());
        if (e == core::IsoTpEvent::kRemoteOverflow || e == core::IsoTpEvent::kWaitLimit ||
            e == core::IsoTpEvent::kBadFrame)
          throw CanError(std::string("loopback: ") + isotp_error(e));
        if (e == core::IsoTpEvent::kRxComplete) {
          Received r;
          r.kind = Received::Kind::kMessage;
          r.message.assign(isotp_.message().begin(), isotp_.message().end());
          pending_.push_back(std::move(r));
        }
      } else {
        Received r;
        if (handle(f, r)) pending_.push_back(std::move(r));
      }
    }
    const core::IsoTpEvent timeout = isotp_.check_timeouts(now_us());
    if (timeout == core::IsoTpEvent::kTxTimeout) throw CanError(std::string("loopback: ") + isotp_error(timeout));
  }
}

bool LoopbackTransport::receive(Received& out, std::chrono::milliseconds timeout) {
  if (!pending_.empty()) {
    out = std::move(pending_.front());
    pending_.pop_front();
    return true;
  }
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) return false;
    CanFrame f;
    if (endpoint_->receive(f, std::chrono::duration_cast<std::chrono::microseconds>(deadline - now))) {
      if (handle(f, out)) return true;
    }
    (void)isotp_.check_timeouts(now_us());
  }
}

}  // namespace kincal::can

// An in-process CAN bus: the default on a machine with no CAN interface, and the bus of the
// ordinary end-to-end test. Every frame sent by one endpoint is delivered to every other
// endpoint (not back to the sender, as on a real bus), in send order, optionally logged in
// candump -L format. LoopbackTransport puts the host side of the protocol on an endpoint, with
// the firmware core's ISO-TP (firmware/core/isotp.hpp) standing in for the kernel's can-isotp.
//
// Thread safety: the bus and its endpoints may be used from several threads (one thread per
// endpoint). Memory: each endpoint queues up to kQueueFrames frames; a full queue drops the
// frame and counts it (dropped()), like a controller whose FIFO overflows.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "firmware/app/ports.hpp"
#include "firmware/core/isotp.hpp"
#include "host/can/candump_log.hpp"
#include "host/can/transport.hpp"

namespace kincal::can {

class LoopbackBus;

class LoopbackEndpoint {
 public:
  static constexpr std::size_t kQueueFrames = 4096;
  void send(const CanFrame& frame);
  // Waits up to `timeout` for a frame.
  bool receive(CanFrame& out, std::chrono::microseconds timeout);
  std::size_t dropped() const;

 private:
  friend class LoopbackBus;
  explicit LoopbackEndpoint(LoopbackBus& bus) : bus_(bus) {}
  void deliver(const CanFrame& frame);

  LoopbackBus& bus_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<CanFrame> queue_;
  std::size_t dropped_ = 0;
};

class LoopbackBus {
 public:
  explicit LoopbackBus(std::string name = "loop0") : name_(std::move(name)) {}
  std::shared_ptr<LoopbackEndpoint> attach();
  // Logs every frame on the bus to `path` from now on.
  void log_to(const std::string& path);
  const std::string& name() const { return name_; }

 private:
  friend class LoopbackEndpoint;
  void broadcast(const LoopbackEndpoint* from, const CanFrame& frame);

  std::string name_;
  std::mutex mutex_;
  std::vector<std::shared_ptr<LoopbackEndpoint>> endpoints_;
  std::unique_ptr<CandumpWriter> log_;
};

// The platform application's CanPort (firmware/app/ports.hpp) on a loopback endpoint: how the
// firmware runs in-process on the bus (host/sim's simulated platform, the end-to-end tests).
// Sending never fails (the endpoints queue), and the bus has no error states.
struct LoopbackCanPort {
  std::shared_ptr<LoopbackEndpoint> endpoint;
  bool try_send(const CanFrame& frame) {
    endpoint->send(frame);
    return true;
  }
  app::CanHealth health() { return {}; }
};

struct LoopbackOptions {
  bool fd = false;      // ISO-TP frames of 64 bytes (CAN FD)
  bool padding = true;  // pad ISO-TP frames with 0xCC
  std::chrono::milliseconds isotp_timeout{1000};
};

class LoopbackTransport : public Transport {
 public:
  LoopbackTransport(std::shared_ptr<LoopbackEndpoint> endpoint, const LoopbackOptions& options = {});
  void send_frame(const CanFrame& frame) override;
  void send_message(std::span<const std::uint8_t> message) override;
  bool receive(Received& out, std::chrono::milliseconds timeout) override;
  std::string name() const override { return "loopback"; }

 private:
  // Feeds one frame to ISO-TP or returns it; true if `out` was filled.
  bool handle(const CanFrame& frame, Received& out);
  void flush_isotp();
  std::uint64_t now_us() const;

  std::shared_ptr<LoopbackEndpoint> endpoint_;
  core::IsoTpBuffers<8192, 8192> buffers_;
  core::IsoTpEndpoint isotp_;
  std::deque<Received> pending_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace kincal::can

// SocketCAN: the host end of the protocol on a Linux CAN interface (can0, vcan0, ...).
//   RawCanSocket   CAN_RAW socket: classic and CAN FD frames (CAN_RAW_FD_FRAMES), receive
//                  filters (CAN_RAW_FILTER), timeouts by poll().
//   IsoTpSocket    the kernel's CAN_ISOTP socket (module can-isotp): padding with 0xCC
//                  (CAN_ISOTP_TX_PADDING), our receive flow control (BS, STmin), CAN FD frames
//                  of up to 64 bytes (CAN_ISOTP_LL_OPTS).
//   SocketCanTransport  both together, plus an optional candump -L log of every frame on the
//                  interface (a third, unfiltered raw socket sees our own ISO-TP frames too).
// Errors: every failing system call throws CanError naming the interface, the call and errno's
// text, e.g. "vcan0: cannot bind CAN_ISOTP socket: No such device (is the module can-isotp
// loaded?)". Ownership: each class owns its file descriptors (closed on destruction).
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "host/can/candump_log.hpp"
#include "host/can/transport.hpp"

namespace kincal::can {

struct IdFilter {
  std::uint32_t id = 0;
  std::uint32_t mask = 0x7FF;
};

class RawCanSocket {
 public:
  // filters empty = every frame. fd = also receive and send CAN FD frames.
  RawCanSocket(const std::string& interface, bool fd, const std::vector<IdFilter>& filters);
  ~RawCanSocket();
  RawCanSocket(const RawCanSocket&) = delete;
  RawCanSocket& operator=(const RawCanSocket&) = delete;

  void send(const CanFrame& frame);
  bool receive(CanFrame& out, std::chrono::milliseconds timeout);
  // Reads one frame that poll() said is there.
  CanFrame read_ready();
  int descriptor() const { return fd_; }

 private:
  std::string interface_;
  int fd_ = -1;
  bool can_fd_ = false;
};

struct IsoTpOptions {
  std::uint32_t tx_id = 0;
  std::uint32_t rx_id = 0;
  bool padding = true;
  bool fd = false;
  std::uint8_t block_size = 0;
  std::uint8_t st_min_raw = 0;
};

class IsoTpSocket {
 public:
  IsoTpSocket(const std::string& interface, const IsoTpOptions& options);
  ~IsoTpSocket();
  IsoTpSocket(const IsoTpSocket&) = delete;
  IsoTpSocket& operator=(const IsoTpSocket&) = delete;

  // Blocks until the kernel has sent the whole message (or failed, e.g. no flow control).
  void send(std::span<const std::uint8_t> message);
  std::vector<std::uint8_t> read_ready();
  int descriptor() const { return fd_; }

 private:
  std::string interface_;
  int fd_ = -1;
};

struct SocketCanOptions {
  bool fd = false;       // CAN FD interface: FD frames for ISO-TP and the FD joint stream
  bool padding = true;   // ISO-TP padding 0xCC
  std::string log_path;  // candump -L log of the session; empty = none
};

class SocketCanTransport : public Transport {
 public:
  SocketCanTransport(const std::string& interface, const SocketCanOptions& options);
  void send_frame(const CanFrame& frame) override;
  void send_message(std::span<const std::uint8_t> message) override;
  bool receive(Received& out, std::chrono::milliseconds timeout) override;
  std::string name() const override { return interface_; }

 private:
  void drain_tap();

  std::string interface_;
  RawCanSocket raw_;
  IsoTpSocket isotp_;
  std::unique_ptr<RawCanSocket> tap_;
  std::unique_ptr<CandumpWriter> log_;
};

}  // namespace kincal::can

// How the host reaches the platform: single CAN frames plus ISO-TP messages, over SocketCAN
// (raw + kernel can-isotp sockets) or the in-process loopback bus. PlatformClient and
// `kincal monitor` are written against this interface only.
//
// Ownership: a Transport owns its sockets or bus endpoint. Thread safety: one thread per
// Transport. Errors: operating-system and protocol failures throw CanError with a message
// naming the interface and the operation; a timeout is not an error (receive() returns false).
#pragma once

#include <chrono>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "shared/can_frame.hpp"

namespace kincal::can {

using shared::CanFrame;

class CanError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A frame or a complete ISO-TP message from the platform.
struct Received {
  enum class Kind { kFrame, kMessage } kind = Kind::kFrame;
  CanFrame frame;
  std::vector<std::uint8_t> message;
};

class Transport {
 public:
  virtual ~Transport() = default;
  virtual void send_frame(const CanFrame& frame) = 0;
  // Sends one ISO-TP message to the platform; returns when the last frame is on the bus.
  virtual void send_message(std::span<const std::uint8_t> message) = 0;
  // The next single frame from the platform or complete message, waiting up to `timeout`.
  virtual bool receive(Received& out, std::chrono::milliseconds timeout) = 0;
  virtual std::string name() const = 0;
};

}  // namespace kincal::can

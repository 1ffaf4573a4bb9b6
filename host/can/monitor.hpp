// Live decoding of the platform's traffic, for `kincal monitor` and for reading candump logs:
// each frame becomes one line; ISO-TP transfers in both directions are reassembled passively
// (firmware/core/isotp.hpp in listen-only mode, so the monitor never sends) and decoded as
// whole messages. Frames outside the protocol block are shown as "other node"; malformed frames
// say what is wrong with them. Never throws on bus content.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "shared/can_frame.hpp"

namespace kincal::can {

// One line for a single frame of the protocol (or why it does not decode).
std::string describe_frame(const shared::CanFrame& frame);
// One line for an ISO-TP message; `to_platform` is its direction.
std::string describe_message(std::span<const std::uint8_t> message, bool to_platform);

class Monitor {
 public:
  Monitor();
  ~Monitor();
  // Lines for this frame: its own, plus a message's when it completes an ISO-TP transfer.
  std::vector<std::string> feed(const shared::CanFrame& frame, std::uint64_t time_us);
  std::size_t messages() const { return messages_; }
  std::size_t frames() const { return frames_; }
  std::size_t undecodable() const { return undecodable_; }

 private:
  struct Reassembly;
  std::unique_ptr<Reassembly> reassembly_;
  std::size_t messages_ = 0, frames_ = 0, undecodable_ = 0;
};

}  // namespace kincal::can

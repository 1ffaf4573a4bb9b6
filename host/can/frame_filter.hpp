// Which frames the host side wants from the bus: the platform's single-frame messages
// (the same list the SocketCAN raw socket's filters are built from).
#pragma once

#include <vector>

#include "shared/can_frame.hpp"
#include "shared/protocol.hpp"

namespace kincal::can {

// IDs of the single-frame messages the platform sends.
inline std::vector<std::uint32_t> platform_frame_ids() {
  std::vector<std::uint32_t> ids;
  for (const shared::MessageSpec& m : shared::single_frame_messages())
    if (m.direction == shared::Direction::kPlatformToHost) ids.push_back(m.id);
  return ids;
}

inline bool is_platform_frame(const shared::CanFrame& frame) {
  if (frame.extended) return false;
  const shared::MessageSpec* spec = shared::find_message(frame.id);
  return spec != nullptr && spec->direction == shared::Direction::kPlatformToHost;
}

}  // namespace kincal::can

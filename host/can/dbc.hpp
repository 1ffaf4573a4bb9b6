// The DBC file of the protocol's single-frame messages, generated from shared/protocol.hpp's
// catalogue (the same tables the codecs use), so that standard CAN tools decode the traffic.
// Nodes: Host and Platform. CAN FD messages carry the attribute VFrameFormat = StandardCAN_FD.
#pragma once

#include <ostream>

namespace kincal::can {

void write_dbc(std::ostream& out);

}  // namespace kincal::can

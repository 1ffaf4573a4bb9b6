// The bus budget of the protocol: bits on the wire per frame with worst-case bit stuffing, and
// the highest correction-loop rate that keeps the bus under a load limit while measurements
// stream. Computed from the catalogue (shared/), not measured: a bus at that load is what the
// figures promise, whatever the controllers' own latencies add.
//
// Frame model (11-bit IDs, ISO 11898-1):
//   classic: 47 + 8n bits (SOF..EOF plus the 3-bit interframe space) + worst-case stuff bits
//            floor((34 + 8n - 1) / 4) over the 34 + 8n stuffed bits: 135 bits for n = 8.
//   CAN FD with bit-rate switch: nominal-rate bits SOF..BRS (17, worst stuffing 4) and CRC
//            delimiter, ACK, EOF, IFS (13); data-rate bits ESI, DLC, data (worst dynamic stuffing
//            over everything from SOF to the last data bit, minus the 4 counted above), stuff
//            count (4) and CRC (17 bits up to 16 data bytes, else 21) with their fixed stuff bits
//            (6 or 7).
// Traffic model per correction cycle (6-joint arm): joint state in + corrected targets out
// (classic: 4 frames of 8 bytes; CAN FD: 2 frames of 16 bytes). Per measurement: the trigger
// frame, the report by ISO-TP (the ARID set: ranges, plane, 4 fiducials, camera pose = 77
// bytes in protocol 3.0; classic: first + consecutive frames padded to 8 bytes, plus the host's
// flow control; CAN FD, whose frames carry at most 64 bytes: a single frame up to 62 report
// bytes, else a 64-byte first frame (62), the host's flow control (8 bytes) and consecutive frames
// of 63, the last rounded up to an FD length: 77 bytes are 64 + 8 + 16), at 30 Hz. Plus the
// heartbeat at 10 Hz.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace kincal::can {

struct BusConfig {
  double nominal_bit_rate = 1e6;  // bit/s, arbitration phase (and all of a classic frame)
  double data_bit_rate = 1e6;     // bit/s, CAN FD data phase
  bool fd = false;
};

struct FrameTime {
  unsigned nominal_bits = 0;
  unsigned data_bits = 0;
  double seconds = 0;
};

FrameTime classic_frame_time(std::size_t payload_bytes, const BusConfig& bus);
FrameTime fd_frame_time(std::size_t payload_bytes, const BusConfig& bus);

struct BudgetLine {
  std::string what;
  double rate_hz = 0;
  double seconds_per_event = 0;  // bus time per event (all frames of it)
  unsigned frames = 0;
};

struct Budget {
  std::vector<BudgetLine> fixed;  // measurements, heartbeat
  BudgetLine correction;          // per cycle
  double max_correction_hz = 0;
};

// The ARID measurement report's size in bytes (from shared/measurement_report.hpp's layout).
std::size_t arid_report_bytes();
Budget compute_budget(const BusConfig& bus, double load_limit, double measurement_hz);

}  // namespace kincal::can

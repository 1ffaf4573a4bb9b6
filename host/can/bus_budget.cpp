#include "host/can/bus_budget.hpp"

#include "shared/can_frame.hpp"
#include "shared/measurement_report.hpp"
#include "shared/protocol.hpp"

namespace kincal::can {

FrameTime classic_frame_time(std::size_t n, const BusConfig& bus) {
  const unsigned data = static_cast<unsigned>(8 * n);
  const unsigned stuffed = 34 + data;
  FrameTime t;
  t.nominal_bits = 47 + data + (stuffed - 1) / 4;
  t.seconds = t.nominal_bits / bus.nominal_bit_rate;
  return t;
}

FrameTime fd_frame_time(std::size_t n, const BusConfig& bus) {
  const unsigned length = shared::fd_length_at_least(n);
  const unsigned data = 8 * length;
  const unsigned arbitration = 17, arbitration_stuff = (arbitration - 1) / 4;
  const unsigned dynamic = arbitration + 5 + data;  // SOF .. last data bit
  const unsigned dynamic_stuff = (dynamic - 1) / 4;
  const unsigned crc = length <= 16 ? 17 : 21;
  const unsigned fixed_stuff = 1 + (4 + crc - 1) / 4;
  FrameTime t;
  t.nominal_bits = arbitration + arbitration_stuff + 13;
  t.data_bits = 5 + data + (dynamic_stuff - arbitration_stuff) + 4 + crc + fixed_stuff;
  t.seconds = t.nominal_bits / bus.nominal_bit_rate + t.data_bits / bus.data_bit_rate;
  return t;
}

std::size_t arid_report_bytes() {
  shared::MeasurementReport r;
  r.sections =
      shared::section::kRanges | shared::section::kPlane | shared::section::kFiducials | shared::section::kPose;
  r.fiducial_count = 4;
  return shared::report_size(r);
}

Budget compute_budget(const BusConfig& bus, double load_limit, double measurement_hz) {
  Budget b;
  const auto frame = [&bus](std::size_t n, bool fd) {
    return fd ? fd_frame_time(n, bus).seconds : classic_frame_time(n, bus).seconds;
  };
  const std::size_t report = arid_report_bytes();
  BudgetLine m{"measurement (trigger + ARID report by ISO-TP)", measurement_hz, 0, 0};
  m.seconds_per_event += frame(2, false);  // MeasureTrigger
  m.frames = 1;
  if (bus.fd && report + 2 <= 64) {
    m.seconds_per_event += frame(report + 2, true);  // one escape single frame
    m.frames += 1;
  } else if (bus.fd) {
    // First frame (2 PCI bytes, 62 of the report), the host's flow control, consecutive frames
    // of 63 bytes each (the last one rounded up to an FD length).
    const std::size_t rest = report - 62, full = rest / 63, last = rest % 63;
    m.seconds_per_event += frame(64, true) + frame(8, true) + static_cast<double>(full) * frame(64, true) +
                           (last > 0 ? frame(last + 1, true) : 0.0);
    m.frames += static_cast<unsigned>(2 + full + (last > 0 ? 1 : 0));
  } else {
    const std::size_t consecutive = (report - 6 + 6) / 7;  // FF carries 6 bytes, each CF 7
    m.seconds_per_event += frame(8, false) * static_cast<double>(1 + consecutive) + frame(8, false);  // + host FC
    m.frames += static_cast<unsigned>(2 + consecutive);
  }
  b.fixed.push_back(m);
  b.fixed.push_back({"heartbeat", 1000.0 / shared::kHeartbeatPeriodMs, frame(8, false), 1});
  b.correction = {"correction cycle (joint state in, corrected out)", 0, 0, 0};
  if (bus.fd) {
    b.correction.seconds_per_event = 2 * frame(16, true);
    b.correction.frames = 2;
  } else {
    b.correction.seconds_per_event = 4 * frame(8, false);
    b.correction.frames = 4;
  }
  double used = 0;
  for (const BudgetLine& l : b.fixed) used += l.rate_hz * l.seconds_per_event;
  b.max_correction_hz = (load_limit - used) / b.correction.seconds_per_event;
  return b;
}

}  // namespace kincal::can

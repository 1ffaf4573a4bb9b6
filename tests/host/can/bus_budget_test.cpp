// The bus budget's frame model against values worked out by hand from ISO 11898-1.
#include "host/can/bus_budget.hpp"

#include <doctest.h>

using namespace kincal::can;

TEST_CASE("classic frames: 55 bits empty, 135 bits with 8 bytes (worst-case stuffing, 3-bit IFS)") {
  const BusConfig bus{1e6, 1e6, false};
  CHECK(classic_frame_time(0, bus).nominal_bits == 55);
  CHECK(classic_frame_time(8, bus).nominal_bits == 135);
  CHECK(classic_frame_time(8, bus).seconds == doctest::Approx(135e-6));
}

TEST_CASE("CAN FD frames: 16 bytes at 1/2 Mbit/s") {
  const BusConfig bus{1e6, 2e6, true};
  const FrameTime t = fd_frame_time(16, bus);
  // 17 arbitration bits + 4 stuff + 13 (CRC delimiter, ACK, EOF, IFS) at the nominal rate;
  // 5 + 128 data + 33 dynamic stuff + 4 stuff count + 17 CRC + 6 fixed stuff at the data rate.
  CHECK(t.nominal_bits == 34);
  CHECK(t.data_bits == 193);
  CHECK(t.seconds == doctest::Approx(34e-6 + 96.5e-6));
  CHECK(fd_frame_time(20, bus).data_bits > fd_frame_time(16, bus).data_bits + 32);  // CRC-21 from 20 bytes on
}

TEST_CASE("budget: correction rate from the load left by measurements and heartbeat") {
  const Budget b = compute_budget({1e6, 1e6, false}, 0.5, 30.0);
  // 58 header + 64 ranges + 48 plane + 4 + 4 x 36 fiducials + 298 pose (its square count,
  // protocol 3.0, and its covariance) = 616 bits.
  CHECK(arid_report_bytes() == 77);
  // Trigger (75 us) + first frame + 11 consecutive frames + flow control (13 x 135 us): 30 x
  // 1830 us of measurement traffic and 10 x 135 us of heartbeat leave 443.75 ms per second for
  // 540-us cycles.
  CHECK(b.max_correction_hz == doctest::Approx((0.5 - 30 * 1830e-6 - 10 * 135e-6) / 540e-6));
  CHECK(b.max_correction_hz >= 500);
  CHECK(compute_budget({1e6, 2e6, true}, 0.5, 30.0).max_correction_hz >= 1500);
}

TEST_CASE("budget: on CAN FD the 77-byte report is a first frame, a flow control and a consecutive frame") {
  // An FD frame carries at most 64 bytes: a single frame at most 62 of the report (escape PCI),
  // a first frame 62, a consecutive frame 63; the host's flow control comes between.
  const BusConfig bus{1e6, 2e6, true};
  const Budget b = compute_budget(bus, 0.5, 30.0);
  REQUIRE(!b.fixed.empty());
  const BudgetLine& m = b.fixed.front();
  CHECK(m.frames == 4);  // trigger, first frame, flow control, consecutive frame (1 PCI + 15 bytes)
  CHECK(m.seconds_per_event == doctest::Approx(classic_frame_time(2, bus).seconds + fd_frame_time(64, bus).seconds +
                                               fd_frame_time(8, bus).seconds + fd_frame_time(16, bus).seconds));
}

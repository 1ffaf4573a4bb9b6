// The protocol's bus budget (host/can/bus_budget.hpp), printed as FIGURE lines: bits on the wire
// per message with worst-case stuffing, and the highest correction-loop rate of a 6-joint arm
// that keeps the bus under 50% load with measurements streaming at 30 Hz.
#include <cstdio>

#include "host/can/bus_budget.hpp"
#include "shared/protocol.hpp"

using namespace kincal::can;

namespace {

void print_budget(const char* name, const BusConfig& bus) {
  const Budget b = compute_budget(bus, 0.5, 30.0);
  for (const BudgetLine& l : b.fixed)
    std::printf("# %s: %s at %.0f Hz: %u frames, %.1f us each event, %.2f%% of the bus\n", name, l.what.c_str(),
                l.rate_hz, l.frames, l.seconds_per_event * 1e6, 100 * l.rate_hz * l.seconds_per_event);
  std::printf("# %s: %s: %u frames, %.1f us per cycle\n", name, b.correction.what.c_str(), b.correction.frames,
              b.correction.seconds_per_event * 1e6);
  std::printf("FIGURE %s %.0f Hz\n", name, b.max_correction_hz);
}

}  // namespace

int main() {
  const BusConfig classic{1e6, 1e6, false};
  std::printf("# worst-case bits on the wire per single-frame message (11-bit ID, incl. 3-bit IFS):\n");
  for (const kincal::shared::MessageSpec& m : kincal::shared::single_frame_messages()) {
    if (m.fd) {
      const FrameTime t = fd_frame_time(m.length, BusConfig{1e6, 2e6, true});
      std::printf("#   %-15s %2u bytes CAN FD: %u nominal + %u data-phase bits\n", m.name, m.length, t.nominal_bits,
                  t.data_bits);
    } else {
      std::printf("#   %-15s %2u bytes: %u bits\n", m.name, m.length,
                  classic_frame_time(m.length, classic).nominal_bits);
    }
  }
  std::printf("# ARID measurement report: %zu bytes\n", arid_report_bytes());
  print_budget("max_correction_hz_1m_classic", classic);
  print_budget("max_correction_hz_fd_2m", BusConfig{1e6, 2e6, true});
  // The same data phase behind a 500 kbit/s arbitration phase, a common CAN FD configuration.
  print_budget("max_correction_hz_fd_500k_2m", BusConfig{500e3, 2e6, true});
  return 0;
}

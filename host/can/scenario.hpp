// The platform scenario both end-to-end tests run (in-process loopback bus in the ordinary test
// run, real kernel SocketCAN in the VM test) and `kincal exercise` runs against any platform:
// heartbeat and protocol version, parameter upload and read-back (correction parameters and
// camera intrinsics), a series of measurements, and a stream of corrections whose results are
// checked against the joint-offset correction computed here in double precision.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "host/can/platform_client.hpp"

namespace kincal::can {

struct ScenarioOptions {
  int measurements = 10;
  int corrections = 200;
  bool fd = false;  // CAN FD joint stream
};

struct ScenarioResult {
  std::vector<std::string> failures;
  int measurements_done = 0;
  int corrections_done = 0;
  double correction_round_trip_us_median = 0;
  bool ok() const { return failures.empty(); }
};

// The correction parameters the scenario uploads (joint zero offsets of a few tenths of a mrad).
shared::CorrectionParameters scenario_correction_parameters();

// Runs the scenario; prints one line per step to `log`. Transport failures propagate as exceptions.
ScenarioResult run_platform_scenario(PlatformClient& client, const ScenarioOptions& options, std::ostream& log);

}  // namespace kincal::can

// The platform scenario both end-to-end tests run (in-process loopback bus in the ordinary test
// run, real kernel SocketCAN in the VM test) and `kincal exercise` runs against any platform:
// heartbeat and protocol version, parameter upload and read-back (correction parameters and
// camera intrinsics), a series of measurements, and a stream of corrections whose results are
// checked against the platform's kinematic correction (firmware/app/kinematic_correction.hpp)
// computed here in double precision: the same reading of the block (correction_chain.hpp) and
// the same damped first-order step and chord refinement, with firmware/core's link and error
// models instantiated for double, and its joint map (joint_map.hpp). A corrected joint may differ from the double
// result by one LSB (2^-16 rad: the float result and the double one round to neighbouring values).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "host/can/platform_client.hpp"

namespace kincal::can {

struct ScenarioOptions {
  int measurements = 10;
  int corrections = 200;
  bool fd = false;  // CAN FD joint stream
  // How long one corrected joint state may take (the first after an upload also builds the
  // platform's correction model); the VM test's emulated, sanitized platform needs more.
  std::chrono::milliseconds correction_timeout{100};
};

struct ScenarioResult {
  std::vector<std::string> failures;
  int measurements_done = 0;
  int corrections_done = 0;
  double correction_round_trip_us_median = 0;
  bool ok() const { return failures.empty(); }
};

// The correction parameters the scenario uploads: a PUMA 560 (Craig's modified DH) with
// identified errors of a few tenths of a mrad and of a mm, and a 12 cm tool, itself off by as much;
// a joint map (format 3) with Fanuc-style elbow coupling (chain joint 3 = reading 2 + reading 3),
// scale errors on joints 1-3 and gravity compliance of shoulder and elbow (PUMA link masses).
shared::CorrectionParameters scenario_correction_parameters();

// The corrected joint targets the platform should return for `joints`, in double precision
// (before quantization). Throws std::invalid_argument if the block cannot be read as a chain.
std::array<double, shared::kJoints> reference_correction(const shared::CorrectionParameters& parameters,
                                                         const std::array<std::int32_t, shared::kJoints>& joints);

// Runs the scenario; prints one line per step to `log`. Transport failures propagate as exceptions.
ScenarioResult run_platform_scenario(PlatformClient& client, const ScenarioOptions& options, std::ostream& log);

}  // namespace kincal::can

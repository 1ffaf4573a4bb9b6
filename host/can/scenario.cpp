#include "host/can/scenario.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>

namespace kincal::can {

shared::CorrectionParameters scenario_correction_parameters() {
  shared::CorrectionParameters c;
  c.joint_count = 6;
  const float offsets_rad[6] = {5.0e-4f, -3.0e-4f, 2.0e-4f, -1.0e-4f, 5.0e-5f, 4.0e-4f};
  for (std::size_t j = 0; j < shared::kJoints; ++j) {
    c.joints[j].nominal = {0.1f * static_cast<float>(j), 1.5707964f, 0.15f, 0.0f, 0.0f};
    c.joints[j].error.theta_rad = offsets_rad[j];
  }
  c.tool_offset = {0.0f, 0.0f, 0.12f, 0.0f, 0.0f, 0.0f};
  return c;
}

namespace {

template <class Block>
std::vector<std::uint8_t> image_of(const Block& block, std::size_t size) {
  std::vector<std::uint8_t> image(size);
  shared::encode_block(block, image);
  return image;
}

}  // namespace

ScenarioResult run_platform_scenario(PlatformClient& client, const ScenarioOptions& options, std::ostream& log) {
  ScenarioResult result;
  auto check = [&result, &log](bool ok, const std::string& what) {
    if (!ok) {
      result.failures.push_back(what);
      log << "scenario: FAILED " << what << "\n";
    }
    return ok;
  };

  const shared::Heartbeat first = client.wait_heartbeat(std::chrono::milliseconds(1000));
  log << "scenario: heartbeat state=" << to_string(first.state) << " protocol " << int(first.version_major) << "."
      << int(first.version_minor) << " error_flags=0x" << std::hex << first.error_flags << std::dec << "\n";
  check(first.version_major == shared::kProtocolVersionMajor, "protocol major version differs");
  client.set_mode(false, false, true);

  // Parameters: upload, then read back and compare byte for byte.
  const auto correction = image_of(scenario_correction_parameters(), shared::kCorrectionBytes);
  const std::uint32_t sequence = client.upload(shared::ParameterBlock::kCorrection, correction);
  log << "scenario: uploaded correction parameters (" << correction.size() << " bytes), slot sequence " << sequence
      << "\n";
  check(client.download(shared::ParameterBlock::kCorrection) == correction, "correction parameters read back differ");
  const shared::CameraIntrinsics intrinsics{810.5f, 811.25f, 319.5f, 239.5f, -0.12f, 0.03f,
                                            1e-4f,  -2e-4f,  0.0f,   640,    480};
  const auto intrinsics_image = image_of(intrinsics, shared::kIntrinsicsBytes);
  client.upload(shared::ParameterBlock::kIntrinsics, intrinsics_image);
  check(client.download(shared::ParameterBlock::kIntrinsics) == intrinsics_image, "intrinsics read back differ");
  log << "scenario: parameters read back identical\n";

  client.set_mode(true, true);
  client.clear_error_reports();
  for (int i = 0; i < options.measurements; ++i) {
    const shared::MeasurementReport r = client.measure(shared::section::kRanges);
    if (!check((r.sections & shared::section::kRanges) != 0, "measurement without ranges")) break;
    ++result.measurements_done;
    if (i == 0) {
      log << "scenario: measurement seq=" << int(r.sequence) << " t=" << r.timestamp_us << " us ranges m:";
      for (const std::uint16_t range : r.range_raw) {
        if (range == shared::kNoEcho)
          log << " none";
        else
          log << " " << range * shared::kRangeLsbM;
      }
      log << " status=" << to_string(r.status) << "\n";
    }
  }
  log << "scenario: " << result.measurements_done << " measurements\n";

  const shared::CorrectionParameters params = scenario_correction_parameters();
  std::vector<double> round_trips_us;
  for (int i = 0; i < options.corrections; ++i) {
    std::array<std::int32_t, shared::kJoints> joints{};
    for (std::size_t j = 0; j < shared::kJoints; ++j)
      joints[j] = shared::quantize_joint_angle(std::sin(0.01 * i + static_cast<double>(j)) * 3.0);
    const auto t0 = std::chrono::steady_clock::now();
    const auto out = client.correct(joints, options.fd);
    round_trips_us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
    bool exact = true;
    for (std::size_t j = 0; j < shared::kJoints; ++j) {
      const double expected =
          shared::joint_angle_rad<double>(joints[j]) - static_cast<double>(params.joints[j].error.theta_rad);
      exact &= std::abs(out[j] - shared::quantize_joint_angle(expected)) <= 1;  // float vs double: 1 LSB
    }
    if (!check(exact, "corrected joint state differs from the expected joint-offset correction")) break;
    ++result.corrections_done;
  }
  if (!round_trips_us.empty()) {
    std::sort(round_trips_us.begin(), round_trips_us.end());
    result.correction_round_trip_us_median = round_trips_us[round_trips_us.size() / 2];
  }
  log << "scenario: " << result.corrections_done << " corrections (" << (options.fd ? "CAN FD" : "classic")
      << "), median round trip " << result.correction_round_trip_us_median << " us\n";

  client.set_mode(false, false);
  const shared::Heartbeat last = client.wait_heartbeat(std::chrono::milliseconds(1000));
  log << "scenario: heartbeat state=" << to_string(last.state) << " measurements=" << int(last.measurements)
      << " corrections=" << int(last.corrections) << " rejected=" << int(last.rejected_frames) << "\n";
  check(static_cast<std::uint8_t>(last.measurements - first.measurements) ==
            static_cast<std::uint8_t>(result.measurements_done),
        "heartbeat measurement count");
  check(static_cast<std::uint8_t>(last.corrections - first.corrections) ==
            static_cast<std::uint8_t>(result.corrections_done),
        "heartbeat correction count");
  check((last.error_flags & shared::error_flag::kNoCorrection) == 0, "platform still reports no correction block");
  log << "scenario: " << (result.ok() ? "PASS" : "FAIL") << "\n";
  return result;
}

}  // namespace kincal::can

// The host's client of the sensor platform: what calibration sessions, `kincal exercise` and the
// end-to-end tests use. It speaks the protocol of shared/ over any Transport (SocketCAN or the
// loopback bus) and turns the platform's answers into values or exceptions.
//
// Every call waits at most its timeout. Failures throw:
//   PlatformError  the platform answered with an ErrorReport or a non-OK ParameterAck (the
//                  message names the reason), or did not answer in time (names what was awaited);
//                  a heartbeat of another protocol major version (names both versions; any call
//                  that receives one refuses the platform); the report of a measurement that does
//                  not decode (names why);
//   CanError       the transport failed.
// Heartbeats and error reports that arrive while waiting are recorded (last_heartbeat(),
// error_reports()). Thread safety: one thread per client.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "host/can/transport.hpp"
#include "shared/measurement_report.hpp"
#include "shared/parameters.hpp"
#include "shared/protocol.hpp"

namespace kincal::can {

class PlatformError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

const char* to_string(shared::ErrorReason reason);
const char* to_string(shared::AckStatus status);
const char* to_string(shared::PlatformState state);
const char* to_string(shared::MeasureStatus status);
const char* to_string(shared::DecodeStatus status);
// Empty if the heartbeat's protocol major version is this host's, else the refusal's message
// naming both versions.
std::string protocol_version_mismatch(const shared::Heartbeat& heartbeat);

class PlatformClient {
 public:
  using Milliseconds = std::chrono::milliseconds;
  explicit PlatformClient(Transport& transport) : transport_(transport) {}

  // Waits for the next heartbeat.
  shared::Heartbeat wait_heartbeat(Milliseconds timeout = Milliseconds(500));
  void set_mode(bool measure, bool correct, bool clear_errors = false);
  // Triggers one measurement and waits for its report (matched by sequence number).
  shared::MeasurementReport measure(std::uint8_t sections, Milliseconds timeout = Milliseconds(1000));
  // Uploads a parameter block; returns the storage sequence number of the stored copy.
  std::uint32_t upload(shared::ParameterBlock block, std::span<const std::uint8_t> image,
                       Milliseconds timeout = Milliseconds(3000));
  // Downloads a parameter block's image (CRC and version checked).
  std::vector<std::uint8_t> download(shared::ParameterBlock block, Milliseconds timeout = Milliseconds(3000));
  // One cycle of the correction stream: joint state in, corrected targets out (raw, LSB 2^-16 rad).
  std::array<std::int32_t, shared::kJoints> correct(const std::array<std::int32_t, shared::kJoints>& joints_raw,
                                                    bool fd, Milliseconds timeout = Milliseconds(100));

  const std::optional<shared::Heartbeat>& last_heartbeat() const { return heartbeat_; }
  const std::vector<shared::ErrorReport>& error_reports() const { return errors_; }
  void clear_error_reports() { errors_.clear(); }

 private:
  // Receives until `accept` returns true or the timeout passes; records heartbeats and errors.
  template <class Accept>
  bool wait_for(Milliseconds timeout, Accept accept);
  [[noreturn]] void fail_with_last_error(const std::string& what, std::uint32_t id);

  Transport& transport_;
  std::optional<shared::Heartbeat> heartbeat_;
  std::vector<shared::ErrorReport> errors_;
  std::uint8_t trigger_sequence_ = 0;
  std::uint8_t joint_sequence_ = 0;
};

}  // namespace kincal::can

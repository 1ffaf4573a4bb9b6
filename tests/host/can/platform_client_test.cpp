// The host client's refusals: a platform of another protocol major version, and a measurement
// report that does not decode, each with a message naming what differs.
#include <doctest.h>

#include <deque>
#include <string>

#include "host/can/platform_client.hpp"

using namespace kincal;

namespace {

// Plays back what the platform would send; records nothing of what the host sends.
class ScriptedTransport : public can::Transport {
 public:
  void send_frame(const shared::CanFrame&) override {}
  void send_message(std::span<const std::uint8_t>) override {}
  bool receive(can::Received& out, std::chrono::milliseconds) override {
    if (script.empty()) return false;
    out = script.front();
    script.pop_front();
    return true;
  }
  std::string name() const override { return "script"; }
  std::deque<can::Received> script;
};

can::Received heartbeat(std::uint8_t major, std::uint8_t minor) {
  shared::Heartbeat h;
  h.state = shared::PlatformState::kIdle;
  h.version_major = major;
  h.version_minor = minor;
  can::Received r;
  shared::encode(h, r.frame);
  return r;
}

std::string refusal(can::PlatformClient& client, bool measure) {
  try {
    if (measure)
      (void)client.measure(shared::section::kPose, std::chrono::milliseconds(50));
    else
      (void)client.wait_heartbeat(std::chrono::milliseconds(50));
  } catch (const can::PlatformError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("platform client: a heartbeat of another protocol major version is refused, naming both") {
  ScriptedTransport transport;
  can::PlatformClient client(transport);
  transport.script.push_back(heartbeat(1, 0));
  const std::string message = refusal(client, false);
  CHECK(message.find("protocol 1.0") != std::string::npos);
  CHECK(message.find("this host speaks " + std::to_string(shared::kProtocolVersionMajor) + ".") != std::string::npos);
  // Also while waiting for something else (a measurement report).
  transport.script.push_back(heartbeat(1, 3));
  CHECK(refusal(client, true).find("protocol 1.3") != std::string::npos);
  // Another minor version of the same major is accepted.
  transport.script.push_back(heartbeat(shared::kProtocolVersionMajor, 7));
  CHECK(client.wait_heartbeat(std::chrono::milliseconds(50)).version_minor == 7);
  CHECK(can::protocol_version_mismatch(shared::Heartbeat{}).empty());
}

TEST_CASE("platform client: a report that does not decode names why") {
  ScriptedTransport transport;
  can::PlatformClient client(transport);
  // A version-1 report of the pose section: 180 bits shorter than this protocol's.
  shared::MeasurementReport report;
  report.sequence = 1;  // the client's first trigger
  report.sections = shared::section::kPose;
  std::array<std::uint8_t, shared::kMaxReportBytes> bytes{};
  const std::size_t n = shared::encode(report, bytes);
  REQUIRE(n == shared::report_size(report));
  can::Received r;
  r.kind = can::Received::Kind::kMessage;
  r.message.assign(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(n - 180 / 8));
  transport.script.push_back(r);
  const std::string message = refusal(client, true);
  CHECK(message.find("measurement 1") != std::string::npos);
  CHECK(message.find("does not decode (wrong length") != std::string::npos);
  // The whole report decodes (the client's second trigger).
  report.sequence = 2;
  REQUIRE(shared::encode(report, bytes) == n);
  r.message.assign(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(n));
  transport.script.push_back(r);
  CHECK(client.measure(shared::section::kPose, std::chrono::milliseconds(50)).sections == shared::section::kPose);
}

// The end-to-end scenario over the in-process loopback bus, in the ordinary test run: the
// platform application (firmware/app, with the test's RAM storage and rangers) runs in its own
// thread on one endpoint, the host client on another; measurement, parameter upload and
// read-back, and the correction stream, on classic CAN and on CAN FD. The bus writes a
// candump -L log, which our reader and the monitor then decode completely. Also the monitor's
// line for a report with a pose.
#include <doctest.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <thread>

#include "firmware/app/kinematic_correction.hpp"
#include "firmware/app/platform_app.hpp"
#include "firmware/app/platform_measurement.hpp"
#include "host/can/candump_log.hpp"
#include "host/can/loopback.hpp"
#include "host/can/monitor.hpp"
#include "host/can/platform_client.hpp"
#include "host/can/scenario.hpp"
#include "tests/firmware/app/fake_ports.hpp"

using namespace kincal;

namespace {

using Measure = app::PlatformMeasurement<test::FakeCamera, test::FakeRangers>;
using LoopbackApp = app::PlatformApp<can::LoopbackCanPort, test::FakeStorage, Measure, app::KinematicCorrection>;

std::uint64_t now_us() {
  return static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch())
          .count());
}

// The platform on its own thread for the lifetime of the object.
class PlatformThread {
 public:
  PlatformThread(can::LoopbackBus& bus, bool fd) : port_{bus.attach()} {
    app::AppConfig config;
    config.fd = fd;
    rangers_.ranges_um = {200000, 210000, 190000, app::kNoEchoUm};
    app_ = std::make_unique<LoopbackApp>(config, port_, storage_, measure_, correct_);
    app_->start(now_us());
    thread_ = std::thread([this] {
      while (!stop_) {
        shared::CanFrame f;
        if (port_.endpoint->receive(f, std::chrono::microseconds(500))) app_->on_frame(f, now_us());
        app_->poll(now_us());
      }
    });
  }
  ~PlatformThread() {
    stop_ = true;
    thread_.join();
  }

 private:
  can::LoopbackCanPort port_;
  test::FakeStorage storage_;
  test::FakeCamera camera_;  // the scenario asks for ranges only
  test::FakeRangers rangers_;
  Measure measure_{camera_, rangers_};
  app::KinematicCorrection correct_;
  std::unique_ptr<LoopbackApp> app_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

void run(bool fd) {
  const std::string log_path =
      (std::filesystem::temp_directory_path() / (std::string("kincal-loopback-") + (fd ? "fd" : "classic") + ".log"))
          .string();
  std::size_t logged = 0;
  {
    can::LoopbackBus bus;
    bus.log_to(log_path);
    auto host_endpoint = bus.attach();
    PlatformThread platform(bus, fd);
    can::LoopbackOptions options;
    options.fd = fd;
    can::LoopbackTransport transport(host_endpoint, options);
    can::PlatformClient client(transport);
    std::ostringstream log;
    const can::ScenarioResult result = can::run_platform_scenario(client, {10, 200, fd}, log);
    MESSAGE(log.str());
    CHECK(result.ok());
    CHECK(result.measurements_done == 10);
    CHECK(result.corrections_done == 200);
    CHECK(host_endpoint->dropped() == 0);
    // The ranges crossed the bus exactly (0.2 m = 13107 LSB).
    client.set_mode(true, false);
    const shared::MeasurementReport r = client.measure(shared::section::kRanges);
    CHECK(r.range_raw[0] == 13107);
    CHECK(r.range_raw[3] == shared::kNoEcho);
    // Defined responses through the whole stack: a measurement while measuring is disabled.
    client.set_mode(false, false);
    CHECK_THROWS_WITH_AS(client.measure(shared::section::kRanges), doctest::Contains("not in mode"),
                         can::PlatformError);
  }
  // Every frame of the session is in the log, and every one decodes.
  can::CandumpReader reader(log_path);
  can::Monitor monitor;
  bool saw_report = false, saw_write = false;
  while (auto frame = reader.next()) {
    ++logged;
    CHECK(frame->interface == "loop0");
    for (const std::string& line : monitor.feed(frame->frame, frame->time_us)) {
      saw_report |= line.find("MeasurementReport seq=") != std::string::npos;
      saw_write |= line.find("ParameterWrite block=4 version=" + std::to_string(shared::kBlockFormatVersion) +
                             " length=" + std::to_string(shared::kCorrectionBytes) + " check=ok") != std::string::npos;
    }
  }
  CHECK(logged > 400);
  CHECK(monitor.undecodable() == 0);
  CHECK(monitor.messages() >= 15);  // 11 reports, 2 writes, 2 reads, 2 data
  CHECK(saw_report);
  CHECK(saw_write);
  std::filesystem::remove(log_path);
}

}  // namespace

TEST_CASE("loopback end to end: classic CAN") { run(false); }

TEST_CASE("loopback end to end: CAN FD") { run(true); }

TEST_CASE("the monitor prints how many squares a report's pose used (protocol 3.0)") {
  shared::MeasurementReport r;
  r.sequence = 7;
  r.sections = shared::section::kPose;
  r.pose_squares = 3;
  r.translation_raw = {262144, 0, -131072};  // 1 m, 0, -0.5 m
  std::array<std::uint8_t, shared::kMaxReportBytes> bytes{};
  const std::size_t n = shared::encode(r, bytes);
  REQUIRE(n == shared::report_size(r));
  const std::string line = can::describe_message(std::span<const std::uint8_t>(bytes).first(n), false);
  CHECK(line.find("MeasurementReport seq=7") != std::string::npos);
  CHECK(line.find(" pose_squares=3 t_m=1,0,-0.5") != std::string::npos);
}

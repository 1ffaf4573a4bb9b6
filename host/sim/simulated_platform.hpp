// The sensor platform's firmware, running in-process on the loopback bus and seeing the
// simulator's world (issue #6): the very firmware/app the STM32 image and kincal_platform run
// (PlatformApp, PlatformMeasurement, KinematicCorrection), bound to simulated ports -- a camera
// that delivers the current rendered frame row by row, four rangers that read the current
// simulated ranges, parameter storage in RAM -- on its own thread, so that `kincal demo` and
// the session tests exercise the real measurement and correction code over the real protocol.
//
// SimulatedView is what the platform sees now: the driver of the simulated robot sets a new
// frame and new ranges after each move (the robot stands still during a measurement, so both
// frames of a measurement, metering and labelled, are the same picture). Thread-safe.
// Cost: a thread polling the bus every 0.5 ms while the object lives; the frame is shared, not
// copied, per measurement. Errors: std::invalid_argument for a frame of another size or type.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <thread>

#include <opencv2/core.hpp>

#include "host/can/loopback.hpp"
#include "shared/measurement_report.hpp"

namespace kincal::sim {

class SimulatedView {
 public:
  // frame: CV_8UC1 of the camera's size; ranges: metres along each beam, NaN for no echo.
  void set(cv::Mat frame, const std::array<double, shared::kRangers>& ranges_m);
  cv::Mat frame() const;
  std::array<double, shared::kRangers> ranges_m() const;

 private:
  mutable std::mutex mutex_;
  cv::Mat frame_;
  std::array<double, shared::kRangers> ranges_m_{};
};

class SimulatedPlatform {
 public:
  SimulatedPlatform(can::LoopbackBus& bus, bool fd, int width_px, int height_px, const SimulatedView& view);
  ~SimulatedPlatform();
  SimulatedPlatform(const SimulatedPlatform&) = delete;
  SimulatedPlatform& operator=(const SimulatedPlatform&) = delete;

 private:
  struct Firmware;  // the app and its ports
  std::unique_ptr<Firmware> firmware_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace kincal::sim

#include "host/sim/simulated_platform.hpp"

#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "firmware/app/kinematic_correction.hpp"
#include "firmware/app/platform_app.hpp"
#include "firmware/app/platform_measurement.hpp"

namespace kincal::sim {

void SimulatedView::set(cv::Mat frame, const std::array<double, shared::kRangers>& ranges_m) {
  std::lock_guard lock(mutex_);
  frame_ = std::move(frame);
  ranges_m_ = ranges_m;
}

cv::Mat SimulatedView::frame() const {
  std::lock_guard lock(mutex_);
  return frame_;
}

std::array<double, shared::kRangers> SimulatedView::ranges_m() const {
  std::lock_guard lock(mutex_);
  return ranges_m_;
}

namespace {

std::uint64_t now_us() {
  return static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch())
          .count());
}

// Parameter storage in RAM: the platform starts without parameters, as a fresh board does.
struct RamStorage {
  static constexpr std::size_t kSlotBytes = 4096;
  std::array<std::array<std::uint8_t, kSlotBytes>, app::slot_format::kSlotCount> slots;
  RamStorage() {
    for (auto& s : slots) s.fill(0xFF);
  }
  app::StorageStatus read(std::uint8_t slot, std::uint32_t offset, std::span<std::uint8_t> out) {
    if (slot >= slots.size() || offset + out.size() > kSlotBytes) return app::StorageStatus::kFailed;
    std::memcpy(out.data(), slots[slot].data() + offset, out.size());
    return app::StorageStatus::kOk;
  }
  app::StorageStatus erase(std::uint8_t slot) {
    if (slot >= slots.size()) return app::StorageStatus::kFailed;
    slots[slot].fill(0xFF);
    return app::StorageStatus::kOk;
  }
  app::StorageStatus write(std::uint8_t slot, std::uint32_t offset, std::span<const std::uint8_t> in) {
    if (slot >= slots.size() || offset + in.size() > kSlotBytes) return app::StorageStatus::kFailed;
    std::memcpy(slots[slot].data() + offset, in.data(), in.size());
    return app::StorageStatus::kOk;
  }
};

class ViewCamera {
 public:
  ViewCamera(const SimulatedView& view, int width_px, int height_px)
      : view_(view), width_(static_cast<std::uint16_t>(width_px)), height_(static_cast<std::uint16_t>(height_px)) {}
  std::uint16_t width_px() const { return width_; }
  std::uint16_t height_px() const { return height_; }
  app::CaptureStatus begin_frame(app::FrameUse, std::uint64_t& exposure_us) {
    frame_ = view_.frame();
    row_ = 0;
    exposure_us = now_us();
    if (frame_.empty() || frame_.type() != CV_8UC1 || frame_.cols != width_ || frame_.rows != height_)
      return app::CaptureStatus::kFailed;
    return app::CaptureStatus::kOk;
  }
  app::CaptureStatus read_row(std::span<std::uint8_t> row) {
    if (frame_.empty() || row_ >= height_ || row.size() != width_) return app::CaptureStatus::kFailed;
    std::memcpy(row.data(), frame_.ptr<std::uint8_t>(row_++), row.size());
    return app::CaptureStatus::kOk;
  }

 private:
  const SimulatedView& view_;
  std::uint16_t width_, height_;
  cv::Mat frame_;
  int row_ = 0;
};

class ViewRangers {
 public:
  explicit ViewRangers(const SimulatedView& view) : view_(view) {}
  app::RangerStatus read(std::array<std::uint32_t, shared::kRangers>& ranges_um, std::uint64_t& time_us) {
    const auto ranges = view_.ranges_m();
    for (std::size_t i = 0; i < ranges.size(); ++i)
      ranges_um[i] = std::isfinite(ranges[i]) && ranges[i] >= 0 && ranges[i] < 4000
                         ? static_cast<std::uint32_t>(std::lround(ranges[i] * 1e6))
                         : app::kNoEchoUm;
    time_us = now_us();
    return app::RangerStatus::kOk;
  }

 private:
  const SimulatedView& view_;
};

using Measurement = app::PlatformMeasurement<ViewCamera, ViewRangers>;
using App = app::PlatformApp<can::LoopbackCanPort, RamStorage, Measurement, app::KinematicCorrection>;

}  // namespace

struct SimulatedPlatform::Firmware {
  Firmware(can::LoopbackBus& bus, bool fd, int width_px, int height_px, const SimulatedView& view)
      : port{bus.attach()}, camera(view, width_px, height_px), rangers(view) {
    app::AppConfig config;
    config.fd = fd;
    application = std::make_unique<App>(config, port, storage, measure, correct);
  }
  can::LoopbackCanPort port;
  RamStorage storage;
  ViewCamera camera;
  ViewRangers rangers;
  Measurement measure{camera, rangers};
  app::KinematicCorrection correct;
  std::unique_ptr<App> application;
};

SimulatedPlatform::SimulatedPlatform(can::LoopbackBus& bus, bool fd, int width_px, int height_px,
                                     const SimulatedView& view) {
  if (width_px <= 0 || height_px <= 0 || width_px > 4096 || height_px > 4096)
    throw std::invalid_argument("simulated platform: camera size " + std::to_string(width_px) + " x " +
                                std::to_string(height_px) + " px is outside 1..4096");
  firmware_ = std::make_unique<Firmware>(bus, fd, width_px, height_px, view);
  firmware_->application->start(now_us());
  thread_ = std::thread([this] {
    App& a = *firmware_->application;
    while (!stop_) {
      shared::CanFrame f;
      if (firmware_->port.endpoint->receive(f, std::chrono::microseconds(500))) a.on_frame(f, now_us());
      a.poll(now_us());
    }
  });
}

SimulatedPlatform::~SimulatedPlatform() {
  stop_ = true;
  thread_.join();
}

}  // namespace kincal::sim

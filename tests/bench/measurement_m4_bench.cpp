// The platform's whole measurement step on the Cortex-M4 (QEMU, -icount shift=0): one ARID
// measurement (ranges, plane, fiducials, pose with its covariance) of a 640x480 calibration-square
// frame through app::PlatformMeasurement: the metering frame (grey histogram, Otsu), then the
// measurement frame's rows through the labeler, and at its end FID, the range plane and its
// covariance, the camera-first planar pose fused with the plane prior (one perspective pass) and
// the report's covariance.
//
// The frame (vga_square_frame.hpp) is rendered a row at a time inside the camera port, outside
// the counted instructions (on the platform the camera's DMA writes the rows); the step's own
// copy of each row is counted. The scene: a strip 0.25 m below the camera, facing it
// (fx = fy = 1181.1 px: 1.75 inch = 210 px at 0.25 m), the four rangers reading 0.25 m; its
// square centred at (239.5, 239.5) px is whole, the next one's left fiducials (p1, p3) are in the
// frame at x = 509.5 px: the strip's matching and the second pose over both squares are counted.
// Frames per second assume one instruction per cycle at 168 MHz (STM32F407); the M4 takes more
// cycles for loads, divisions and flash wait states, so the real rate is lower.
#include <array>
#include <cstdint>
#include <cstdio>

#include "firmware/app/platform_measurement.hpp"
#include "tests/bench/m4_instruction_counter.hpp"
#include "tests/bench/vga_square_frame.hpp"

using namespace kincal;

namespace {

constexpr int kCx = 240, kCy = 240;  // the centre fiducial's centre at (239.5, 239.5) px
constexpr float kSideM = 0.00635f;   // Doty's 1/4-inch fiducial side
constexpr float kDistanceM = 0.25f;
constexpr float kFocalPx = static_cast<float>(bench::kVgaPerimeterDistancePx) * kDistanceM / (7.0f * kSideM);

// Renders each row on request; the instructions spent rendering are not counted. Counts the
// rest per frame: counted[0] the metering frame, counted[1] the measurement frame (and the
// step's work after it).
struct BenchCamera {
  bench::M4InstructionCounter* counter = nullptr;
  std::array<std::uint64_t, 2> counted{};
  std::size_t current = 0;
  int row = 0;
  std::uint16_t width_px() const { return bench::kVgaWidth; }
  std::uint16_t height_px() const { return bench::kVgaHeight; }
  app::CaptureStatus begin_frame(app::FrameUse use, std::uint64_t& exposure_us) {
    counted[current] += counter->stop_instructions();
    counter->start();
    current = use == app::FrameUse::kMetering ? 0 : 1;
    row = 0;
    exposure_us = 1000;
    return app::CaptureStatus::kOk;
  }
  app::CaptureStatus read_row(std::span<std::uint8_t> out) {
    if (row >= bench::kVgaHeight) return app::CaptureStatus::kFailed;
    counted[current] += counter->stop_instructions();
    bench::render_vga_square_row(row++, kCx, kCy, out.data(), bench::kVgaSquarePitchPx);
    counter->start();
    return app::CaptureStatus::kOk;
  }
  std::uint64_t total() const { return counted[0] + counted[1] + counter->stop_instructions(); }
};

struct BenchRangers {
  app::RangerStatus read(std::array<std::uint32_t, shared::kRangers>& ranges_um, std::uint64_t& time_us) {
    ranges_um.fill(static_cast<std::uint32_t>(kDistanceM * 1e6f));
    time_us = 1000;
    return app::RangerStatus::kOk;
  }
};

app::ParameterSet parameters() {
  app::ParameterSet p;
  p.has_intrinsics = true;
  p.intrinsics = {kFocalPx, kFocalPx, 319.5f, 239.5f, 0, 0, 0, 0, 0, bench::kVgaWidth, bench::kVgaHeight};
  p.has_geometry = true;
  const float beam[4][2] = {{0.03f, 0}, {0, 0.03f}, {-0.03f, 0}, {0, -0.03f}};
  for (std::size_t i = 0; i < shared::kRangers; ++i) p.geometry.rangers[i] = {{beam[i][0], beam[i][1], 0}, {0, 0, 1}};
  const float s = kSideM;
  const float fiducials[6][2] = {{-7 * s, 7 * s}, {0, 7 * s}, {-7 * s, 0}, {0, 0}, {7 * s, 0}, {0, -7 * s}};
  p.geometry.fiducial_count = 6;
  for (std::size_t k = 0; k < 6; ++k) p.geometry.fiducial_square_m[k] = {fiducials[k][0], fiducials[k][1], 0};
  p.geometry.square_pitch_m = 16 * s;  // Doty's 4-inch squares
  return p;
}

BenchCamera g_camera;
BenchRangers g_rangers;
app::PlatformMeasurement<BenchCamera, BenchRangers> g_step(g_camera, g_rangers);  // static: 30+ KiB
shared::MeasurementReport g_report;

}  // namespace

int main() {
  bench::M4InstructionCounter counter;
  g_camera.counter = &counter;
  constexpr std::uint8_t kArid =
      shared::section::kRanges | shared::section::kPlane | shared::section::kFiducials | shared::section::kPose;
  const app::ParameterSet p = parameters();
  constexpr int kRuns = 2;
  std::uint64_t metering = 0, measuring = 0, last_poll = 0;
  for (int run = 0; run < kRuns; ++run) {
    g_camera.counted = {};
    g_camera.current = 0;
    counter.start();
    if (g_step.start({static_cast<std::uint8_t>(run), kArid}, p, 0) != app::MeasureStart::kStarted) return 1;
    std::uint64_t now_us = 0;
    bool done = false;
    while (!done) {
      const std::uint64_t before = g_camera.total();
      done = g_step.poll(now_us += 100, g_report);
      last_poll = g_camera.total() - before;
    }
    g_camera.counted[g_camera.current] += counter.stop_instructions();
    metering += g_camera.counted[0];
    measuring += g_camera.counted[1];
  }
  metering /= kRuns;
  measuring /= kRuns;
  const bool ok = g_report.status == shared::MeasureStatus::kOk && g_report.sections == kArid &&
                  g_report.fiducial_count == 6 && g_report.pose_squares == 2;
  std::printf("status %u, sections 0x%x, fiducials %u, squares %u; camera in the square (um): %ld %ld %ld\n",
              static_cast<unsigned>(g_report.status), static_cast<unsigned>(g_report.sections),
              static_cast<unsigned>(g_report.fiducial_count), static_cast<unsigned>(g_report.pose_squares),
              static_cast<long>(g_report.translation_raw[0] * 1e6 / 262144.0),
              static_cast<long>(g_report.translation_raw[1] * 1e6 / 262144.0),
              static_cast<long>(g_report.translation_raw[2] * 1e6 / 262144.0));
  std::printf("metering frame %lu instructions, measurement frame %lu, its last poll (16 rows, FID, plane, pose) %lu\n",
              static_cast<unsigned long>(metering), static_cast<unsigned long>(measuring),
              static_cast<unsigned long>(last_poll));
  const std::uint64_t total = metering + measuring;
  std::printf("FIGURE measurement_m4_instructions_per_frame %lu instructions\n", static_cast<unsigned long>(measuring));
  std::printf("FIGURE measurement_m4_instructions_per_measurement %lu instructions\n",
              static_cast<unsigned long>(total));
  std::printf("FIGURE measurement_m4_measurements_per_second_168mhz %.1f per_second\n",
              168e6 / static_cast<double>(total));
  std::printf("FIGURE measurement_m4_frames_per_second_168mhz %.1f per_second\n",
              168e6 / static_cast<double>(measuring));
  std::printf("FIGURE measurement_step_ram_bytes %u bytes\n", static_cast<unsigned>(sizeof(g_step)));
  return ok ? 0 : 1;
}

// The measurement step this build runs: the four rangers, read through a RangerPort.
//
// What: on each trigger it reads the rangers once and reports the ranges section (LSB 2^-16 m,
// kNoEcho for a sensor without a valid reading or one outside [0, 1) m), time-stamped with the
// rangers' reading time. Sections computed from the camera rows and the rangers together
// (plane, fiducials, pose, blobs, triangulated point) come from the blob labeler and the
// geometry of firmware/core, which are being written in parallel: until they are composed into
// a step behind the same MeasurementStep concept, a request for them is answered with those
// sections absent and status kNotAvailable, never with invented values.
// Port: RangerPort::read(ranges_um, time_us) -> RangerStatus, synchronous; UINT32_MAX = no echo.
// Memory: the request and the reading (~24 bytes). Cost: one port call and four conversions.
// Thread/ISR safety: main loop only. Failure modes: a failed ranger read gives kRangerFailure.
#pragma once

#include <array>
#include <concepts>
#include <cstdint>

#include "firmware/app/ports.hpp"

namespace kincal::app {

enum class [[nodiscard]] RangerStatus : std::uint8_t{kOk, kFailed};
inline constexpr std::uint32_t kNoEchoUm = 0xFFFFFFFFu;

template <class T>
concept RangerPort = requires(T& port, std::array<std::uint32_t, shared::kRangers>& ranges_um, std::uint64_t& time_us) {
  { port.read(ranges_um, time_us) } -> std::same_as<RangerStatus>;
};

// Micrometres to the report's LSB of 2^-16 m, rounded to nearest; out of [0, 1) m -> kNoEcho.
constexpr std::uint16_t range_raw_from_um(std::uint32_t range_um) {
  if (range_um == kNoEchoUm) return shared::kNoEcho;
  const std::uint64_t raw = (std::uint64_t{range_um} * 65536u + 500000u) / 1000000u;
  return raw >= shared::kNoEcho ? shared::kNoEcho : static_cast<std::uint16_t>(raw);
}

template <RangerPort Rangers>
class RangerMeasurement {
 public:
  explicit RangerMeasurement(Rangers& rangers) : rangers_(rangers) {}

  MeasureStart start(const MeasureRequest& request, const ParameterSet&, std::uint64_t) {
    if (pending_) return MeasureStart::kBusy;
    request_ = request;
    pending_ = true;
    return MeasureStart::kStarted;
  }

  bool poll(std::uint64_t now_us, shared::MeasurementReport& report) {
    if (!pending_) return false;
    pending_ = false;
    report = shared::MeasurementReport{};
    report.sequence = request_.sequence;
    report.timestamp_us = static_cast<std::uint32_t>(now_us);
    report.status = shared::MeasureStatus::kOk;
    if (request_.sections & shared::section::kRanges) {
      std::array<std::uint32_t, shared::kRangers> ranges_um{};
      std::uint64_t time_us = now_us;
      if (rangers_.read(ranges_um, time_us) == RangerStatus::kOk) {
        for (std::size_t i = 0; i < shared::kRangers; ++i) report.range_raw[i] = range_raw_from_um(ranges_um[i]);
        report.sections |= shared::section::kRanges;
        report.timestamp_us = static_cast<std::uint32_t>(time_us);
      } else {
        report.status = shared::MeasureStatus::kRangerFailure;
      }
    }
    if ((request_.sections & ~shared::section::kRanges & shared::section::kAll) != 0 &&
        report.status == shared::MeasureStatus::kOk)
      report.status = shared::MeasureStatus::kNotAvailable;
    return true;
  }

 private:
  Rangers& rangers_;
  MeasureRequest request_;
  bool pending_ = false;
};

}  // namespace kincal::app

// The platform application's ports: what a board (firmware/platform/<board>) or a test provides
// to firmware/app, written as C++20 concepts so the application binds to them at compile time.
//
// Why concepts and not virtual interfaces: the stack check (toolchain/check_stack.py) must see
// every call, and an indirect call cannot be bounded; a template bound to the board's concrete
// types costs nothing at run time and keeps the call graph complete.
//
// Ports and their contracts (all called from the application's single main-loop context; none
// is called from an ISR, so a port shared with an ISR must do its own locking):
//   CanPort          try_send(frame) -> bool: queue one frame for transmission without
//                    blocking; false when the controller's queue is full (the app keeps the
//                    frame and retries). health() -> CanHealth: error state for the heartbeat.
//                    Received frames are pushed by the board into PlatformApp::on_frame().
//   StoragePort      non-volatile slots of kSlotBytes each: read/erase/write, synchronous and
//                    bounded in time; erase sets a slot to the erased state, write programs bytes
//                    of an erased slot. A power cut may stop any of them at any byte.
//   CameraPort       one grey frame per request, delivered row by row (below).
//   RangerPort       read(ranges_um, time_us) -> RangerStatus: the four rangers once,
//                    synchronous and bounded; kNoEchoUm marks a sensor without a valid reading;
//                    time_us = the platform clock when the reading was taken.
//   MeasurementStep  start(request, parameters, now) begins one measurement (the camera rows,
//                    rangers, labeler and geometry behind it are the step's business);
//                    poll(now, report) -> true once the report is filled. One at a time.
//                    poll() must return within a bounded time (a slice of the work), so that
//                    the correction stream keeps its rate while a frame streams in.
//   CorrectionStep   correct(parameters, in, out): corrected joint targets for one joint state.
//
// CameraPort, the contract (the STM32's DCMI with DMA per line, a file, the simulator's image):
//   width_px(), height_px()   the frame size, fixed for the port's lifetime (sensor set-up).
//   begin_frame(use, exposure_us) -> CaptureStatus
//                    requests one frame and returns at once (snapshot mode); abandons any frame
//                    still being read. exposure_us = the platform clock at mid-exposure of that
//                    frame (what a measurement report is time-stamped with). `use` says why: a
//                    measurement asks for a kMetering frame (the step only takes its grey-level
//                    histogram, for the automatic threshold) and then a kMeasurement frame of
//                    the same scene (labelled). The robot stands still during a measurement, so
//                    a live camera simply takes two snapshots; a port that replays recorded
//                    frames moves to its next recording for kMetering and delivers the same one
//                    again for kMeasurement.
//   read_row(row) -> CaptureStatus
//                    copies the frame's next row (row.size() == width_px(), top row first) and
//                    returns kOk; kPending when that row has not arrived yet (call again: the
//                    step never waits in the port, it gives the main loop back); kFailed when
//                    the frame is lost (DMA overrun, sensor timeout, short file) or no frame was
//                    requested; then begin_frame again. After height_px() rows the frame is over.
//   Rows are 8-bit grey: the blob labeler's input. A colour sensor's port converts its rows
//   (RGB565, YUV422) to luma with firmware/core/pixel_formats before handing them over; colour
//   classes for the beacon are a separate path (colour_class.hpp) not used by this concept.
//   Cost: read_row is one row copy (on the board out of the DMA line buffer).
// The joint-state input arrives over CAN (the protocol's JointState messages).
#pragma once

#include <array>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <span>

#include "shared/can_frame.hpp"
#include "shared/measurement_report.hpp"
#include "shared/parameters.hpp"

namespace kincal::app {

using shared::CanFrame;

struct CanHealth {
  bool error_passive = false;        // TEC or REC >= 128
  bool bus_off = false;              // TEC > 255: the controller is off the bus now
  std::uint8_t tx_error_count = 0;   // TEC, saturating at 255
  std::uint32_t bus_off_events = 0;  // times the controller went bus-off and recovered
};

enum class [[nodiscard]] StorageStatus : std::uint8_t{kOk, kFailed};

// The parameter blocks in RAM, as the steps read them; `has_*` says whether a valid copy exists.
struct ParameterSet {
  bool has_intrinsics = false, has_colour_lut = false, has_geometry = false, has_correction = false;
  shared::CameraIntrinsics intrinsics;
  shared::ColourLut colour_lut;
  shared::PlatformGeometry geometry;
  shared::CorrectionParameters correction;
};

struct MeasureRequest {
  std::uint8_t sequence = 0;
  std::uint8_t sections = 0;  // shared::section bits
};

enum class [[nodiscard]] MeasureStart : std::uint8_t{kStarted, kBusy};
// kNoParameters: no correction block, or one the step cannot apply; kNotCorrectable: this joint
// target cannot be corrected (out of range, or near a singularity where the step would exceed
// its bound): nothing is sent for it rather than an uncorrected target.
enum class [[nodiscard]] CorrectStatus : std::uint8_t{kOk, kNoParameters, kNotCorrectable};

enum class [[nodiscard]] CaptureStatus : std::uint8_t{kOk, kPending, kFailed};
enum class FrameUse : std::uint8_t { kMetering, kMeasurement };

enum class [[nodiscard]] RangerStatus : std::uint8_t{kOk, kFailed};
inline constexpr std::uint32_t kNoEchoUm = 0xFFFFFFFFu;

using JointRaw = std::array<std::int32_t, shared::kJoints>;  // LSB 2^-16 rad (shared/protocol.hpp)

template <class T>
concept CanPort = requires(T& port, const CanFrame& frame) {
  { port.try_send(frame) } -> std::same_as<bool>;
  { port.health() } -> std::same_as<CanHealth>;
};

template <class T>
concept StoragePort = requires(T& port, std::uint8_t slot, std::uint32_t offset, std::span<std::uint8_t> out,
                               std::span<const std::uint8_t> in) {
  { T::kSlotBytes } -> std::convertible_to<std::size_t>;
  { port.read(slot, offset, out) } -> std::same_as<StorageStatus>;
  { port.erase(slot) } -> std::same_as<StorageStatus>;
  { port.write(slot, offset, in) } -> std::same_as<StorageStatus>;
};

template <class T>
concept CameraPort = requires(T& port, const T& const_port, FrameUse use, std::uint64_t& exposure_us,
                              std::span<std::uint8_t> row) {
  { const_port.width_px() } -> std::same_as<std::uint16_t>;
  { const_port.height_px() } -> std::same_as<std::uint16_t>;
  { port.begin_frame(use, exposure_us) } -> std::same_as<CaptureStatus>;
  { port.read_row(row) } -> std::same_as<CaptureStatus>;
};

template <class T>
concept RangerPort = requires(T& port, std::array<std::uint32_t, shared::kRangers>& ranges_um, std::uint64_t& time_us) {
  { port.read(ranges_um, time_us) } -> std::same_as<RangerStatus>;
};

template <class T>
concept MeasurementStep = requires(T& step, const MeasureRequest& request, const ParameterSet& parameters,
                                   std::uint64_t now_us, shared::MeasurementReport& report) {
  { step.start(request, parameters, now_us) } -> std::same_as<MeasureStart>;
  { step.poll(now_us, report) } -> std::same_as<bool>;
};

template <class T>
concept CorrectionStep = requires(T& step, const shared::CorrectionParameters& parameters, const JointRaw& in,
                                  JointRaw& out) {
  { step.correct(parameters, in, out) } -> std::same_as<CorrectStatus>;
};

}  // namespace kincal::app

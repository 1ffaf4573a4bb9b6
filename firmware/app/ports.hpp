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
//   MeasurementStep  start(request, parameters, now) begins one measurement (the camera rows,
//                    rangers, labeler and geometry behind it are the step's business);
//                    poll(now, report) -> true once the report is filled. One at a time.
//   CorrectionStep   correct(parameters, in, out): corrected joint targets for one joint state.
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
enum class [[nodiscard]] CorrectStatus : std::uint8_t{kOk, kNoParameters};

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

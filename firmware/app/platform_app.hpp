// The sensor platform's application: protocol dispatch, the platform state machine,
// measurement scheduling, the correction stream, parameter upload/download and storage, the
// heartbeat and the rate-limited error reports. Board-independent: it runs on the STM32F407,
// as a Linux process (firmware/platform/native) and in tests, bound to their ports at compile
// time (firmware/app/ports.hpp).
//
// State machine (Heartbeat.state):
//   kStartup --start()--> kIdle, or kFault if a parameter slot could not be read
//   kIdle <--ModeCommand--> kRunning (measure and/or correct enabled; both off = idle)
//   kFault --ModeCommand clear_errors--> kIdle
// Dispatch, per received frame (frames outside the protocol block 0x100..0x17F are ignored: the
// bus may carry other nodes' traffic; IDs the platform itself sends are ignored too):
//   ModeCommand      applies the mode; clear_errors clears the latched error flags
//   MeasureTrigger   starts a measurement if measuring is enabled and none is in flight (else
//                    ErrorReport kNotInMode / kBusy); its report goes out by ISO-TP
//   JointState A+B / Fd   corrected by the CorrectionStep and answered with Corrected A+B / Fd
//                    carrying the same sequence number (kNotInMode, kNoParameters, kSequence;
//                    kBadValue for a target the correction cannot serve)
//   ISO-TP request   ParameterWrite (answered by ParameterAck), ParameterRead (ParameterData)
//   anything else in the block, or a malformed frame: ErrorReport with the reason. Reports are
//   sent at most once per error_report_interval_us; rejections in between are counted in it.
// Memory: everything is inside the object (about 10 KiB: ISO-TP buffers, the parameter set,
// one encoded report, one parameter message, a 16-frame transmit queue); construct it once,
// statically. No heap.
// Cost: on_frame() is O(frame) except for a completed parameter write (CRC, storage write and
// read-back of at most 2 KiB) and a completed measurement (encoding, <= 562 bytes); poll() moves
// at most 16 ISO-TP frames.
// Thread/ISR safety: not reentrant; call on_frame() and poll() from the main loop only (a
// board's receive ISR queues frames for it).
// Failure modes: none escape: every bad input is answered on the bus and counted in the
// heartbeat (rejected_frames, error flags); a full transmit path drops the frame and latches
// kTxOverflow.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "firmware/app/frame_queue.hpp"
#include "firmware/app/parameter_store.hpp"
#include "firmware/app/ports.hpp"
#include "firmware/core/isotp.hpp"
#include "shared/measurement_report.hpp"
#include "shared/parameters.hpp"
#include "shared/protocol.hpp"

namespace kincal::app {

struct AppConfig {
  bool fd = false;                           // CAN FD bus: ISO-TP frames of up to 64 bytes
  bool isotp_padding = true;                 // pad ISO-TP frames to 8 bytes with 0xCC
  std::uint8_t isotp_block_size = 0;         // BS announced to the host
  std::uint8_t isotp_st_min_raw = 0;         // STmin announced to the host (ISO encoding)
  std::uint32_t isotp_timeout_us = 1000000;  // N_Bs and N_Cr
  std::uint16_t board_error_flags = 0;       // flags the board sets (e.g. kClockFallback)
  std::uint32_t error_report_interval_us = 10000;
};

shared::ErrorReason reason_for(shared::DecodeStatus status);
// kNoParameters -> kNoParameters; kNotCorrectable -> kBadValue (the joint target is outside what
// the correction can serve).
shared::ErrorReason reason_for(CorrectStatus status);
// The reason an ISO-TP event is reported with, or 0 if the event is not an error.
std::uint8_t reason_for(core::IsoTpEvent event);
core::IsoTpConfig isotp_config(const AppConfig& config);

// Aggregates rejected frames into rate-limited ErrorReports.
class RejectionTracker {
 public:
  void reject(shared::ErrorReason reason, std::uint32_t id);
  // A report is due if something was rejected and the interval since the last report passed.
  bool take_report(std::uint64_t now_us, std::uint32_t interval_us, shared::ErrorReport& out);
  std::uint8_t rejected_frames() const { return total_; }

 private:
  shared::ErrorReason reason_ = shared::ErrorReason::kUnknownId;
  std::uint16_t id_ = 0;
  std::uint8_t pending_ = 0;
  std::uint8_t total_ = 0;
  bool sent_once_ = false;
  std::uint64_t last_report_us_ = 0;
};

template <CanPort Can, StoragePort Storage, MeasurementStep Measure, CorrectionStep Correct>
class PlatformApp {
 public:
  static constexpr std::size_t kTxQueueFrames = 16;
  static constexpr std::size_t kIsoTpFramesPerPoll = 16;

  PlatformApp(const AppConfig& config, Can& can, Storage& storage, Measure& measure, Correct& correct)
      : config_(config),
        can_(can),
        store_(storage),
        measure_(measure),
        correct_(correct),
        isotp_(isotp_config(config), isotp_buffers_) {}

  // Loads the parameter blocks from storage and enters kIdle (or kFault).
  void start(std::uint64_t now_us) {
    bool storage_ok = true;
    for (std::uint8_t b = 1; b <= shared::kParameterBlockCount; ++b) {
      const auto block = static_cast<shared::ParameterBlock>(b);
      const LoadResult r = store_.load(block, scratch_);
      if (r.status == StoreStatus::kStorageFailed) storage_ok = false;
      if (r.status != StoreStatus::kOk || r.version != shared::kBlockFormatVersion) continue;
      if (apply_block(block, std::span<const std::uint8_t>(scratch_).first(r.length))) sequences_[b - 1] = r.sequence;
    }
    if (!storage_ok) latched_ |= shared::error_flag::kStorageFailure;
    state_ = storage_ok ? shared::PlatformState::kIdle : shared::PlatformState::kFault;
    next_heartbeat_us_ = now_us;
  }

  void on_frame(const CanFrame& frame, std::uint64_t now_us) {
    if (frame.extended || frame.id < shared::can_id::kBlockFirst || frame.id > shared::can_id::kBlockLast) return;
    switch (frame.id) {
      case shared::can_id::kModeCommand:
        return on_mode(frame);
      case shared::can_id::kMeasureTrigger:
        return on_trigger(frame, now_us);
      case shared::can_id::kJointStateA:
      case shared::can_id::kJointStateB:
        return on_joint_half(frame);
      case shared::can_id::kJointStateFd:
        return on_joint_full(frame);
      case shared::can_id::kIsoTpRequest:
        return on_isotp(frame, now_us);
      case shared::can_id::kCorrectedA:
      case shared::can_id::kCorrectedB:
      case shared::can_id::kCorrectedFd:
      case shared::can_id::kParameterAck:
      case shared::can_id::kErrorReport:
      case shared::can_id::kIsoTpResponse:
      case shared::can_id::kHeartbeat:
        return;  // our own messages (e.g. echoed by a loopback interface)
      default:
        return reject(shared::ErrorReason::kUnknownId, frame.id);
    }
  }

  // Timers, measurement progress, ISO-TP transmission, heartbeat and error reports; then flushes
  // what is queued to the CAN port. Call it at least every millisecond while busy.
  void poll(std::uint64_t now_us) {
    const std::uint8_t timeout_reason = reason_for(isotp_.check_timeouts(now_us));
    if (timeout_reason != 0) {
      latched_ |= shared::error_flag::kIsoTpError;
      reject(static_cast<shared::ErrorReason>(timeout_reason), shared::can_id::kIsoTpRequest);
    }
    if (measuring_ && measure_.poll(now_us, report_)) finish_measurement();
    if (report_pending_ && !isotp_.tx_busy()) {
      if (isotp_.start_send(std::span<const std::uint8_t>(report_bytes_).first(report_length_), now_us) ==
          core::IsoTpSendStatus::kOk) {
        report_pending_ = false;
        ++measurements_;
      }
    }
    if (now_us >= next_heartbeat_us_) {
      queue(heartbeat());
      next_heartbeat_us_ = now_us + shared::kHeartbeatPeriodMs * 1000u;
    }
    shared::ErrorReport report;
    if (rejections_.take_report(now_us, config_.error_report_interval_us, report)) {
      CanFrame f;
      shared::encode(report, f);
      queue(f);
    }
    flush(now_us);
  }

  // The board reports frames its receive queue had to drop.
  void note_rx_overflow() { latched_ |= shared::error_flag::kRxOverflow; }

  shared::PlatformState state() const { return state_; }
  std::uint16_t error_flags() const { return current_flags(); }
  const ParameterSet& parameters() const { return parameters_; }
  const core::IsoTpStats& isotp_stats() const { return isotp_.stats(); }
  std::uint8_t rejected_frames() const { return rejections_.rejected_frames(); }
  // When poll() next has timed work (ISO-TP STmin/timeouts, heartbeat); a board may sleep until then.
  std::uint64_t next_deadline_us() const {
    const std::uint64_t isotp = isotp_.next_deadline_us();
    std::uint64_t next = isotp < next_heartbeat_us_ ? isotp : next_heartbeat_us_;
    if (measuring_ || report_pending_ || !tx_queue_.empty() || held_isotp_) next = 0;
    return next;
  }

 private:
  void reject(shared::ErrorReason reason, std::uint32_t id) {
    rejections_.reject(reason, id);
    if (reason != shared::ErrorReason::kNotInMode && reason != shared::ErrorReason::kBusy &&
        reason != shared::ErrorReason::kNoParameters)
      latched_ |= shared::error_flag::kMalformedFrame;
  }

  void on_mode(const CanFrame& frame) {
    shared::ModeCommand m;
    const shared::DecodeStatus status = shared::decode(frame, m);
    if (status != shared::DecodeStatus::kOk) return reject(reason_for(status), frame.id);
    if (m.clear_errors) {
      latched_ = 0;
      if (state_ == shared::PlatformState::kFault) state_ = shared::PlatformState::kIdle;
    }
    if (state_ == shared::PlatformState::kFault || state_ == shared::PlatformState::kStartup) {
      if (m.measure_enable || m.correct_enable) reject(shared::ErrorReason::kNotInMode, frame.id);
      return;
    }
    measure_enabled_ = m.measure_enable;
    correct_enabled_ = m.correct_enable;
    have_half_a_ = false;
    state_ = (measure_enabled_ || correct_enabled_) ? shared::PlatformState::kRunning : shared::PlatformState::kIdle;
  }

  void on_trigger(const CanFrame& frame, std::uint64_t now_us) {
    shared::MeasureTrigger t;
    const shared::DecodeStatus status = shared::decode(frame, t);
    if (status != shared::DecodeStatus::kOk) return reject(reason_for(status), frame.id);
    if (!measure_enabled_) return reject(shared::ErrorReason::kNotInMode, frame.id);
    if (measuring_ || report_pending_) return reject(shared::ErrorReason::kBusy, frame.id);
    if (measure_.start({t.sequence, t.sections}, parameters_, now_us) != MeasureStart::kStarted)
      return reject(shared::ErrorReason::kBusy, frame.id);
    measuring_ = true;
    trigger_sequence_ = t.sequence;
  }

  void finish_measurement() {
    measuring_ = false;
    report_.sequence = trigger_sequence_;
    if (report_.status == shared::MeasureStatus::kCameraFailure ||
        report_.status == shared::MeasureStatus::kRangerFailure)
      latched_ |= shared::error_flag::kMeasurementFailed;
    report_length_ = shared::encode(report_, report_bytes_);
    report_pending_ = report_length_ != 0;
  }

  bool correction_ready(std::uint32_t id) {
    if (!correct_enabled_) {
      reject(shared::ErrorReason::kNotInMode, id);
      return false;
    }
    if (!parameters_.has_correction) {
      reject(shared::ErrorReason::kNoParameters, id);
      return false;
    }
    return true;
  }

  void on_joint_half(const CanFrame& frame) {
    shared::JointHalf half;
    const shared::DecodeStatus status = shared::decode_joint_half(frame.id, frame, half);
    if (status != shared::DecodeStatus::kOk) return reject(reason_for(status), frame.id);
    if (!correction_ready(frame.id)) return;
    if (frame.id == shared::can_id::kJointStateA) {
      if (have_half_a_) reject(shared::ErrorReason::kSequence, frame.id);  // the previous A lost its B
      half_a_ = half;
      have_half_a_ = true;
      return;
    }
    if (!have_half_a_ || half_a_.sequence != half.sequence) {
      have_half_a_ = false;
      return reject(shared::ErrorReason::kSequence, frame.id);
    }
    have_half_a_ = false;
    JointRaw in{}, out{};
    for (std::size_t j = 0; j < shared::kJointsPerClassicFrame; ++j) {
      in[j] = half_a_.angle_raw[j];
      in[j + shared::kJointsPerClassicFrame] = half.angle_raw[j];
    }
    const CorrectStatus corrected = correct_.correct(parameters_.correction, in, out);
    if (corrected != CorrectStatus::kOk) return reject(reason_for(corrected), frame.id);
    shared::JointHalf a, b;
    a.sequence = b.sequence = half.sequence;
    for (std::size_t j = 0; j < shared::kJointsPerClassicFrame; ++j) {
      a.angle_raw[j] = out[j];
      b.angle_raw[j] = out[j + shared::kJointsPerClassicFrame];
    }
    CanFrame fa, fb;
    shared::encode_joint_half(shared::can_id::kCorrectedA, a, fa);
    shared::encode_joint_half(shared::can_id::kCorrectedB, b, fb);
    queue(fa);
    queue(fb);
    ++corrections_;
  }

  void on_joint_full(const CanFrame& frame) {
    shared::JointFull full;
    const shared::DecodeStatus status = shared::decode_joint_full(frame.id, frame, full);
    if (status != shared::DecodeStatus::kOk) return reject(reason_for(status), frame.id);
    if (!correction_ready(frame.id)) return;
    shared::JointFull out;
    out.sequence = full.sequence;
    const CorrectStatus corrected = correct_.correct(parameters_.correction, full.angle_raw, out.angle_raw);
    if (corrected != CorrectStatus::kOk) return reject(reason_for(corrected), frame.id);
    CanFrame f;
    shared::encode_joint_full(shared::can_id::kCorrectedFd, out, f);
    queue(f);
    ++corrections_;
  }

  void on_isotp(const CanFrame& frame, std::uint64_t now_us) {
    const core::IsoTpEvent event = isotp_.on_frame(frame, now_us);
    if (event == core::IsoTpEvent::kRxComplete) return on_request(isotp_.message(), now_us);
    const std::uint8_t reason = reason_for(event);
    if (reason != 0) {
      latched_ |= shared::error_flag::kIsoTpError;
      reject(static_cast<shared::ErrorReason>(reason), frame.id);
    }
  }

  void on_request(std::span<const std::uint8_t> message, std::uint64_t now_us) {
    if (message.empty()) return reject(shared::ErrorReason::kUnknownMessage, shared::can_id::kIsoTpRequest);
    if (message[0] == static_cast<std::uint8_t>(shared::MessageType::kParameterWrite))
      return on_parameter_write(message);
    if (message[0] == static_cast<std::uint8_t>(shared::MessageType::kParameterRead))
      return on_parameter_read(message, now_us);
    reject(shared::ErrorReason::kUnknownMessage, shared::can_id::kIsoTpRequest);
  }

  void ack(std::uint8_t block, shared::AckStatus status, bool read) {
    shared::ParameterAck a;
    a.block = block;
    a.status = status;
    a.read = read;
    a.slot_sequence = shared::is_known_block(block) ? sequences_[block - 1] : 0;
    CanFrame f;
    shared::encode(a, f);
    queue(f);
  }

  void on_parameter_write(std::span<const std::uint8_t> message) {
    shared::ParameterHeader header;
    std::span<const std::uint8_t> payload;
    if (shared::decode_parameter_message(message, header, payload) != shared::DecodeStatus::kOk)
      return reject(shared::ErrorReason::kUnknownMessage, shared::can_id::kIsoTpRequest);
    shared::AckStatus status = shared::check_parameter_payload(header, payload);
    if (status == shared::AckStatus::kOk && state_ != shared::PlatformState::kIdle &&
        state_ != shared::PlatformState::kFault)
      status = shared::AckStatus::kNotIdle;
    const auto block = static_cast<shared::ParameterBlock>(header.block);
    if (status == shared::AckStatus::kOk && !valid_block(block, payload)) status = shared::AckStatus::kBadValue;
    if (status == shared::AckStatus::kOk) {
      std::uint32_t sequence = 0;
      if (store_.save(block, header.version, payload, sequence) != StoreStatus::kOk) {
        latched_ |= shared::error_flag::kStorageFailure;
        status = shared::AckStatus::kStorageFailure;
      } else if (apply_block(block, payload)) {
        sequences_[header.block - 1] = sequence;
      }
    }
    ack(header.block, status, false);
  }

  void on_parameter_read(std::span<const std::uint8_t> message, std::uint64_t now_us) {
    std::uint8_t b = 0;
    if (shared::decode_parameter_read(message, b) != shared::DecodeStatus::kOk)
      return reject(shared::ErrorReason::kUnknownMessage, shared::can_id::kIsoTpRequest);
    if (!shared::is_known_block(b)) return ack(b, shared::AckStatus::kUnknownBlock, true);
    const auto block = static_cast<shared::ParameterBlock>(b);
    // The block image goes where the message's payload belongs, so the message is built in
    // place (encode_parameter_message copies each payload byte onto itself).
    const auto image = std::span<std::uint8_t>(scratch_).subspan(shared::kParameterHeaderBytes);
    const std::size_t n = encode_block(block, image);
    if (n == 0) return ack(b, shared::AckStatus::kMissing, true);
    if (isotp_.tx_busy() || report_pending_) return ack(b, shared::AckStatus::kBusy, true);
    const std::size_t length =
        shared::encode_parameter_message(shared::MessageType::kParameterData, block, image.first(n), scratch_);
    if (length == 0 ||
        isotp_.start_send(std::span<const std::uint8_t>(scratch_).first(length), now_us) != core::IsoTpSendStatus::kOk)
      ack(b, shared::AckStatus::kBusy, true);
  }

  // Decodes a block into a temporary to judge it before it is stored.
  static bool valid_block(shared::ParameterBlock block, std::span<const std::uint8_t> payload) {
    switch (block) {
      case shared::ParameterBlock::kIntrinsics: {
        shared::CameraIntrinsics v;
        return shared::decode_block(payload, v) == shared::DecodeStatus::kOk;
      }
      case shared::ParameterBlock::kColourLut:
        return payload.size() == shared::kColourLutBytes;
      case shared::ParameterBlock::kGeometry: {
        shared::PlatformGeometry v;
        return shared::decode_block(payload, v) == shared::DecodeStatus::kOk;
      }
      case shared::ParameterBlock::kCorrection:  // judged in place: the block is ~700 bytes
        return shared::check_correction_block(payload) == shared::DecodeStatus::kOk;
    }
    return false;
  }

  bool apply_block(shared::ParameterBlock block, std::span<const std::uint8_t> payload) {
    switch (block) {
      case shared::ParameterBlock::kIntrinsics:
        return parameters_.has_intrinsics =
                   shared::decode_block(payload, parameters_.intrinsics) == shared::DecodeStatus::kOk;
      case shared::ParameterBlock::kColourLut:
        return parameters_.has_colour_lut =
                   shared::decode_block(payload, parameters_.colour_lut) == shared::DecodeStatus::kOk;
      case shared::ParameterBlock::kGeometry:
        return parameters_.has_geometry =
                   shared::decode_block(payload, parameters_.geometry) == shared::DecodeStatus::kOk;
      case shared::ParameterBlock::kCorrection:
        return parameters_.has_correction =
                   shared::decode_block(payload, parameters_.correction) == shared::DecodeStatus::kOk;
    }
    return false;
  }

  // The RAM copy of a block as a byte image; 0 if there is none.
  std::size_t encode_block(shared::ParameterBlock block, std::span<std::uint8_t> out) const {
    switch (block) {
      case shared::ParameterBlock::kIntrinsics:
        return parameters_.has_intrinsics ? shared::encode_block(parameters_.intrinsics, out) : 0;
      case shared::ParameterBlock::kColourLut:
        return parameters_.has_colour_lut ? shared::encode_block(parameters_.colour_lut, out) : 0;
      case shared::ParameterBlock::kGeometry:
        return parameters_.has_geometry ? shared::encode_block(parameters_.geometry, out) : 0;
      case shared::ParameterBlock::kCorrection:
        return parameters_.has_correction ? shared::encode_block(parameters_.correction, out) : 0;
    }
    return 0;
  }

  std::uint16_t current_flags() const {
    std::uint16_t flags = static_cast<std::uint16_t>(latched_ | config_.board_error_flags);
    if (!parameters_.has_intrinsics) flags |= shared::error_flag::kNoIntrinsics;
    if (!parameters_.has_colour_lut) flags |= shared::error_flag::kNoColourLut;
    if (!parameters_.has_geometry) flags |= shared::error_flag::kNoGeometry;
    if (!parameters_.has_correction) flags |= shared::error_flag::kNoCorrection;
    const CanHealth health = can_.health();
    if (health.error_passive) flags |= shared::error_flag::kCanErrorPassive;
    if (health.bus_off_events != 0) flags |= shared::error_flag::kCanBusOffRecovered;
    return flags;
  }

  CanFrame heartbeat() {
    shared::Heartbeat h;
    h.state = state_;
    h.measure_enabled = measure_enabled_;
    h.correct_enabled = correct_enabled_;
    h.counter = heartbeat_counter_;
    heartbeat_counter_ = static_cast<std::uint8_t>((heartbeat_counter_ + 1u) & 0xFu);
    h.error_flags = current_flags();
    h.rejected_frames = rejections_.rejected_frames();
    h.measurements = measurements_;
    h.corrections = corrections_;
    h.can_tx_errors = can_.health().tx_error_count;
    CanFrame f;
    shared::encode(h, f);
    return f;
  }

  void queue(const CanFrame& frame) {
    if (!tx_queue_.push(frame)) latched_ |= shared::error_flag::kTxOverflow;
  }

  // Protocol frames first (they are few and time-critical), then ISO-TP frames.
  void flush(std::uint64_t now_us) {
    while (!tx_queue_.empty()) {
      if (!can_.try_send(tx_queue_.front())) return;
      tx_queue_.pop();
    }
    if (held_isotp_) {
      if (!can_.try_send(held_frame_)) return;
      held_isotp_ = false;
    }
    for (std::size_t i = 0; i < kIsoTpFramesPerPoll; ++i) {
      if (!isotp_.next_frame(now_us, held_frame_)) return;
      if (!can_.try_send(held_frame_)) {
        held_isotp_ = true;
        return;
      }
    }
  }

  AppConfig config_;
  Can& can_;
  ParameterStore<Storage> store_;
  Measure& measure_;
  Correct& correct_;

  core::IsoTpBuffers<shared::kMaxRequestBytes, shared::kMaxResponseBytes> isotp_buffers_;
  core::IsoTpEndpoint isotp_;
  FrameQueue<kTxQueueFrames> tx_queue_;
  CanFrame held_frame_;
  bool held_isotp_ = false;

  shared::PlatformState state_ = shared::PlatformState::kStartup;
  bool measure_enabled_ = false;
  bool correct_enabled_ = false;
  std::uint16_t latched_ = 0;
  RejectionTracker rejections_;
  std::uint8_t heartbeat_counter_ = 0;
  std::uint64_t next_heartbeat_us_ = 0;
  std::uint8_t measurements_ = 0;
  std::uint8_t corrections_ = 0;

  ParameterSet parameters_;
  std::array<std::uint32_t, shared::kParameterBlockCount> sequences_{};
  std::array<std::uint8_t, shared::kMaxParameterMessageBytes> scratch_{};

  bool measuring_ = false;
  std::uint8_t trigger_sequence_ = 0;
  shared::MeasurementReport report_;
  std::array<std::uint8_t, shared::kMaxReportBytes> report_bytes_{};
  std::size_t report_length_ = 0;
  bool report_pending_ = false;

  shared::JointHalf half_a_;
  bool have_half_a_ = false;
};

}  // namespace kincal::app

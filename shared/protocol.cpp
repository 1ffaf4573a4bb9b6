#include "shared/protocol.hpp"

#include "shared/bit_field.hpp"

namespace kincal::shared {

namespace {

constexpr double kJointLsb = 1.0 / 65536.0;
constexpr const char* kJointComment =
    "signed 20 bits, LSB 2^-16 rad = 15.3 urad, range [-8, 8) rad: covers +-450 deg wrist joints; "
    "15 um at 1 m reach, an order below a calibrated arm's accuracy";

constexpr Signal kModeSignals[] = {
    {"measure_enable", 0, 1, false, 1, 0, "", "1: accept measurement triggers"},
    {"correct_enable", 1, 1, false, 1, 0, "", "1: correct the joint-state stream"},
    {"clear_errors", 2, 1, false, 1, 0, "", "1: clear the latched error flags"},
};

constexpr Signal kJointASignals[] = {
    {"joint0_angle", 0, 20, true, kJointLsb, 0, "rad", kJointComment},
    {"joint1_angle", 20, 20, true, kJointLsb, 0, "rad", kJointComment},
    {"joint2_angle", 40, 20, true, kJointLsb, 0, "rad", kJointComment},
    {"sequence", 60, 4, false, 1, 0, "", "4 bits: pairs halves A and B and the output with its input"},
};
constexpr Signal kJointBSignals[] = {
    {"joint3_angle", 0, 20, true, kJointLsb, 0, "rad", kJointComment},
    {"joint4_angle", 20, 20, true, kJointLsb, 0, "rad", kJointComment},
    {"joint5_angle", 40, 20, true, kJointLsb, 0, "rad", kJointComment},
    {"sequence", 60, 4, false, 1, 0, "", "4 bits: pairs halves A and B and the output with its input"},
};
constexpr Signal kJointFdSignals[] = {
    {"joint0_angle", 0, 20, true, kJointLsb, 0, "rad", kJointComment},
    {"joint1_angle", 20, 20, true, kJointLsb, 0, "rad", kJointComment},
    {"joint2_angle", 40, 20, true, kJointLsb, 0, "rad", kJointComment},
    {"joint3_angle", 60, 20, true, kJointLsb, 0, "rad", kJointComment},
    {"joint4_angle", 80, 20, true, kJointLsb, 0, "rad", kJointComment},
    {"joint5_angle", 100, 20, true, kJointLsb, 0, "rad", kJointComment},
    {"sequence", 120, 8, false, 1, 0, "", "8 bits: ties the corrected output to its input"},
};

constexpr Signal kTriggerSignals[] = {
    {"sequence", 0, 8, false, 1, 0, "", "echoed by the report; 256 triggers = 8.5 s at 30 Hz before it wraps"},
    {"sections", 8, 6, false, 1, 0, "",
     "bit 0 ranges, 1 plane, 2 fiducials, 3 camera pose, 4 blob list, 5 triangulated point"},
};

constexpr Signal kAckSignals[] = {
    {"block", 0, 4, false, 1, 0, "", "1 intrinsics, 2 colour LUT, 3 platform geometry, 4 correction"},
    {"status", 4, 4, false, 1, 0, "",
     "0 ok, 1 CRC mismatch, 2 bad length, 3 bad version, 4 bad value, 5 storage failure, 6 busy, 7 not idle, "
     "8 unknown block, 9 missing"},
    {"read", 8, 1, false, 1, 0, "", "1: answers a read, 0: answers a write"},
    {"slot_sequence", 9, 32, false, 1, 0, "", "storage sequence number of the active copy of the block"},
};

constexpr Signal kErrorSignals[] = {
    {"reason", 0, 8, false, 1, 0, "",
     "1 unknown ID, 2 wrong length, 3 wrong format, 4 bad value, 5 sequence, 6 not in mode, 7 no parameters, "
     "8 busy, 9 ISO-TP protocol, 10 ISO-TP timeout, 11 ISO-TP overflow, 12 unknown message"},
    {"offending_id", 8, 11, false, 1, 0, "", "11-bit ID of the last rejected frame"},
    {"count", 19, 8, false, 1, 0, "", "rejections since the previous report, saturating at 255"},
};

constexpr Signal kHeartbeatSignals[] = {
    {"state", 0, 2, false, 1, 0, "", "0 startup, 1 idle, 2 running, 3 fault"},
    {"measure_enabled", 2, 1, false, 1, 0, "", ""},
    {"correct_enabled", 3, 1, false, 1, 0, "", ""},
    {"counter", 4, 4, false, 1, 0, "", "+1 per heartbeat: a missed heartbeat shows"},
    {"version_major", 8, 4, false, 1, 0, "", "protocol major version"},
    {"version_minor", 12, 4, false, 1, 0, "", "protocol minor version"},
    {"error_flags", 16, 16, false, 1, 0, "", "error_flag bits of shared/protocol.hpp"},
    {"rejected_frames", 32, 8, false, 1, 0, "", "wrapping count of rejected frames"},
    {"measurements", 40, 8, false, 1, 0, "", "wrapping count of measurement reports sent"},
    {"corrections", 48, 8, false, 1, 0, "", "wrapping count of corrected joint states sent"},
    {"can_tx_errors", 56, 8, false, 1, 0, "", "CAN transmit error counter, saturating at 255"},
};

constexpr MessageSpec kMessages[] = {
    {can_id::kModeCommand, "ModeCommand", Direction::kHostToPlatform, false, 1, kModeSignals,
     "enables measurement and correction; both 0 = idle"},
    {can_id::kJointStateA, "JointStateA", Direction::kHostToPlatform, false, 8, kJointASignals,
     "joint state input, joints 0..2 (classic CAN)"},
    {can_id::kJointStateB, "JointStateB", Direction::kHostToPlatform, false, 8, kJointBSignals,
     "joint state input, joints 3..5 (classic CAN); completes the pair with the same sequence"},
    {can_id::kJointStateFd, "JointStateFd", Direction::kHostToPlatform, true, 16, kJointFdSignals,
     "joint state input, all joints (CAN FD)"},
    {can_id::kCorrectedA, "CorrectedA", Direction::kPlatformToHost, false, 8, kJointASignals,
     "corrected joint targets, joints 0..2 (classic CAN)"},
    {can_id::kCorrectedB, "CorrectedB", Direction::kPlatformToHost, false, 8, kJointBSignals,
     "corrected joint targets, joints 3..5 (classic CAN)"},
    {can_id::kCorrectedFd, "CorrectedFd", Direction::kPlatformToHost, true, 16, kJointFdSignals,
     "corrected joint targets, all joints (CAN FD)"},
    {can_id::kMeasureTrigger, "MeasureTrigger", Direction::kHostToPlatform, false, 2, kTriggerSignals,
     "starts one measurement; the report comes by ISO-TP on 0x158"},
    {can_id::kParameterAck, "ParameterAck", Direction::kPlatformToHost, false, 6, kAckSignals,
     "answers a parameter write, or a read that failed"},
    {can_id::kErrorReport, "ErrorReport", Direction::kPlatformToHost, false, 4, kErrorSignals,
     "a rejected frame or message; at most one per 10 ms, counts aggregated"},
    {can_id::kHeartbeat, "Heartbeat", Direction::kPlatformToHost, false, 8, kHeartbeatSignals,
     "platform status every 100 ms"},
};

// Every layout fits its frame and no two signals overlap.
constexpr bool layouts_are_sound() {
  for (const MessageSpec& m : kMessages) {
    if (!is_valid_length(m.fd, m.length)) return false;
    std::array<bool, 512> used{};
    for (const Signal& s : m.signals) {
      if (s.bits == 0 || s.bits > 32 || s.start_bit + s.bits > m.length * 8) return false;
      for (unsigned b = s.start_bit; b < s.start_bit + s.bits; ++b) {
        if (used[b]) return false;
        used[b] = true;
      }
    }
  }
  return true;
}
static_assert(layouts_are_sound(), "a single-frame layout overlaps or does not fit its frame");

template <std::size_t N>
void encode_values(std::uint32_t id, const std::array<std::int64_t, N>& raw, CanFrame& frame) {
  encode_raw(*find_message(id), raw, frame);
}

template <std::size_t N>
DecodeStatus decode_values(std::uint32_t id, const CanFrame& frame, std::array<std::int64_t, N>& raw) {
  const MessageSpec* spec = find_message(id);
  if (spec == nullptr || spec->signals.size() != N) return DecodeStatus::kWrongId;
  return decode_raw(*spec, frame, raw);
}

bool is_joint_half_id(std::uint32_t id) {
  return id == can_id::kJointStateA || id == can_id::kJointStateB || id == can_id::kCorrectedA ||
         id == can_id::kCorrectedB;
}
bool is_joint_full_id(std::uint32_t id) { return id == can_id::kJointStateFd || id == can_id::kCorrectedFd; }

}  // namespace

std::span<const MessageSpec> single_frame_messages() { return kMessages; }

const MessageSpec* find_message(std::uint32_t id) {
  for (const MessageSpec& m : kMessages)
    if (m.id == id) return &m;
  return nullptr;
}

void encode_raw(const MessageSpec& spec, std::span<const std::int64_t> raw, CanFrame& frame) {
  frame = CanFrame{};
  frame.id = spec.id;
  frame.fd = spec.fd;
  frame.brs = spec.fd;
  frame.length = spec.length;
  const std::span<std::uint8_t> bytes(frame.data.data(), spec.length);
  for (std::size_t i = 0; i < spec.signals.size() && i < raw.size(); ++i)
    put_bits(bytes, spec.signals[i].start_bit, spec.signals[i].bits, static_cast<std::uint64_t>(raw[i]));
}

DecodeStatus check_frame(const MessageSpec& spec, const CanFrame& frame) {
  if (frame.id != spec.id || frame.extended)
    return frame.extended ? DecodeStatus::kWrongFormat : DecodeStatus::kWrongId;
  if (frame.fd != spec.fd) return DecodeStatus::kWrongFormat;
  if (frame.length != spec.length) return DecodeStatus::kWrongLength;
  // Reserved bits: clear every signal's bits in a copy; what is left must be zero.
  std::array<std::uint8_t, CanFrame::kMaxFdBytes> rest = frame.data;
  const std::span<std::uint8_t> bytes(rest.data(), spec.length);
  for (const Signal& s : spec.signals) put_bits(bytes, s.start_bit, s.bits, 0);
  for (const std::uint8_t b : bytes)
    if (b != 0) return DecodeStatus::kBadValue;
  return DecodeStatus::kOk;
}

DecodeStatus decode_raw(const MessageSpec& spec, const CanFrame& frame, std::span<std::int64_t> raw) {
  const DecodeStatus status = check_frame(spec, frame);
  if (status != DecodeStatus::kOk) return status;
  const std::span<const std::uint8_t> bytes(frame.data.data(), spec.length);
  for (std::size_t i = 0; i < spec.signals.size() && i < raw.size(); ++i) {
    const Signal& s = spec.signals[i];
    const std::uint64_t v = get_bits(bytes, s.start_bit, s.bits);
    raw[i] = s.is_signed ? sign_extend(v, s.bits) : static_cast<std::int64_t>(v);
  }
  return DecodeStatus::kOk;
}

void encode(const ModeCommand& m, CanFrame& frame) {
  encode_values<3>(can_id::kModeCommand, {m.measure_enable, m.correct_enable, m.clear_errors}, frame);
}

DecodeStatus decode(const CanFrame& frame, ModeCommand& m) {
  std::array<std::int64_t, 3> raw{};
  const DecodeStatus status = decode_values(can_id::kModeCommand, frame, raw);
  if (status != DecodeStatus::kOk) return status;
  m = {raw[0] != 0, raw[1] != 0, raw[2] != 0};
  return DecodeStatus::kOk;
}

void encode_joint_half(std::uint32_t id, const JointHalf& m, CanFrame& frame) {
  if (!is_joint_half_id(id)) return;
  encode_values<4>(id, {m.angle_raw[0], m.angle_raw[1], m.angle_raw[2], m.sequence & 0xF}, frame);
}

DecodeStatus decode_joint_half(std::uint32_t id, const CanFrame& frame, JointHalf& m) {
  if (!is_joint_half_id(id)) return DecodeStatus::kWrongId;
  std::array<std::int64_t, 4> raw{};
  const DecodeStatus status = decode_values(id, frame, raw);
  if (status != DecodeStatus::kOk) return status;
  for (std::size_t j = 0; j < kJointsPerClassicFrame; ++j) m.angle_raw[j] = static_cast<std::int32_t>(raw[j]);
  m.sequence = static_cast<std::uint8_t>(raw[3]);
  return DecodeStatus::kOk;
}

void encode_joint_full(std::uint32_t id, const JointFull& m, CanFrame& frame) {
  if (!is_joint_full_id(id)) return;
  std::array<std::int64_t, kJoints + 1> raw{};
  for (std::size_t j = 0; j < kJoints; ++j) raw[j] = m.angle_raw[j];
  raw[kJoints] = m.sequence;
  encode_values(id, raw, frame);
}

DecodeStatus decode_joint_full(std::uint32_t id, const CanFrame& frame, JointFull& m) {
  if (!is_joint_full_id(id)) return DecodeStatus::kWrongId;
  std::array<std::int64_t, kJoints + 1> raw{};
  const DecodeStatus status = decode_values(id, frame, raw);
  if (status != DecodeStatus::kOk) return status;
  for (std::size_t j = 0; j < kJoints; ++j) m.angle_raw[j] = static_cast<std::int32_t>(raw[j]);
  m.sequence = static_cast<std::uint8_t>(raw[kJoints]);
  return DecodeStatus::kOk;
}

void encode(const MeasureTrigger& m, CanFrame& frame) {
  encode_values<2>(can_id::kMeasureTrigger, {m.sequence, m.sections & section::kAll}, frame);
}

DecodeStatus decode(const CanFrame& frame, MeasureTrigger& m) {
  std::array<std::int64_t, 2> raw{};
  const DecodeStatus status = decode_values(can_id::kMeasureTrigger, frame, raw);
  if (status != DecodeStatus::kOk) return status;
  m = {static_cast<std::uint8_t>(raw[0]), static_cast<std::uint8_t>(raw[1])};
  return DecodeStatus::kOk;
}

void encode(const ParameterAck& m, CanFrame& frame) {
  encode_values<4>(can_id::kParameterAck, {m.block & 0xF, static_cast<std::uint8_t>(m.status), m.read, m.slot_sequence},
                   frame);
}

DecodeStatus decode(const CanFrame& frame, ParameterAck& m) {
  std::array<std::int64_t, 4> raw{};
  const DecodeStatus status = decode_values(can_id::kParameterAck, frame, raw);
  if (status != DecodeStatus::kOk) return status;
  if (raw[1] > kMaxAckStatus) return DecodeStatus::kBadValue;
  m.block = static_cast<std::uint8_t>(raw[0]);
  m.status = static_cast<AckStatus>(raw[1]);
  m.read = raw[2] != 0;
  m.slot_sequence = static_cast<std::uint32_t>(raw[3]);
  return DecodeStatus::kOk;
}

void encode(const ErrorReport& m, CanFrame& frame) {
  encode_values<3>(can_id::kErrorReport, {static_cast<std::uint8_t>(m.reason), m.offending_id & 0x7FF, m.count}, frame);
}

DecodeStatus decode(const CanFrame& frame, ErrorReport& m) {
  std::array<std::int64_t, 3> raw{};
  const DecodeStatus status = decode_values(can_id::kErrorReport, frame, raw);
  if (status != DecodeStatus::kOk) return status;
  if (raw[0] < 1 || raw[0] > kMaxErrorReason) return DecodeStatus::kBadValue;
  m.reason = static_cast<ErrorReason>(raw[0]);
  m.offending_id = static_cast<std::uint16_t>(raw[1]);
  m.count = static_cast<std::uint8_t>(raw[2]);
  return DecodeStatus::kOk;
}

void encode(const Heartbeat& m, CanFrame& frame) {
  encode_values<11>(
      can_id::kHeartbeat,
      {static_cast<std::uint8_t>(m.state), m.measure_enabled, m.correct_enabled, m.counter & 0xF, m.version_major & 0xF,
       m.version_minor & 0xF, m.error_flags, m.rejected_frames, m.measurements, m.corrections, m.can_tx_errors},
      frame);
}

DecodeStatus decode(const CanFrame& frame, Heartbeat& m) {
  std::array<std::int64_t, 11> raw{};
  const DecodeStatus status = decode_values(can_id::kHeartbeat, frame, raw);
  if (status != DecodeStatus::kOk) return status;
  m.state = static_cast<PlatformState>(raw[0]);
  m.measure_enabled = raw[1] != 0;
  m.correct_enabled = raw[2] != 0;
  m.counter = static_cast<std::uint8_t>(raw[3]);
  m.version_major = static_cast<std::uint8_t>(raw[4]);
  m.version_minor = static_cast<std::uint8_t>(raw[5]);
  m.error_flags = static_cast<std::uint16_t>(raw[6]);
  m.rejected_frames = static_cast<std::uint8_t>(raw[7]);
  m.measurements = static_cast<std::uint8_t>(raw[8]);
  m.corrections = static_cast<std::uint8_t>(raw[9]);
  m.can_tx_errors = static_cast<std::uint8_t>(raw[10]);
  return DecodeStatus::kOk;
}

}  // namespace kincal::shared

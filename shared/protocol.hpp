// The kincal CAN protocol: the one source of truth for IDs, directions, layouts, fixed-point
// scalings, units and the protocol version. The firmware and the host compile these tables and
// codecs; the DBC file for standard CAN tools is generated from the same tables (`kincal dbc`),
// so no layout is written twice.
//
// Bus and framing
//   11-bit identifiers in one block, 0x100..0x17F (kBlockFirst..kBlockLast). The platform answers
//   a frame in the block with an unknown ID with an ErrorReport; frames outside the block belong
//   to other nodes and are ignored. Lower ID wins arbitration: mode commands first, then the
//   correction stream, then measurement traffic, then the heartbeat.
//   Single-frame messages (this file) have an exact length: any other length is rejected
//   (ErrorReport kWrongLength). Bits not covered by a signal are reserved and must be 0.
//   Longer messages (measurement reports, parameter blocks) travel by ISO 15765-2 (ISO-TP, normal
//   addressing) on kIsoTpRequest (host -> platform) and kIsoTpResponse (platform -> host), so the
//   Linux kernel's can-isotp is the host end; their payloads are in measurement_report.hpp and
//   parameters.hpp and start with a MessageType byte.
//   Bit order: Intel (little-endian) as in shared/bit_field.hpp; start bit = least significant bit.
//
// Joint angles (correction stream)
//   signed 20 bits, LSB 2^-16 rad (15.3 urad), range [-8, 8) rad (+-458 deg): covers the widest
//   common industrial wrist joints (+-450 deg); at 1 m reach one LSB is 15 um and the rounding
//   error (RMS LSB/sqrt(12) = 4.4 um) is an order below a calibrated arm's 50-100 um accuracy.
//   A binary LSB is exact in float and in the firmware's fixed point. 24 bits would add nothing
//   measurable and cost a third classic frame per direction.
//   Classic CAN: 6 joints = 2 frames of 3 x 20 bits + a 4-bit sequence number (exactly 64 bits);
//   the sequence pairs the halves and ties the corrected output to its input (wraps every 16
//   cycles, far longer than the 2-frame pairing window). CAN FD: one 16-byte frame, 6 x 20 bits +
//   an 8-bit sequence number (exactly 128 bits).
//
// Cost: the codecs are table-driven bit copies, O(bits), no heap. Thread/ISR safety: pure
// functions and constant tables. Failure modes: decoders return a DecodeStatus and never read
// past the frame; encoders of in-range structs cannot fail (out-of-range raw values are masked
// to their width, so callers quantize with quantize_joint_angle() & co., which saturate).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "shared/can_frame.hpp"

namespace kincal::shared {

// Major changes break the wire format; minor ones only add (new messages or reserved bits used).
// The heartbeat carries both; the host refuses a platform of another major version.
//   2.0: the measurement report's pose section carries the pose's covariance
//        (measurement_report.hpp); a 1.x report's pose section is 180 bits shorter.
//   3.0: 2.0 plus, at the start of the pose section, how many squares of the strip the pose
//        used (4 bits); a 2.x report's pose section is 4 bits shorter.
inline constexpr std::uint8_t kProtocolVersionMajor = 3;
inline constexpr std::uint8_t kProtocolVersionMinor = 0;

namespace can_id {
inline constexpr std::uint32_t kBlockFirst = 0x100;
inline constexpr std::uint32_t kBlockLast = 0x17F;
inline constexpr std::uint32_t kModeCommand = 0x100;     // host -> platform
inline constexpr std::uint32_t kJointStateA = 0x110;     // host -> platform, joints 0..2, classic
inline constexpr std::uint32_t kJointStateB = 0x111;     // host -> platform, joints 3..5, classic
inline constexpr std::uint32_t kJointStateFd = 0x112;    // host -> platform, joints 0..5, CAN FD
inline constexpr std::uint32_t kCorrectedA = 0x118;      // platform -> host
inline constexpr std::uint32_t kCorrectedB = 0x119;      // platform -> host
inline constexpr std::uint32_t kCorrectedFd = 0x11A;     // platform -> host, CAN FD
inline constexpr std::uint32_t kMeasureTrigger = 0x120;  // host -> platform
inline constexpr std::uint32_t kParameterAck = 0x130;    // platform -> host
inline constexpr std::uint32_t kErrorReport = 0x140;     // platform -> host
inline constexpr std::uint32_t kIsoTpRequest = 0x150;    // ISO-TP, host -> platform (and the host's flow control)
inline constexpr std::uint32_t kIsoTpResponse = 0x158;   // ISO-TP, platform -> host (and the platform's flow control)
inline constexpr std::uint32_t kHeartbeat = 0x170;       // platform -> host, every kHeartbeatPeriodMs
}  // namespace can_id

inline constexpr std::uint32_t kHeartbeatPeriodMs = 100;
inline constexpr std::size_t kJoints = 6;
inline constexpr std::size_t kJointsPerClassicFrame = 3;

enum class Direction : std::uint8_t { kHostToPlatform, kPlatformToHost };

// One field of a single-frame message: physical = raw * scale + offset, in `unit`.
struct Signal {
  const char* name;
  std::uint16_t start_bit;
  std::uint8_t bits;
  bool is_signed;
  double scale;
  double offset;
  const char* unit;
  const char* comment;  // resolution, range and why
};

struct MessageSpec {
  std::uint32_t id;
  const char* name;
  Direction direction;
  bool fd;              // sent as a CAN FD frame
  std::uint8_t length;  // exact payload length in bytes
  std::span<const Signal> signals;
  const char* comment;
};

// What a decoder says about a frame. Closed set: every decoder returns one of these.
enum class [[nodiscard]] DecodeStatus : std::uint8_t{
    kOk,
    kWrongId,      // not the message this decoder reads
    kWrongFormat,  // classic frame where FD is specified or the reverse, or an extended ID
    kWrongLength,  // payload length differs from the specification
    kBadValue,     // reserved bits set, or an enumeration or count out of its range
};

// Measurement result sections: the trigger asks for them, the report says which it carries.
namespace section {
inline constexpr std::uint8_t kRanges = 1u << 0;
inline constexpr std::uint8_t kPlane = 1u << 1;
inline constexpr std::uint8_t kFiducials = 1u << 2;
inline constexpr std::uint8_t kPose = 1u << 3;
inline constexpr std::uint8_t kBlobs = 1u << 4;
inline constexpr std::uint8_t kPoint = 1u << 5;
inline constexpr std::uint8_t kAll = 0x3F;
}  // namespace section

enum class PlatformState : std::uint8_t { kStartup = 0, kIdle = 1, kRunning = 2, kFault = 3 };

// Heartbeat error flags. "latched" flags stay set until a ModeCommand with clear_errors.
namespace error_flag {
inline constexpr std::uint16_t kNoIntrinsics = 1u << 0;        // parameter block missing
inline constexpr std::uint16_t kNoColourLut = 1u << 1;         // parameter block missing
inline constexpr std::uint16_t kNoGeometry = 1u << 2;          // parameter block missing
inline constexpr std::uint16_t kNoCorrection = 1u << 3;        // parameter block missing
inline constexpr std::uint16_t kStorageFailure = 1u << 4;      // latched: a storage read/write failed
inline constexpr std::uint16_t kCanErrorPassive = 1u << 5;     // controller is error passive now
inline constexpr std::uint16_t kCanBusOffRecovered = 1u << 6;  // latched: went bus-off and recovered
inline constexpr std::uint16_t kRxOverflow = 1u << 7;          // latched: received frames were dropped
inline constexpr std::uint16_t kIsoTpError = 1u << 8;          // latched: an ISO-TP transfer was aborted
inline constexpr std::uint16_t kMeasurementFailed = 1u << 9;   // latched: a measurement step failed
inline constexpr std::uint16_t kClockFallback = 1u << 10;      // MCU runs on its internal oscillator
inline constexpr std::uint16_t kMalformedFrame = 1u << 11;     // latched: a frame was rejected
inline constexpr std::uint16_t kTxOverflow = 1u << 12;         // latched: an outgoing frame was dropped
inline constexpr std::uint16_t kLatched = kStorageFailure | kCanBusOffRecovered | kRxOverflow | kIsoTpError |
                                          kMeasurementFailed | kMalformedFrame | kTxOverflow;
}  // namespace error_flag

// Why the platform rejected a frame (ErrorReport.reason). Closed set.
enum class ErrorReason : std::uint8_t {
  kUnknownId = 1,        // an ID in the protocol block that no message uses
  kWrongLength = 2,      // a known ID with the wrong payload length
  kWrongFormat = 3,      // classic/FD or standard/extended mismatch
  kBadValue = 4,         // reserved bits or an out-of-range value
  kSequence = 5,         // joint-state halves with different sequence numbers, or B without A
  kNotInMode = 6,        // e.g. a joint state while correction is disabled
  kNoParameters = 7,     // the request needs a parameter block the platform does not have
  kBusy = 8,             // a measurement is still running; the trigger was dropped
  kIsoTpProtocol = 9,    // malformed or out-of-sequence ISO-TP frame; the transfer was aborted
  kIsoTpTimeout = 10,    // an ISO-TP transfer timed out (N_Bs or N_Cr)
  kIsoTpOverflow = 11,   // an ISO-TP message longer than the platform's buffer
  kUnknownMessage = 12,  // an ISO-TP message with an unknown type or a malformed body
};
inline constexpr std::uint8_t kMaxErrorReason = 12;

enum class ParameterBlock : std::uint8_t { kIntrinsics = 1, kColourLut = 2, kGeometry = 3, kCorrection = 4 };
inline constexpr std::uint8_t kParameterBlockCount = 4;

enum class AckStatus : std::uint8_t {
  kOk = 0,
  kCrcMismatch = 1,     // the payload's CRC-32 differs from the one sent
  kBadLength = 2,       // the payload length is not the block's length
  kBadVersion = 3,      // the block's format version is not the one this firmware reads
  kBadValue = 4,        // a value in the block is out of range (non-finite float, count too large)
  kStorageFailure = 5,  // writing or verifying the storage slot failed; the previous copy remains
  kBusy = 6,            // an ISO-TP transfer is in progress; retry
  kNotIdle = 7,         // parameter writes are accepted only in the idle state
  kUnknownBlock = 8,
  kMissing = 9,  // read of a block the platform has no valid copy of
};
inline constexpr std::uint8_t kMaxAckStatus = 9;

// --- Physical scalings (see the signal comments for the reasons) ------------------------------

inline constexpr int kJointAngleBits = 20;
inline constexpr int kJointAngleFractionBits = 16;  // LSB 2^-16 rad

// Rounds to the nearest LSB (ties away from zero) and saturates to the signed 20-bit range; NaN -> 0.
template <class Real>
constexpr std::int32_t quantize_joint_angle(Real angle_rad) {
  if (!(angle_rad == angle_rad)) return 0;
  const Real scaled = angle_rad * static_cast<Real>(1 << kJointAngleFractionBits);
  constexpr Real hi = static_cast<Real>((1 << (kJointAngleBits - 1)) - 1);
  constexpr Real lo = -static_cast<Real>(1 << (kJointAngleBits - 1));
  if (scaled >= hi) return static_cast<std::int32_t>(hi);
  if (scaled <= lo) return static_cast<std::int32_t>(lo);
  return static_cast<std::int32_t>(scaled >= 0 ? scaled + static_cast<Real>(0.5) : scaled - static_cast<Real>(0.5));
}
template <class Real>
constexpr Real joint_angle_rad(std::int32_t raw) {
  return static_cast<Real>(raw) / static_cast<Real>(1 << kJointAngleFractionBits);
}

// --- Single-frame messages -------------------------------------------------------------------

struct ModeCommand {
  bool measure_enable = false;  // accept measurement triggers
  bool correct_enable = false;  // correct the joint-state stream
  bool clear_errors = false;    // clear the latched error flags
};

// Three joints of the classic-CAN stream (A: joints 0..2, B: joints 3..5), input or corrected.
struct JointHalf {
  std::uint8_t sequence = 0;                                     // 4 bits
  std::array<std::int32_t, kJointsPerClassicFrame> angle_raw{};  // LSB 2^-16 rad
};

// All six joints in one CAN FD frame, input or corrected.
struct JointFull {
  std::uint8_t sequence = 0;                      // 8 bits
  std::array<std::int32_t, kJoints> angle_raw{};  // LSB 2^-16 rad
};

struct MeasureTrigger {
  std::uint8_t sequence = 0;  // echoed in the report: pairs results with triggers (wraps at 256)
  std::uint8_t sections = 0;  // section:: bits wanted
};

struct ParameterAck {
  std::uint8_t block = 0;  // ParameterBlock value; echoes an unknown block number too (4 bits)
  AckStatus status = AckStatus::kOk;
  bool read = false;                // answers a ParameterRead (else a ParameterWrite)
  std::uint32_t slot_sequence = 0;  // storage sequence number of the block now active
};

struct ErrorReport {
  ErrorReason reason = ErrorReason::kUnknownId;
  std::uint16_t offending_id = 0;  // 11-bit ID of the (last) rejected frame
  std::uint8_t count = 0;          // rejections since the previous report, saturating at 255
};

struct Heartbeat {
  PlatformState state = PlatformState::kStartup;
  bool measure_enabled = false;
  bool correct_enabled = false;
  std::uint8_t counter = 0;  // 4 bits, +1 per heartbeat: the host sees a missed one
  std::uint8_t version_major = kProtocolVersionMajor;
  std::uint8_t version_minor = kProtocolVersionMinor;
  std::uint16_t error_flags = 0;     // error_flag:: bits
  std::uint8_t rejected_frames = 0;  // wrapping count
  std::uint8_t measurements = 0;     // wrapping count of reports sent
  std::uint8_t corrections = 0;      // wrapping count of corrected outputs sent
  std::uint8_t can_tx_errors = 0;    // the controller's transmit error counter, saturating
};

// The catalogue of single-frame messages, in ID order (the DBC file lists exactly these).
std::span<const MessageSpec> single_frame_messages();
// The specification for `id`, or nullptr.
const MessageSpec* find_message(std::uint32_t id);

// Generic, table-driven codec: raw values in the order of spec.signals.
void encode_raw(const MessageSpec& spec, std::span<const std::int64_t> raw, CanFrame& frame);
DecodeStatus decode_raw(const MessageSpec& spec, const CanFrame& frame, std::span<std::int64_t> raw);
// Frame checks shared by every decoder: ID, format, exact length, reserved bits zero.
DecodeStatus check_frame(const MessageSpec& spec, const CanFrame& frame);

void encode(const ModeCommand& message, CanFrame& frame);
DecodeStatus decode(const CanFrame& frame, ModeCommand& message);

// id: kJointStateA/B or kCorrectedA/B.
void encode_joint_half(std::uint32_t id, const JointHalf& message, CanFrame& frame);
DecodeStatus decode_joint_half(std::uint32_t id, const CanFrame& frame, JointHalf& message);
// id: kJointStateFd or kCorrectedFd.
void encode_joint_full(std::uint32_t id, const JointFull& message, CanFrame& frame);
DecodeStatus decode_joint_full(std::uint32_t id, const CanFrame& frame, JointFull& message);

void encode(const MeasureTrigger& message, CanFrame& frame);
DecodeStatus decode(const CanFrame& frame, MeasureTrigger& message);
void encode(const ParameterAck& message, CanFrame& frame);
DecodeStatus decode(const CanFrame& frame, ParameterAck& message);
void encode(const ErrorReport& message, CanFrame& frame);
DecodeStatus decode(const CanFrame& frame, ErrorReport& message);
void encode(const Heartbeat& message, CanFrame& frame);
DecodeStatus decode(const CanFrame& frame, Heartbeat& message);

}  // namespace kincal::shared

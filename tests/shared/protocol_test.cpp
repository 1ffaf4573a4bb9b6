// The protocol's codecs, natively and on the M4: golden bytes written out by hand from the
// layouts in shared/protocol.hpp, round trips at the extremes of every field, and every
// rejection a decoder promises (wrong length, format, reserved bits, out-of-range values).
#include "shared/protocol.hpp"

#include <doctest.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <limits>

#include "shared/bit_field.hpp"
#include "shared/crc32.hpp"

using namespace kincal::shared;

namespace {

CanFrame frame_of(std::uint32_t id, std::initializer_list<std::uint8_t> bytes, bool fd = false) {
  CanFrame f;
  f.id = id;
  f.fd = fd;
  f.length = static_cast<std::uint8_t>(bytes.size());
  std::size_t i = 0;
  for (const std::uint8_t b : bytes) f.data[i++] = b;
  return f;
}

bool same_bytes(const CanFrame& f, std::initializer_list<std::uint8_t> bytes) {
  if (f.length != bytes.size()) return false;
  std::size_t i = 0;
  for (const std::uint8_t b : bytes)
    if (f.data[i++] != b) return false;
  return true;
}

}  // namespace

TEST_CASE("crc32 matches the IEEE 802.3 / zlib check value") {
  const char* text = "123456789";
  const std::span<const std::uint8_t> bytes(reinterpret_cast<const std::uint8_t*>(text), 9);
  CHECK(crc32(bytes) == 0xCBF43926u);
  // Incremental use gives the same result.
  CHECK(crc32_finish(crc32_update(crc32_update(kCrc32Init, bytes.first(4)), bytes.subspan(4))) == 0xCBF43926u);
  CHECK(crc32(std::span<const std::uint8_t>()) == 0u);
  CHECK(crc32_text(std::span(text, 9)) == 0xCBF43926u);  // text: its bytes as they are
}

TEST_CASE("bit fields: Intel order, sign extension, bounds") {
  std::array<std::uint8_t, 4> buf{};
  put_bits(buf, 4, 12, 0xABC);
  CHECK(buf[0] == 0xC0);
  CHECK(buf[1] == 0xAB);
  CHECK(get_bits(buf, 4, 12) == 0xABC);
  CHECK(sign_extend(0xFFFFF, 20) == -1);
  CHECK(sign_extend(0x80000, 20) == -524288);
  CHECK(sign_extend(0x7FFFF, 20) == 524287);
  // Past the end: nothing written, zeros read.
  put_bits(buf, 30, 8, 0xFF);
  CHECK(buf[3] == 0xC0);
  CHECK(get_bits(buf, 30, 8) == 0x3);
  BitWriter w(buf);
  w.put(32, 1);
  CHECK_FALSE(w.overflow());
  w.put(1, 1);
  CHECK(w.overflow());
}

TEST_CASE("catalogue: IDs unique, inside the protocol block, in ID order") {
  const auto messages = single_frame_messages();
  REQUIRE(messages.size() == 11);
  for (std::size_t i = 0; i < messages.size(); ++i) {
    CHECK(messages[i].id >= can_id::kBlockFirst);
    CHECK(messages[i].id <= can_id::kBlockLast);
    if (i > 0) CHECK(messages[i - 1].id < messages[i].id);
    CHECK(find_message(messages[i].id) == &messages[i]);
  }
  CHECK(find_message(can_id::kIsoTpRequest) == nullptr);
  CHECK(find_message(0x7FF) == nullptr);
}

TEST_CASE("joint angles: LSB 2^-16 rad, round to nearest, saturate at the 20-bit range") {
  CHECK(quantize_joint_angle(1.0) == 65536);
  CHECK(quantize_joint_angle(-1.0) == -65536);
  CHECK(quantize_joint_angle(0.5 / 65536.0) == 1);  // tie away from zero
  CHECK(quantize_joint_angle(-0.5 / 65536.0) == -1);
  CHECK(quantize_joint_angle(0.49 / 65536.0) == 0);
  CHECK(quantize_joint_angle(100.0) == 524287);
  CHECK(quantize_joint_angle(-100.0) == -524288);
  CHECK(quantize_joint_angle(1.0f) == 65536);
  CHECK(joint_angle_rad<double>(524287) == doctest::Approx(8.0 - 1.0 / 65536.0));
  CHECK(quantize_joint_angle(std::numeric_limits<double>::quiet_NaN()) == 0);
}

TEST_CASE("JointStateA golden bytes and round trip") {
  JointHalf in;
  in.sequence = 5;
  in.angle_raw = {65536, -65536, 0};
  CanFrame f;
  encode_joint_half(can_id::kJointStateA, in, f);
  // 0x10000 | 0xF0000 << 20 | 5 << 60 = 0x500000F000010000, little-endian.
  CHECK(same_bytes(f, {0x00, 0x00, 0x01, 0x00, 0xF0, 0x00, 0x00, 0x50}));
  CHECK(f.id == 0x110);
  CHECK_FALSE(f.fd);
  JointHalf out;
  REQUIRE(decode_joint_half(can_id::kJointStateA, f, out) == DecodeStatus::kOk);
  CHECK(out.sequence == 5);
  CHECK(out.angle_raw == in.angle_raw);
  // Extremes of the range.
  in.angle_raw = {524287, -524288, -1};
  in.sequence = 15;
  encode_joint_half(can_id::kCorrectedB, in, f);
  REQUIRE(decode_joint_half(can_id::kCorrectedB, f, out) == DecodeStatus::kOk);
  CHECK(out.angle_raw == in.angle_raw);
  CHECK(out.sequence == 15);
  CHECK(decode_joint_half(can_id::kCorrectedA, f, out) == DecodeStatus::kWrongId);
}

TEST_CASE("JointStateFd: one 16-byte CAN FD frame") {
  JointFull in;
  in.sequence = 200;
  in.angle_raw = {1, -1, 524287, -524288, 12345, -54321};
  CanFrame f;
  encode_joint_full(can_id::kJointStateFd, in, f);
  CHECK(f.fd);
  CHECK(f.brs);
  CHECK(f.length == 16);
  CHECK(f.data[15] == 200);  // bits 120..127
  JointFull out;
  REQUIRE(decode_joint_full(can_id::kJointStateFd, f, out) == DecodeStatus::kOk);
  CHECK(out.angle_raw == in.angle_raw);
  CHECK(out.sequence == 200);
  f.fd = false;
  CHECK(decode_joint_full(can_id::kJointStateFd, f, out) == DecodeStatus::kWrongFormat);
}

TEST_CASE("decoders reject wrong length, wrong format and reserved bits") {
  ModeCommand m;
  CHECK(decode(frame_of(can_id::kModeCommand, {0x03}), m) == DecodeStatus::kOk);
  CHECK(m.measure_enable);
  CHECK(m.correct_enable);
  CHECK_FALSE(m.clear_errors);
  CHECK(decode(frame_of(can_id::kModeCommand, {0x03, 0x00}), m) == DecodeStatus::kWrongLength);
  CHECK(decode(frame_of(can_id::kModeCommand, {}), m) == DecodeStatus::kWrongLength);
  CHECK(decode(frame_of(can_id::kModeCommand, {0x08}), m) == DecodeStatus::kBadValue);
  CHECK(decode(frame_of(can_id::kModeCommand, {0x01}, true), m) == DecodeStatus::kWrongFormat);
  CanFrame ext = frame_of(can_id::kModeCommand, {0x01});
  ext.extended = true;
  CHECK(decode(ext, m) == DecodeStatus::kWrongFormat);
  CHECK(decode(frame_of(0x123, {0x01}), m) == DecodeStatus::kWrongId);

  MeasureTrigger t;
  CHECK(decode(frame_of(can_id::kMeasureTrigger, {7, 0x3F}), t) == DecodeStatus::kOk);
  CHECK(t.sequence == 7);
  CHECK(t.sections == section::kAll);
  CHECK(decode(frame_of(can_id::kMeasureTrigger, {7, 0x40}), t) == DecodeStatus::kBadValue);
}

TEST_CASE("ParameterAck, ErrorReport and Heartbeat round trips and value checks") {
  ParameterAck ack{static_cast<std::uint8_t>(ParameterBlock::kCorrection), AckStatus::kStorageFailure, true,
                   0xFEDCBA98u};
  CanFrame f;
  encode(ack, f);
  CHECK(f.length == 6);
  ParameterAck ack_out;
  REQUIRE(decode(f, ack_out) == DecodeStatus::kOk);
  CHECK(ack_out.block == static_cast<std::uint8_t>(ParameterBlock::kCorrection));
  CHECK(ack_out.status == AckStatus::kStorageFailure);
  CHECK(ack_out.read);
  CHECK(ack_out.slot_sequence == 0xFEDCBA98u);
  f.data[0] = 0xA4;  // status 10 does not exist
  CHECK(decode(f, ack_out) == DecodeStatus::kBadValue);

  ErrorReport e{ErrorReason::kSequence, 0x7FF, 255};
  encode(e, f);
  // reason 5 | id 0x7FF << 8 | 255 << 19 = 0x07FFFF05
  CHECK(same_bytes(f, {0x05, 0xFF, 0xFF, 0x07}));
  ErrorReport e_out;
  REQUIRE(decode(f, e_out) == DecodeStatus::kOk);
  CHECK(e_out.reason == ErrorReason::kSequence);
  CHECK(e_out.offending_id == 0x7FF);
  CHECK(e_out.count == 255);
  f.data[0] = 0;
  CHECK(decode(f, e_out) == DecodeStatus::kBadValue);

  Heartbeat h;
  h.state = PlatformState::kRunning;
  h.measure_enabled = true;
  h.counter = 9;
  h.error_flags = error_flag::kNoColourLut | error_flag::kRxOverflow;
  h.rejected_frames = 3;
  h.measurements = 200;
  h.corrections = 17;
  h.can_tx_errors = 128;
  encode(h, f);
  Heartbeat h_out;
  REQUIRE(decode(f, h_out) == DecodeStatus::kOk);
  CHECK(h_out.state == PlatformState::kRunning);
  CHECK(h_out.measure_enabled);
  CHECK_FALSE(h_out.correct_enabled);
  CHECK(h_out.counter == 9);
  CHECK(h_out.version_major == kProtocolVersionMajor);
  CHECK(h_out.version_minor == kProtocolVersionMinor);
  CHECK(h_out.error_flags == h.error_flags);
  CHECK(h_out.measurements == 200);
  CHECK(h_out.corrections == 17);
  CHECK(h_out.can_tx_errors == 128);
}

TEST_CASE("generic codec agrees with the typed one for every message") {
  for (const MessageSpec& spec : single_frame_messages()) {
    // All-ones in every signal: the largest raw value of each field, then decode generically.
    std::array<std::int64_t, 16> raw{};
    for (std::size_t i = 0; i < spec.signals.size(); ++i)
      raw[i] = spec.signals[i].is_signed ? -1 : max_raw(spec.signals[i].bits, false);
    CanFrame f;
    encode_raw(spec, raw, f);
    CHECK(f.length == spec.length);
    CHECK(f.fd == spec.fd);
    std::array<std::int64_t, 16> back{};
    REQUIRE(decode_raw(spec, f, back) == DecodeStatus::kOk);
    for (std::size_t i = 0; i < spec.signals.size(); ++i) CHECK(back[i] == raw[i]);
  }
}

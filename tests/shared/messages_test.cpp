// The ISO-TP payloads of the protocol: measurement reports at their largest and smallest,
// parameter blocks and their messages, and every rejection the decoders promise.
#include <doctest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "shared/crc32.hpp"
#include "shared/measurement_report.hpp"
#include "shared/parameters.hpp"

using namespace kincal::shared;

namespace {

MeasurementReport full_report() {
  MeasurementReport r;
  r.sequence = 0xA5;
  r.timestamp_us = 0xDEADBEEFu;
  r.sections = section::kAll;
  r.status = MeasureStatus::kNoTarget;
  r.range_raw = {0, 1, 0x8000, kNoEcho};
  r.plane_normal_x_raw = -32768;
  r.plane_normal_y_raw = 32767;
  r.plane_distance_raw = 0xFFFF;
  r.fiducial_count = kMaxFiducials;
  for (std::size_t i = 0; i < kMaxFiducials; ++i)
    r.fiducials[i] = {static_cast<std::uint8_t>(15 - i), static_cast<std::uint16_t>(i * 8191u),
                      static_cast<std::uint16_t>(65535u - i)};
  r.pose_squares = kMaxPoseSquares;
  r.translation_raw = {-524288, 524287, 1};
  r.rotation_raw = {-131072, 131071, -1};
  r.pose_sigma_raw = {0, 1, 512, 896, 1022, kPoseSigmaRawMax};
  for (std::size_t i = 0; i < kPoseCorrelations; ++i)
    r.pose_correlation_raw[i] =
        static_cast<std::int8_t>(i % 2 == 0 ? 127 - 17 * static_cast<int>(i) : -127 + 9 * static_cast<int>(i));
  r.blob_count = kMaxBlobs;
  for (std::size_t i = 0; i < kMaxBlobs; ++i)
    r.blobs[i] = {static_cast<std::uint16_t>(i * 1000u), static_cast<std::uint16_t>(65535u - i * 3u),
                  static_cast<std::uint16_t>(i * 97u), static_cast<std::uint8_t>(i & 0xF),
                  static_cast<std::uint8_t>(255 - i)};
  r.point_raw = {524287, -524288, 0};
  return r;
}

void check_equal(const MeasurementReport& a, const MeasurementReport& b) {
  CHECK(a.sequence == b.sequence);
  CHECK(a.timestamp_us == b.timestamp_us);
  CHECK(a.sections == b.sections);
  CHECK(a.status == b.status);
  CHECK(a.range_raw == b.range_raw);
  CHECK(a.plane_normal_x_raw == b.plane_normal_x_raw);
  CHECK(a.plane_normal_y_raw == b.plane_normal_y_raw);
  CHECK(a.plane_distance_raw == b.plane_distance_raw);
  REQUIRE(a.fiducial_count == b.fiducial_count);
  for (std::size_t i = 0; i < a.fiducial_count; ++i) {
    CHECK(a.fiducials[i].id == b.fiducials[i].id);
    CHECK(a.fiducials[i].x_q6 == b.fiducials[i].x_q6);
    CHECK(a.fiducials[i].y_q6 == b.fiducials[i].y_q6);
  }
  CHECK(a.pose_squares == b.pose_squares);
  CHECK(a.translation_raw == b.translation_raw);
  CHECK(a.rotation_raw == b.rotation_raw);
  CHECK(a.pose_sigma_raw == b.pose_sigma_raw);
  CHECK(a.pose_correlation_raw == b.pose_correlation_raw);
  REQUIRE(a.blob_count == b.blob_count);
  for (std::size_t i = 0; i < a.blob_count; ++i) {
    CHECK(a.blobs[i].x_q6 == b.blobs[i].x_q6);
    CHECK(a.blobs[i].y_q6 == b.blobs[i].y_q6);
    CHECK(a.blobs[i].area_px == b.blobs[i].area_px);
    CHECK(a.blobs[i].colour_class == b.blobs[i].colour_class);
    CHECK(a.blobs[i].peak_dn == b.blobs[i].peak_dn);
  }
  CHECK(a.point_raw == b.point_raw);
}

// The platform's judgement of a ParameterWrite of `payload` whose header says format `version`.
AckStatus ack_of_written_block(ParameterBlock block, std::uint16_t version, std::span<const std::uint8_t> payload) {
  std::array<std::uint8_t, kMaxParameterMessageBytes> message{};
  const std::size_t length = encode_parameter_message(MessageType::kParameterWrite, block, payload, message);
  REQUIRE(length == kParameterHeaderBytes + payload.size());
  message[2] = static_cast<std::uint8_t>(version);
  message[3] = static_cast<std::uint8_t>(version >> 8);
  ParameterHeader h;
  std::span<const std::uint8_t> decoded;
  REQUIRE(decode_parameter_message(std::span<const std::uint8_t>(message).first(length), h, decoded) ==
          DecodeStatus::kOk);
  REQUIRE(h.version == version);
  return check_parameter_payload(h, decoded);
}

}  // namespace

TEST_CASE("measurement report: largest report is kMaxReportBytes and round-trips") {
  const MeasurementReport r = full_report();
  std::array<std::uint8_t, kMaxReportBytes> buf{};
  REQUIRE(encode(r, buf) == kMaxReportBytes);
  CHECK(buf[0] == 0x81);
  CHECK(buf[1] == 0xA5);
  MeasurementReport back;
  REQUIRE(decode(buf, back) == DecodeStatus::kOk);
  check_equal(r, back);
  // One byte short: the encoder refuses rather than truncating.
  CHECK(encode(r, std::span<std::uint8_t>(buf).first(kMaxReportBytes - 1)) == 0);
}

TEST_CASE("measurement report: header-only and ranges-only sizes, golden header") {
  MeasurementReport r;
  r.sequence = 1;
  r.timestamp_us = 0x01020304;
  r.sections = section::kRanges;
  r.range_raw = {0x1111, 0x2222, 0x3333, 0x4444};
  // 58 header bits + 64 range bits = 122 bits -> 16 bytes.
  CHECK(report_size(r) == 16);
  std::array<std::uint8_t, 16> buf{};
  REQUIRE(encode(r, buf) == 16);
  CHECK(buf[0] == 0x81);
  CHECK(buf[1] == 0x01);
  CHECK(buf[2] == 0x04);  // timestamp, little-endian
  CHECK(buf[5] == 0x01);
  CHECK(buf[6] == 0x01);  // sections (6 bits) then status 0
  MeasurementReport back;
  REQUIRE(decode(buf, back) == DecodeStatus::kOk);
  CHECK(back.range_raw == r.range_raw);
  r.sections = 0;
  CHECK(report_size(r) == 8);
}

TEST_CASE("measurement report: rejections") {
  const MeasurementReport r = full_report();
  std::array<std::uint8_t, kMaxReportBytes + 1> buf{};
  const std::size_t n = encode(r, buf);
  REQUIRE(n == kMaxReportBytes);
  MeasurementReport back;
  CHECK(decode(std::span<const std::uint8_t>(buf).first(n - 1), back) == DecodeStatus::kWrongLength);
  CHECK(decode(std::span<const std::uint8_t>(buf).first(n + 1), back) == DecodeStatus::kWrongLength);
  CHECK(decode(std::span<const std::uint8_t>(buf).first(3), back) == DecodeStatus::kWrongLength);
  CHECK(decode(std::span<const std::uint8_t>(), back) == DecodeStatus::kWrongId);
  auto bad = buf;
  bad[0] = 0x82;
  CHECK(decode(std::span<const std::uint8_t>(bad).first(n), back) == DecodeStatus::kWrongId);
  // Status 15 is out of range (bits 54..57 of the header).
  bad = buf;
  bad[6] = static_cast<std::uint8_t>(bad[6] | 0xC0);
  bad[7] = static_cast<std::uint8_t>(bad[7] | 0x03);
  CHECK(decode(std::span<const std::uint8_t>(bad).first(n), back) == DecodeStatus::kBadValue);
  // A fiducial count of 9..15.
  MeasurementReport f;
  f.sections = section::kFiducials;
  f.fiducial_count = 1;
  std::array<std::uint8_t, 32> small{};
  const std::size_t m = encode(f, small);
  REQUIRE(m == 13);                                                     // 58 + 4 + 36 = 98 bits
  small[7] = static_cast<std::uint8_t>((small[7] & 0x03) | (9u << 2));  // count field at bits 58..61
  CHECK(decode(std::span<const std::uint8_t>(small).first(m), back) == DecodeStatus::kBadValue);
  // Non-zero padding bits in the last byte.
  small = {};
  REQUIRE(encode(f, small) == m);
  small[m - 1] = static_cast<std::uint8_t>(small[m - 1] | 0x80);
  CHECK(decode(std::span<const std::uint8_t>(small).first(m), back) == DecodeStatus::kBadValue);
}

TEST_CASE("parameter blocks round-trip and reject bad values") {
  CorrectionParameters c;
  c.joint_count = 6;
  for (std::size_t j = 0; j < kJoints; ++j) {
    c.joints[j].nominal = {0.1f * static_cast<float>(j), 1.5707964f, 0.2f, 0.0f, 0.0f};
    c.joints[j].error = {1e-4f, -2e-4f, 3e-5f, 1e-3f * static_cast<float>(j), 0.0f};
  }
  c.joints[0].type = JointKind::kPrismatic;
  c.joints[0].convention = LinkKind::kDoty;
  c.joints[0].nominal.beta_rad = 0.25f;
  c.tool_offset = {0.0f, 0.0f, 0.1f, 0.0f, 0.0f, 3.1415927f};
  c.tool_error = {1e-3f, 0.0f, 0.0f, 0.0f, 2e-3f, 0.0f};
  std::array<std::uint8_t, kCorrectionBytes> image{};
  REQUIRE(encode_block(c, image) == kCorrectionBytes);
  CorrectionParameters back;
  REQUIRE(decode_block(image, back) == DecodeStatus::kOk);
  CHECK(back.joint_count == 6);
  CHECK(back.joints[5].error.theta_rad == c.joints[5].error.theta_rad);
  CHECK(back.tool_offset[5] == c.tool_offset[5]);
  CHECK(back.joints[0].type == JointKind::kPrismatic);
  CHECK(back.joints[0].convention == LinkKind::kDoty);
  CHECK(back.joints[0].nominal.beta_rad == 0.25f);
  CHECK(back.tool_error == c.tool_error);
  CHECK(back.joints[1].type == JointKind::kRevolute);
  CHECK(back.joints[1].convention == LinkKind::kModifiedDh);
  // An unknown joint type or link convention.
  auto unknown = image;
  unknown[1] = 2;
  CHECK(decode_block(unknown, back) == DecodeStatus::kBadValue);
  unknown = image;
  unknown[2] = 3;
  CHECK(decode_block(unknown, back) == DecodeStatus::kBadValue);
  // NaN in a float, a joint count of 7, a short image.
  auto bad = image;
  bad[5] = 0xFF;
  bad[6] = 0xFF;
  bad[7] = 0xFF;
  bad[8] = 0xFF;
  CHECK(decode_block(bad, back) == DecodeStatus::kBadValue);
  bad = image;
  bad[0] = 7;
  CHECK(decode_block(bad, back) == DecodeStatus::kBadValue);
  CHECK(decode_block(std::span<const std::uint8_t>(image).first(10), back) == DecodeStatus::kWrongLength);

  CameraIntrinsics k{800.0f, 801.0f, 319.5f, 239.5f, -0.1f, 0.01f, 0.0f, 0.0f, 0.0f, 640, 480};
  std::array<std::uint8_t, kIntrinsicsBytes> ki{};
  REQUIRE(encode_block(k, ki) == kIntrinsicsBytes);
  CameraIntrinsics kb;
  REQUIRE(decode_block(ki, kb) == DecodeStatus::kOk);
  CHECK(kb.cx_px == 319.5f);
  CHECK(kb.height_px == 480);

  PlatformGeometry g;
  g.fiducial_count = 4;
  g.rangers[2].direction = {0.0f, 0.0f, 1.0f};
  std::array<std::uint8_t, kGeometryBytes> gi{};
  REQUIRE(encode_block(g, gi) == kGeometryBytes);
  PlatformGeometry gb;
  REQUIRE(decode_block(gi, gb) == DecodeStatus::kOk);
  CHECK(gb.fiducial_count == 4);
  CHECK(gb.rangers[2].direction[2] == 1.0f);

  ColourLut lut;
  lut.packed[0x123 / 2] = 0x70;  // cell 0x123 (odd): class 7
  CHECK(lut.colour_class(1, 2, 3) == 7);
  CHECK(lut.colour_class(1, 2, 2) == 0);
}

TEST_CASE("correction block format 3: the joint map round-trips, its flag is judged, version 2 is refused") {
  CorrectionParameters c;
  c.joint_count = 6;
  c.joint_maps[2].coupled = true;
  c.joint_maps[2].coupling = {0.0f, 1.0f, 1.0f, 0.0f, 0.0f, 0.0f};
  c.joint_maps[1].scale = 1.0f;
  c.joint_maps[1].scale_error = -3e-4f;
  c.joint_maps[1].compliance = 1e-5f;
  c.joint_maps[1].compliance_error = 2e-5f;
  c.joint_maps[1].mass_kg = 17.4f;
  c.joint_maps[1].centre_of_mass_m = {0.068f, 0.006f, -0.016f};
  c.payload_mass_kg = 2.5f;
  c.payload_centre_of_mass_m = {0.0f, 0.01f, 0.1f};
  c.gravity_mps2 = {0.0f, -9.80665f, 0.0f};
  std::array<std::uint8_t, kCorrectionBytes> image{};
  REQUIRE(encode_block(c, image) == 671);
  CHECK(check_correction_block(image) == DecodeStatus::kOk);
  CorrectionParameters back;
  REQUIRE(decode_block(image, back) == DecodeStatus::kOk);
  CHECK(back.joint_maps[2].coupled);
  CHECK(back.joint_maps[2].coupling == c.joint_maps[2].coupling);
  CHECK_FALSE(back.joint_maps[1].coupled);
  CHECK(back.joint_maps[1].scale_error == -3e-4f);
  CHECK(back.joint_maps[1].compliance == 1e-5f);
  CHECK(back.joint_maps[1].compliance_error == 2e-5f);
  CHECK(back.joint_maps[1].mass_kg == 17.4f);
  CHECK(back.joint_maps[1].centre_of_mass_m == c.joint_maps[1].centre_of_mass_m);
  CHECK(back.joint_maps[0].scale == 1.0f);  // the default: the joint's own reading, scale 1
  CHECK(back.payload_mass_kg == 2.5f);
  CHECK(back.payload_centre_of_mass_m == c.payload_centre_of_mass_m);
  CHECK(back.gravity_mps2 == c.gravity_mps2);
  // The joint map starts after the v2 part (301 bytes): joint 1's flag, then joint 2's at +57.
  const std::size_t flag = 1 + kJoints * 42 + 48;
  CHECK(image[flag + 2 * kJointMapBytes] == 1);
  auto bad = image;
  bad[flag] = 2;  // neither "own reading" nor "row follows"
  CHECK(check_correction_block(bad) == DecodeStatus::kBadValue);
  CHECK(decode_block(bad, back) == DecodeStatus::kBadValue);
  bad = image;
  for (std::size_t k = 0; k < 4; ++k) bad[kCorrectionBytes - 4 + k] = 0xFF;  // gravity z: NaN
  CHECK(check_correction_block(bad) == DecodeStatus::kBadValue);
  CHECK(check_correction_block(std::span<const std::uint8_t>(image).first(301)) == DecodeStatus::kWrongLength);
  // A version 2 block (301 bytes, version 2 in the header) is refused as a version.
  CHECK(ack_of_written_block(ParameterBlock::kCorrection, 2, std::span<const std::uint8_t>(image).first(301)) ==
        AckStatus::kBadVersion);
}

TEST_CASE(
    "geometry block format 4: the square pitch round-trips, a pitch out of range or a version 3 block is refused") {
  PlatformGeometry g;
  g.fiducial_count = 6;
  g.fiducial_square_m[4] = {0.04445f, 0.0f, 0.0f};
  g.square_pitch_m = 0.1016f;  // Doty's 4-inch squares
  std::array<std::uint8_t, kGeometryBytes> image{};
  REQUIRE(encode_block(g, image) == 197);
  PlatformGeometry back;
  REQUIRE(decode_block(image, back) == DecodeStatus::kOk);
  CHECK(back.square_pitch_m == 0.1016f);
  CHECK(back.fiducial_square_m[4] == g.fiducial_square_m[4]);
  // The pitch is the last float32, after the v1 part (193 bytes).
  const auto pitch_bits = std::bit_cast<std::uint32_t>(0.1016f);
  for (std::size_t k = 0; k < 4; ++k) CHECK(image[193 + k] == static_cast<std::uint8_t>(pitch_bits >> (8 * k)));

  const auto decoded_with_pitch = [&](float pitch) {
    PlatformGeometry p = g;
    p.square_pitch_m = pitch;
    std::array<std::uint8_t, kGeometryBytes> bytes{};
    REQUIRE(encode_block(p, bytes) == kGeometryBytes);
    PlatformGeometry out;
    out.square_pitch_m = -1.0f;  // written only on kOk
    const DecodeStatus status = decode_block(bytes, out);
    if (status != DecodeStatus::kOk) CHECK(out.square_pitch_m == -1.0f);
    return status;
  };
  for (const float pitch : {0.0f, 0.01f, 0.1016f, 2.0f}) {
    INFO("pitch " << pitch);
    CHECK(decoded_with_pitch(pitch) == DecodeStatus::kOk);
  }
  for (const float pitch :
       {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
        -std::numeric_limits<float>::infinity(), -0.1016f, -1e-30f, 1e-30f, 0.005f, 0.0099f, 2.0001f, 3.0f}) {
    INFO("pitch " << pitch);
    CHECK(decoded_with_pitch(pitch) == DecodeStatus::kBadValue);
  }
  CHECK(decode_block(std::span<const std::uint8_t>(image).first(193), back) == DecodeStatus::kWrongLength);

  // The block as this kincal writes it is taken; a version 3 geometry block (193 bytes, version 3 in
  // the header) is refused as a version.
  CHECK(ack_of_written_block(ParameterBlock::kGeometry, kBlockFormatVersion, image) == AckStatus::kOk);
  CHECK(ack_of_written_block(ParameterBlock::kGeometry, 3, std::span<const std::uint8_t>(image).first(193)) ==
        AckStatus::kBadVersion);
}

TEST_CASE("parameter messages: framing, CRC, version, block") {
  CameraIntrinsics k{800.0f, 800.0f, 320.0f, 240.0f, 0, 0, 0, 0, 0, 640, 480};
  std::array<std::uint8_t, kIntrinsicsBytes> image{};
  REQUIRE(encode_block(k, image) == kIntrinsicsBytes);
  std::array<std::uint8_t, kMaxParameterMessageBytes> msg{};
  const std::size_t n = encode_parameter_message(MessageType::kParameterWrite, ParameterBlock::kIntrinsics, image, msg);
  REQUIRE(n == kParameterHeaderBytes + kIntrinsicsBytes);
  CHECK(msg[0] == 0x01);
  CHECK(msg[1] == 1);
  CHECK(msg[2] == kBlockFormatVersion);  // little-endian
  CHECK(msg[3] == 0);
  CHECK(msg[4] == kIntrinsicsBytes);
  const std::uint32_t crc = crc32(image);
  CHECK(msg[6] == static_cast<std::uint8_t>(crc));
  CHECK(msg[9] == static_cast<std::uint8_t>(crc >> 24));

  ParameterHeader h;
  std::span<const std::uint8_t> payload;
  const auto message = std::span<const std::uint8_t>(msg).first(n);
  REQUIRE(decode_parameter_message(message, h, payload) == DecodeStatus::kOk);
  CHECK(payload.size() == kIntrinsicsBytes);
  CHECK(check_parameter_payload(h, payload) == AckStatus::kOk);
  CHECK(decode_parameter_message(message.first(n - 1), h, payload) == DecodeStatus::kWrongLength);

  auto bad = msg;
  bad[kParameterHeaderBytes + 3] ^= 0x01;  // payload bit flip
  REQUIRE(decode_parameter_message(std::span<const std::uint8_t>(bad).first(n), h, payload) == DecodeStatus::kOk);
  CHECK(check_parameter_payload(h, payload) == AckStatus::kCrcMismatch);
  bad = msg;
  bad[2] = static_cast<std::uint8_t>(kBlockFormatVersion + 1);
  REQUIRE(decode_parameter_message(std::span<const std::uint8_t>(bad).first(n), h, payload) == DecodeStatus::kOk);
  CHECK(check_parameter_payload(h, payload) == AckStatus::kBadVersion);
  bad = msg;
  bad[1] = 9;
  REQUIRE(decode_parameter_message(std::span<const std::uint8_t>(bad).first(n), h, payload) == DecodeStatus::kOk);
  CHECK(check_parameter_payload(h, payload) == AckStatus::kUnknownBlock);
  bad = msg;
  bad[1] = 2;  // colour LUT: 2048 bytes expected
  REQUIRE(decode_parameter_message(std::span<const std::uint8_t>(bad).first(n), h, payload) == DecodeStatus::kOk);
  CHECK(check_parameter_payload(h, payload) == AckStatus::kBadLength);

  std::array<std::uint8_t, 2> read{};
  REQUIRE(encode_parameter_read(ParameterBlock::kColourLut, read) == 2);
  std::uint8_t block = 0;
  REQUIRE(decode_parameter_read(read, block) == DecodeStatus::kOk);
  CHECK(block == 2);
  CHECK(decode_parameter_read(std::span<const std::uint8_t>(read).first(1), block) == DecodeStatus::kWrongLength);
}

TEST_CASE("measurement report: pose covariance encoding, its resolution and range") {
  // Sigma: 1/32 octave steps, so any sigma in range comes back within 2^(1/64) (1.09 %).
  for (float sigma = 4.0e-9f; sigma < 15.0f; sigma *= 1.037f) {
    const double back = pose_sigma(quantize_pose_sigma(sigma));
    CHECK(back / static_cast<double>(sigma) <= 1.0109);
    CHECK(back / static_cast<double>(sigma) >= 1.0 / 1.0109);
  }
  CHECK(quantize_pose_sigma(1.0f) == kPoseSigmaRawOffset);
  CHECK(pose_sigma(static_cast<std::uint16_t>(kPoseSigmaRawOffset)) == 1.0);
  CHECK(pose_sigma(static_cast<std::uint16_t>(kPoseSigmaRawOffset - 32 * 10)) == 1.0 / 1024.0);
  CHECK(quantize_pose_sigma(1.0e-3f) == kPoseSigmaRawOffset - 319);  // log2(1e-3) * 32 = -318.9
  CHECK(quantize_pose_sigma(0.0f) == 0);
  CHECK(quantize_pose_sigma(-1.0f) == 0);
  CHECK(quantize_pose_sigma(1.0e-12f) == 0);
  CHECK(quantize_pose_sigma(100.0f) == kPoseSigmaRawMax);
  CHECK(quantize_pose_sigma(std::numeric_limits<float>::infinity()) == kPoseSigmaRawMax);
  CHECK(quantize_pose_sigma(std::numeric_limits<float>::quiet_NaN()) == kPoseSigmaRawMax);
  // Correlation: LSB 1/127, clamped, NaN -> 0.
  CHECK(quantize_pose_correlation(0.5f) == 64);
  CHECK(quantize_pose_correlation(-0.5f) == -64);
  CHECK(quantize_pose_correlation(1.5f) == 127);
  CHECK(quantize_pose_correlation(-2.0f) == -127);
  CHECK(quantize_pose_correlation(std::numeric_limits<float>::quiet_NaN()) == 0);

  // A covariance with decades between its sigmas and strong correlations survives the report.
  const std::array<double, kPoseDof> sigma = {2e-5, 3e-5, 1.5e-4, 4e-5, 6e-5, 1e-5};
  std::array<double, kPoseCorrelations> rho{};
  for (std::size_t k = 0; k < kPoseCorrelations; ++k) rho[k] = 0.9 * std::sin(1.7 * static_cast<double>(k) + 0.3);
  std::array<float, kPoseDof * kPoseDof> covariance{};
  std::size_t k = 0;
  for (std::size_t i = 0; i < kPoseDof; ++i) {
    covariance[i * kPoseDof + i] = static_cast<float>(sigma[i] * sigma[i]);
    for (std::size_t j = i + 1; j < kPoseDof; ++j, ++k)
      covariance[i * kPoseDof + j] = covariance[j * kPoseDof + i] = static_cast<float>(rho[k] * sigma[i] * sigma[j]);
  }
  MeasurementReport r;
  r.sections = section::kPose;
  set_pose_covariance(covariance, r);
  std::array<std::uint8_t, kMaxReportBytes> buf{};
  const std::size_t n = encode(r, buf);
  REQUIRE(n == report_size(r));
  MeasurementReport back;
  REQUIRE(decode(std::span<const std::uint8_t>(buf).first(n), back) == DecodeStatus::kOk);
  const std::array<double, kPoseDof* kPoseDof> c = pose_covariance(back);
  k = 0;
  for (std::size_t i = 0; i < kPoseDof; ++i) {
    CHECK(std::sqrt(c[i * kPoseDof + i]) == doctest::Approx(sigma[i]).epsilon(0.011));
    for (std::size_t j = i + 1; j < kPoseDof; ++j, ++k) {
      CHECK(c[i * kPoseDof + j] == c[j * kPoseDof + i]);
      CHECK(std::abs(c[i * kPoseDof + j] / std::sqrt(c[i * kPoseDof + i] * c[j * kPoseDof + j]) - rho[k]) <=
            0.5 / kPoseCorrelationScale + 1e-6);
    }
  }
  // A zero variance: its correlations are 0, not NaN.
  covariance[0] = 0.0f;
  set_pose_covariance(covariance, r);
  CHECK(r.pose_sigma_raw[0] == 0);
  for (std::size_t j = 0; j + 1 < kPoseDof; ++j) CHECK(r.pose_correlation_raw[j] == 0);
}

TEST_CASE("measurement report: pose section size and the invalid correlation -128") {
  MeasurementReport r;
  r.sections = section::kPose;
  // 58 header bits + 4 squares + 114 pose + 60 sigma + 120 correlation bits = 356 bits -> 45 bytes.
  REQUIRE(report_size(r) == 45);
  std::array<std::uint8_t, 45> buf{};
  REQUIRE(encode(r, buf) == 45);
  MeasurementReport back;
  REQUIRE(decode(buf, back) == DecodeStatus::kOk);
  // The last correlation is bits 348..355: the high nibble of byte 43, the low nibble of byte 44.
  const auto set_last_correlation = [&buf](std::uint8_t raw) {
    buf[43] = static_cast<std::uint8_t>((buf[43] & 0x0F) | ((raw & 0x0F) << 4));
    buf[44] = static_cast<std::uint8_t>(raw >> 4);
  };
  set_last_correlation(0x80);
  CHECK(decode(buf, back) == DecodeStatus::kBadValue);
  set_last_correlation(0x81);  // -127: valid
  REQUIRE(decode(buf, back) == DecodeStatus::kOk);
  CHECK(back.pose_correlation_raw[kPoseCorrelations - 1] == -127);
}

TEST_CASE("measurement report: the pose's square count (protocol 3.0) round-trips, 0 is refused, encode clamps") {
  MeasurementReport r;
  r.sections = section::kPose;
  std::array<std::uint8_t, 45> buf{};
  MeasurementReport back;
  // The count is the pose section's first field: bits 58..61, bits 2..5 of byte 7.
  for (const std::uint8_t squares : {std::uint8_t{1}, std::uint8_t{2}, std::uint8_t{7}, kMaxPoseSquares}) {
    r.pose_squares = squares;
    REQUIRE(encode(r, buf) == 45);
    CHECK(((buf[7] >> 2) & 0x0F) == squares);
    REQUIRE(decode(buf, back) == DecodeStatus::kOk);
    CHECK(back.pose_squares == squares);
  }
  buf[7] = static_cast<std::uint8_t>(buf[7] & ~0x3C);  // squares 0: a pose on no square
  CHECK(decode(buf, back) == DecodeStatus::kBadValue);
  r.pose_squares = 16;
  REQUIRE(encode(r, buf) == 45);
  REQUIRE(decode(buf, back) == DecodeStatus::kOk);
  CHECK(back.pose_squares == kMaxPoseSquares);
  r.pose_squares = 0;
  REQUIRE(encode(r, buf) == 45);
  REQUIRE(decode(buf, back) == DecodeStatus::kOk);
  CHECK(back.pose_squares == 1);
  // Without a pose section the count is not on the wire, and decode leaves the default.
  r.sections = section::kRanges;
  r.pose_squares = 5;
  REQUIRE(encode(r, buf) == 16);
  REQUIRE(decode(std::span<const std::uint8_t>(buf).first(16), back) == DecodeStatus::kOk);
  CHECK(back.pose_squares == 1);
}

TEST_CASE("measurement report: the ARID report's sizes (protocol 3.0)") {
  MeasurementReport r;
  r.sections = section::kRanges | section::kPlane | section::kFiducials | section::kPose;
  // 58 header + 64 ranges + 48 plane + 4 + n x 36 fiducials + 298 pose (squares, pose, covariance).
  r.fiducial_count = 4;
  CHECK(report_size(r) == 77);  // 616 bits
  r.fiducial_count = 6;
  CHECK(report_size(r) == 86);  // 688 bits (Doty's square)
}

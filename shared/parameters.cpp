#include "shared/parameters.hpp"

#include <bit>

#include "shared/crc32.hpp"

namespace kincal::shared {

namespace {

// Little-endian byte cursor over a fixed image; the callers check the image length first.
class Out {
 public:
  explicit Out(std::span<std::uint8_t> bytes) : bytes_(bytes) {}
  void u8(std::uint8_t v) { bytes_[pos_++] = v; }
  void u16(std::uint16_t v) {
    u8(static_cast<std::uint8_t>(v));
    u8(static_cast<std::uint8_t>(v >> 8));
  }
  void u32(std::uint32_t v) {
    u16(static_cast<std::uint16_t>(v));
    u16(static_cast<std::uint16_t>(v >> 16));
  }
  void f32(float v) { u32(std::bit_cast<std::uint32_t>(v)); }
  std::size_t position() const { return pos_; }

 private:
  std::span<std::uint8_t> bytes_;
  std::size_t pos_ = 0;
};

class In {
 public:
  explicit In(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  std::uint8_t u8() { return bytes_[pos_++]; }
  std::uint16_t u16() {
    const std::uint16_t lo = u8();
    return static_cast<std::uint16_t>(lo | (u8() << 8));
  }
  std::uint32_t u32() {
    const std::uint32_t lo = u16();
    return lo | (static_cast<std::uint32_t>(u16()) << 16);
  }
  // Non-finite values (NaN, infinity) mark the image as bad.
  float f32() {
    const std::uint32_t bits = u32();
    if ((bits & 0x7F800000u) == 0x7F800000u) finite_ = false;
    return std::bit_cast<float>(bits);
  }
  bool finite() const { return finite_; }
  std::size_t position() const { return pos_; }

 private:
  std::span<const std::uint8_t> bytes_;
  std::size_t pos_ = 0;
  bool finite_ = true;
};

void put_dh(Out& o, const DhValues& v) {
  o.f32(v.a_m);
  o.f32(v.alpha_rad);
  o.f32(v.d_m);
  o.f32(v.theta_rad);
  o.f32(v.beta_rad);
}
void get_dh(In& in, DhValues& v) {
  v.a_m = in.f32();
  v.alpha_rad = in.f32();
  v.d_m = in.f32();
  v.theta_rad = in.f32();
  v.beta_rad = in.f32();
}

}  // namespace

std::size_t block_size(ParameterBlock block) {
  switch (block) {
    case ParameterBlock::kIntrinsics:
      return kIntrinsicsBytes;
    case ParameterBlock::kColourLut:
      return kColourLutBytes;
    case ParameterBlock::kGeometry:
      return kGeometryBytes;
    case ParameterBlock::kCorrection:
      return kCorrectionBytes;
  }
  return 0;
}

bool is_known_block(std::uint8_t block) { return block >= 1 && block <= kParameterBlockCount; }

std::size_t encode_block(const CameraIntrinsics& b, std::span<std::uint8_t> out) {
  if (out.size() < kIntrinsicsBytes) return 0;
  Out o(out);
  for (const float v : {b.fx_px, b.fy_px, b.cx_px, b.cy_px, b.k1, b.k2, b.p1, b.p2, b.k3}) o.f32(v);
  o.u16(b.width_px);
  o.u16(b.height_px);
  return o.position();
}

DecodeStatus decode_block(std::span<const std::uint8_t> image, CameraIntrinsics& b) {
  if (image.size() != kIntrinsicsBytes) return DecodeStatus::kWrongLength;
  In in(image);
  CameraIntrinsics v;
  for (float* f : {&v.fx_px, &v.fy_px, &v.cx_px, &v.cy_px, &v.k1, &v.k2, &v.p1, &v.p2, &v.k3}) *f = in.f32();
  v.width_px = in.u16();
  v.height_px = in.u16();
  if (!in.finite() || !(v.fx_px > 0) || !(v.fy_px > 0)) return DecodeStatus::kBadValue;
  b = v;
  return DecodeStatus::kOk;
}

std::size_t encode_block(const ColourLut& b, std::span<std::uint8_t> out) {
  if (out.size() < kColourLutBytes) return 0;
  for (std::size_t i = 0; i < kColourLutBytes; ++i) out[i] = b.packed[i];
  return kColourLutBytes;
}

DecodeStatus decode_block(std::span<const std::uint8_t> image, ColourLut& b) {
  if (image.size() != kColourLutBytes) return DecodeStatus::kWrongLength;
  for (std::size_t i = 0; i < kColourLutBytes; ++i) b.packed[i] = image[i];
  return DecodeStatus::kOk;
}

std::size_t encode_block(const PlatformGeometry& b, std::span<std::uint8_t> out) {
  if (out.size() < kGeometryBytes) return 0;
  Out o(out);
  for (const RangerBeam& r : b.rangers) {
    for (const float v : r.origin_m) o.f32(v);
    for (const float v : r.direction) o.f32(v);
  }
  o.u8(b.fiducial_count);
  for (const auto& p : b.fiducial_square_m)
    for (const float v : p) o.f32(v);
  o.f32(b.square_pitch_m);
  return o.position();
}

DecodeStatus decode_block(std::span<const std::uint8_t> image, PlatformGeometry& b) {
  if (image.size() != kGeometryBytes) return DecodeStatus::kWrongLength;
  In in(image);
  PlatformGeometry v;
  for (RangerBeam& r : v.rangers) {
    for (float& f : r.origin_m) f = in.f32();
    for (float& f : r.direction) f = in.f32();
  }
  v.fiducial_count = in.u8();
  for (auto& p : v.fiducial_square_m)
    for (float& f : p) f = in.f32();
  v.square_pitch_m = in.f32();
  const bool pitch_ok =
      v.square_pitch_m == 0.0f || (v.square_pitch_m >= kMinSquarePitchM && v.square_pitch_m <= kMaxSquarePitchM);
  if (!in.finite() || v.fiducial_count > kMaxFiducials || !pitch_ok) return DecodeStatus::kBadValue;
  b = v;
  return DecodeStatus::kOk;
}

std::size_t encode_block(const CorrectionParameters& b, std::span<std::uint8_t> out) {
  if (out.size() < kCorrectionBytes) return 0;
  Out o(out);
  o.u8(b.joint_count);
  for (const JointModel& j : b.joints) {
    o.u8(static_cast<std::uint8_t>(j.type));
    o.u8(static_cast<std::uint8_t>(j.convention));
    put_dh(o, j.nominal);
    put_dh(o, j.error);
  }
  for (const float v : b.tool_offset) o.f32(v);
  for (const float v : b.tool_error) o.f32(v);
  for (const JointMapValues& m : b.joint_maps) {
    o.u8(m.coupled ? 1 : 0);
    for (const float v : m.coupling) o.f32(v);
    for (const float v : {m.scale, m.scale_error, m.compliance, m.compliance_error, m.mass_kg}) o.f32(v);
    for (const float v : m.centre_of_mass_m) o.f32(v);
  }
  o.f32(b.payload_mass_kg);
  for (const float v : b.payload_centre_of_mass_m) o.f32(v);
  for (const float v : b.gravity_mps2) o.f32(v);
  return o.position();
}

namespace {

// The correction block judged without decoding it (no copy of the ~700-byte struct on the
// stack, which the platform's call paths cannot afford): the layout of the header, walked.
bool correction_image_valid(std::span<const std::uint8_t> image) {
  In in(image);
  bool ok = in.u8() <= kJoints;
  for (std::size_t j = 0; j < kJoints; ++j) {
    const std::uint8_t type = in.u8(), convention = in.u8();
    ok = ok && type <= 1 && convention <= 2;
    for (int k = 0; k < 10; ++k) (void)in.f32();
  }
  for (int k = 0; k < 12; ++k) (void)in.f32();
  for (std::size_t j = 0; j < kJoints; ++j) {
    ok = ok && in.u8() <= 1;
    for (std::size_t k = 0; k < kJoints + 8; ++k) (void)in.f32();
  }
  for (int k = 0; k < 7; ++k) (void)in.f32();
  return ok && in.finite() && in.position() == kCorrectionBytes;
}

}  // namespace

DecodeStatus check_correction_block(std::span<const std::uint8_t> image) {
  if (image.size() != kCorrectionBytes) return DecodeStatus::kWrongLength;
  return correction_image_valid(image) ? DecodeStatus::kOk : DecodeStatus::kBadValue;
}

// Judged first, then read straight into `b`: written only on kOk.
DecodeStatus decode_block(std::span<const std::uint8_t> image, CorrectionParameters& b) {
  if (image.size() != kCorrectionBytes) return DecodeStatus::kWrongLength;
  if (!correction_image_valid(image)) return DecodeStatus::kBadValue;
  In in(image);
  b.joint_count = in.u8();
  for (JointModel& j : b.joints) {
    j.type = static_cast<JointKind>(in.u8());
    j.convention = static_cast<LinkKind>(in.u8());
    get_dh(in, j.nominal);
    get_dh(in, j.error);
  }
  for (float& f : b.tool_offset) f = in.f32();
  for (float& f : b.tool_error) f = in.f32();
  for (JointMapValues& m : b.joint_maps) {
    m.coupled = in.u8() == 1;
    for (float& f : m.coupling) f = in.f32();
    for (float* f : {&m.scale, &m.scale_error, &m.compliance, &m.compliance_error, &m.mass_kg}) *f = in.f32();
    for (float& f : m.centre_of_mass_m) f = in.f32();
  }
  b.payload_mass_kg = in.f32();
  for (float& f : b.payload_centre_of_mass_m) f = in.f32();
  for (float& f : b.gravity_mps2) f = in.f32();
  return DecodeStatus::kOk;
}

std::size_t encode_parameter_message(MessageType type, ParameterBlock block, std::span<const std::uint8_t> payload,
                                     std::span<std::uint8_t> out) {
  if (payload.size() > kMaxBlockBytes || out.size() < kParameterHeaderBytes + payload.size()) return 0;
  Out o(out);
  o.u8(static_cast<std::uint8_t>(type));
  o.u8(static_cast<std::uint8_t>(block));
  o.u16(kBlockFormatVersion);
  o.u16(static_cast<std::uint16_t>(payload.size()));
  o.u32(crc32(payload));
  for (const std::uint8_t b : payload) o.u8(b);
  return o.position();
}

DecodeStatus decode_parameter_message(std::span<const std::uint8_t> message, ParameterHeader& header,
                                      std::span<const std::uint8_t>& payload) {
  if (message.empty()) return DecodeStatus::kWrongLength;
  if (message[0] != static_cast<std::uint8_t>(MessageType::kParameterWrite) &&
      message[0] != static_cast<std::uint8_t>(MessageType::kParameterData))
    return DecodeStatus::kWrongId;
  if (message.size() < kParameterHeaderBytes) return DecodeStatus::kWrongLength;
  In in(message);
  header.type = static_cast<MessageType>(in.u8());
  header.block = in.u8();
  header.version = in.u16();
  header.length = in.u16();
  header.crc32 = in.u32();
  if (message.size() != kParameterHeaderBytes + header.length) return DecodeStatus::kWrongLength;
  payload = message.subspan(kParameterHeaderBytes);
  return DecodeStatus::kOk;
}

AckStatus check_parameter_payload(const ParameterHeader& header, std::span<const std::uint8_t> payload) {
  if (!is_known_block(header.block)) return AckStatus::kUnknownBlock;
  if (header.version != kBlockFormatVersion) return AckStatus::kBadVersion;
  if (payload.size() != block_size(static_cast<ParameterBlock>(header.block))) return AckStatus::kBadLength;
  if (crc32(payload) != header.crc32) return AckStatus::kCrcMismatch;
  return AckStatus::kOk;
}

std::size_t encode_parameter_read(ParameterBlock block, std::span<std::uint8_t> out) {
  if (out.size() < 2) return 0;
  out[0] = static_cast<std::uint8_t>(MessageType::kParameterRead);
  out[1] = static_cast<std::uint8_t>(block);
  return 2;
}

DecodeStatus decode_parameter_read(std::span<const std::uint8_t> message, std::uint8_t& block) {
  if (message.empty() || message[0] != static_cast<std::uint8_t>(MessageType::kParameterRead))
    return DecodeStatus::kWrongId;
  if (message.size() != 2) return DecodeStatus::kWrongLength;
  block = message[1];
  return DecodeStatus::kOk;
}

}  // namespace kincal::shared

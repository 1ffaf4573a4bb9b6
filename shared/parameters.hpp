// Parameter blocks the host loads into the platform, and the ISO-TP messages that carry them.
//
// Blocks are little-endian byte images with IEEE-754 float32 values: the M4F computes in single
// precision, so float32 is exactly what the firmware uses (no conversion loss, no wasted bits on
// the way), and a block crosses the bus only when the calibration changes. Each block has a
// format version; the platform refuses a version it does not read.
//   kIntrinsics  v1  40 bytes: fx fy cx cy (px), k1 k2 p1 p2 k3 (OpenCV's distortion model),
//                    width height (u16 px). Pixel (0, 0) is the centre of the top-left pixel.
//   kColourLut   v1  2048 bytes: one 4-bit colour class per RGB444 cell (r4 << 8 | g4 << 4 | b4),
//                    two cells per byte, even cell in the low nibble; class 0 is background.
//   kGeometry    v4  197 bytes: four ranger beams in the camera frame, each origin (m) and unit
//                    direction; fiducial count (u8, <= 8) and their positions in the square frame (m);
//                    then the strip's square pitch (m): the centre-to-centre distance of neighbouring
//                    calibration squares along the square frame's x axis (Doty's strip: squares in a
//                    row, axes parallel), 0 when the platform uses one square per frame; refused
//                    unless 0 or within [0.01, 2] m (kMinSquarePitchM, kMaxSquarePitchM).
//   kCorrection  v3  671 bytes: joint count (u8, <= 6); per joint its type (u8: 0 revolute, 1
//                    prismatic), its link convention (u8: 0 standard DH, 1 modified DH, 2 Doty's
//                    (d, theta, beta, a, alpha); link_model.hpp), the nominal values and their
//                    identified errors (a m, alpha rad, d m, theta rad, beta rad; 2 x 5 float32);
//                    then the nominal tool offset flange_T_tool, x y z (m) rx ry rz (rotation
//                    vector, rad), and its identified error, a small motion of the tool frame
//                    along and about its own axes (error_model.hpp's tool_x..tool_rz), 2 x 6 float32.
//                    Format 3 adds the joint map (host/model/robot_model.hpp's top comment), 370
//                    bytes more (671 in all; an ISO-TP message carries up to 4095): per joint a
//                    coupling flag (u8: 0 the joint's own reading, 1 the row follows) and row
//                    (6 float32: v_i = sum_k row_k u_k; not read when the flag is 0), the nominal
//                    scale and its identified error, the nominal compliance (rad/(N m) or m/N)
//                    and its identified error (4 float32), the mass (kg) of the link the joint
//                    moves and its centre of mass in the frame at the link's end (m) (4 float32);
//                    then the payload's mass and centre of mass in the flange frame, and the
//                    gravity vector in frame 0 (m/s^2) (7 float32). Coupling, masses, payload
//                    and gravity are one set for the nominal and the identified model (the
//                    identified masses and gravity direction when the nominal has no compliance,
//                    host/correct/correction_block.cpp); a block without compliance carries them
//                    all the same (zeros are fine).
//   Format version 2 (all blocks): v1's correction block had no joint type or convention (every
//   joint revolute, modified DH), which cannot describe a prismatic axis or Doty's links.
//   Format version 3 (all blocks): the correction block's joint map; a platform refuses a
//   version 2 block (AckStatus kBadVersion) and ignores a stored one at start.
//   Format version 4 (all blocks): the geometry block's square pitch (193 -> 197 bytes), so that
//   the platform's pose can use every square of the strip in view; a platform refuses a version 3
//   block and ignores a stored one at start, as above.
//
// Messages (ISO-TP payloads, little-endian):
//   ParameterWrite  host -> platform: type 0x01 | block u8 | version u16 | length u16 | crc32 u32 | payload
//   ParameterRead   host -> platform: type 0x02 | block u8
//   ParameterData   platform -> host: type 0x82 and the rest as ParameterWrite
//   crc32 (shared/crc32.hpp) covers the payload. The platform answers a write with a ParameterAck
//   frame and a read with ParameterData (or a ParameterAck saying why not).
//
// Cost: O(bytes), no heap. Thread/ISR safety: pure. Failure modes: every decoder returns a
// DecodeStatus or AckStatus; decode of a block rejects non-finite floats, counts too large and
// a square pitch out of range (kBadValue).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "shared/measurement_report.hpp"
#include "shared/protocol.hpp"

namespace kincal::shared {

inline constexpr std::uint16_t kBlockFormatVersion = 4;

struct CameraIntrinsics {
  float fx_px = 0, fy_px = 0, cx_px = 0, cy_px = 0;
  float k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
  std::uint16_t width_px = 0, height_px = 0;
};
inline constexpr std::size_t kIntrinsicsBytes = 9 * 4 + 2 * 2;

struct ColourLut {
  static constexpr std::size_t kCells = 4096;
  std::array<std::uint8_t, kCells / 2> packed{};
  constexpr std::uint8_t colour_class(std::uint8_t r4, std::uint8_t g4, std::uint8_t b4) const {
    const std::size_t cell = (static_cast<std::size_t>(r4 & 0xF) << 8) | static_cast<std::size_t>((g4 & 0xF) << 4) |
                             static_cast<std::size_t>(b4 & 0xF);
    const std::uint8_t byte = packed[cell / 2];
    return static_cast<std::uint8_t>((cell % 2) ? byte >> 4 : byte & 0xF);
  }
};
inline constexpr std::size_t kColourLutBytes = ColourLut::kCells / 2;

struct RangerBeam {
  std::array<float, 3> origin_m{};
  std::array<float, 3> direction{};  // unit vector, camera frame
};
struct PlatformGeometry {
  std::array<RangerBeam, kRangers> rangers{};
  std::uint8_t fiducial_count = 0;
  std::array<std::array<float, 3>, kMaxFiducials> fiducial_square_m{};
  // Centre-to-centre distance of neighbouring squares of the strip along the square frame's x
  // axis (format 4); 0: the platform uses one square per frame.
  float square_pitch_m = 0.0f;
};
inline constexpr std::size_t kGeometryBytes = kRangers * 6 * 4 + 1 + kMaxFiducials * 3 * 4 + 4;
static_assert(kGeometryBytes == 197);
// The square pitch a geometry block may carry besides 0. A pitch smaller than the fiducial
// pattern would overlap the squares; 0.01 m is a floor well below any printed strip (Doty's
// squares are 0.1016 m). The platform's camera sees a few decimetres, so no two squares 2 m apart.
inline constexpr float kMinSquarePitchM = 0.01f;
inline constexpr float kMaxSquarePitchM = 2.0f;

struct DhValues {
  float a_m = 0, alpha_rad = 0, d_m = 0, theta_rad = 0, beta_rad = 0;
};
enum class JointKind : std::uint8_t { kRevolute = 0, kPrismatic = 1 };
enum class LinkKind : std::uint8_t { kStandardDh = 0, kModifiedDh = 1, kDoty = 2 };
struct JointModel {
  JointKind type = JointKind::kRevolute;
  LinkKind convention = LinkKind::kModifiedDh;
  DhValues nominal;
  DhValues error;  // identified deviation: true = nominal + error
};
// One joint's part of the joint map (format 3). Defaults: the joint's own reading, scale 1, no
// compliance, no mass.
struct JointMapValues {
  bool coupled = false;
  std::array<float, kJoints> coupling{};  // read only when coupled
  float scale = 1.0f, scale_error = 0.0f;
  float compliance = 0.0f, compliance_error = 0.0f;  // rad/(N m) or m/N
  float mass_kg = 0.0f;
  std::array<float, 3> centre_of_mass_m{};  // in the frame at the end of the link
};
struct CorrectionParameters {
  std::uint8_t joint_count = 0;
  std::array<JointModel, kJoints> joints{};
  std::array<float, 6> tool_offset{};  // x y z (m), rx ry rz (rad)
  std::array<float, 6> tool_error{};   // along x y z (m), about x y z (rad), in the tool frame
  std::array<JointMapValues, kJoints> joint_maps{};
  float payload_mass_kg = 0.0f;
  std::array<float, 3> payload_centre_of_mass_m{};           // flange frame
  std::array<float, 3> gravity_mps2{0.0f, 0.0f, -9.80665f};  // frame 0
};
inline constexpr std::size_t kJointMapBytes = 1 + kJoints * 4 + 4 * 4 + 4 * 4;
inline constexpr std::size_t kCorrectionBytes = 1 + kJoints * (2 + 10 * 4) + 12 * 4 + kJoints * kJointMapBytes + 7 * 4;
static_assert(kCorrectionBytes == 671);

inline constexpr std::size_t kParameterHeaderBytes = 10;
inline constexpr std::size_t kMaxBlockBytes = kColourLutBytes;
inline constexpr std::size_t kMaxParameterMessageBytes = kParameterHeaderBytes + kMaxBlockBytes;
// The largest message each side receives: sizes the ISO-TP buffers.
inline constexpr std::size_t kMaxRequestBytes = kMaxParameterMessageBytes;
inline constexpr std::size_t kMaxResponseBytes =
    kMaxParameterMessageBytes > kMaxReportBytes ? kMaxParameterMessageBytes : kMaxReportBytes;

// Byte length of a block's image, or 0 for an unknown block.
std::size_t block_size(ParameterBlock block);
bool is_known_block(std::uint8_t block);

// Block images. encode_* return the bytes written (0 if `out` is too small).
std::size_t encode_block(const CameraIntrinsics& block, std::span<std::uint8_t> out);
std::size_t encode_block(const ColourLut& block, std::span<std::uint8_t> out);
std::size_t encode_block(const PlatformGeometry& block, std::span<std::uint8_t> out);
std::size_t encode_block(const CorrectionParameters& block, std::span<std::uint8_t> out);
DecodeStatus decode_block(std::span<const std::uint8_t> image, CameraIntrinsics& block);
DecodeStatus decode_block(std::span<const std::uint8_t> image, ColourLut& block);
DecodeStatus decode_block(std::span<const std::uint8_t> image, PlatformGeometry& block);
DecodeStatus decode_block(std::span<const std::uint8_t> image, CorrectionParameters& block);
// decode_block's judgement of a correction block without decoding it (no struct on the stack).
DecodeStatus check_correction_block(std::span<const std::uint8_t> image);

struct ParameterHeader {
  MessageType type = MessageType::kParameterWrite;  // kParameterWrite or kParameterData
  std::uint8_t block = 0;
  std::uint16_t version = kBlockFormatVersion;
  std::uint16_t length = 0;
  std::uint32_t crc32 = 0;
};

// Writes header (with length and crc32 computed from `payload`) + payload; returns the bytes
// written or 0 if `out` is too small or the payload too long.
std::size_t encode_parameter_message(MessageType type, ParameterBlock block, std::span<const std::uint8_t> payload,
                                     std::span<std::uint8_t> out);
// Parses the header of a ParameterWrite/ParameterData message and checks its framing: the
// payload span points into `message`. Block, version and CRC are left for the caller to judge
// (check_parameter_payload), because each failure has its own AckStatus.
DecodeStatus decode_parameter_message(std::span<const std::uint8_t> message, ParameterHeader& header,
                                      std::span<const std::uint8_t>& payload);
AckStatus check_parameter_payload(const ParameterHeader& header, std::span<const std::uint8_t> payload);

std::size_t encode_parameter_read(ParameterBlock block, std::span<std::uint8_t> out);
DecodeStatus decode_parameter_read(std::span<const std::uint8_t> message, std::uint8_t& block);

}  // namespace kincal::shared

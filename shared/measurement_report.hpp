// ISO-TP messages of the protocol (payloads on can_id::kIsoTpRequest / kIsoTpResponse): the
// MessageType byte every one starts with, and the measurement report.
//
// Measurement report layout (bit-packed, Intel order, no padding between fields; the message is
// ceil(bits / 8) bytes and any other length is rejected):
//   type 8 (0x81) | sequence 8 (the trigger's) | timestamp_us 32 | sections 6 | status 4
//   then each present section, in bit order of section:::
//   ranges     4 x u16, LSB 2^-16 m (15.3 um), range [0, 1) m, 0xFFFF = no echo. The rangers read
//              tens of um of noise at 0.05-0.5 m; 15 um is below that, and 1 m is beyond any
//              working distance of the platform.
//   plane      in the camera frame, normal pointing at the camera (n_z < 0, n_z is implied):
//              n_x, n_y i16 LSB 2^-15 (30.5 urad of tilt), distance u16 LSB 2^-16 m, [0, 1) m.
//   fiducials  count 4 (0..8), then per fiducial: id 4 | x 16 | y 16, pixel centre as uq10.6
//              (LSB 1/64 px, range [0, 1024) px): the camera rows of the STM32F407 are at most
//              1024 px (VGA in practice), and 1/64 px rounding (RMS 0.0045 px) is below the
//              centroid's noise floor (about 0.01 px for a bright spot, DESIGN.md).
//   pose       squares 4 (protocol 3.0): how many calibration squares of the strip the pose used,
//              1..15 (0 is refused, kBadValue); the reference square, whose frame the pose is in
//              and whose fiducials the fiducials section lists, is one of them. The others are its
//              neighbours along the strip (the geometry block's square pitch).
//              Then square_T_camera (the reference square's frame): translation 3 x i20 LSB
//              2^-18 m (3.8 um, +-2 m), rotation vector (axis * angle) 3 x i18 LSB 2^-15 rad
//              (30.5 urad, +-4 rad >= pi). A pose from four fiducials is good to ~10 um /
//              ~0.1 mrad, so neither LSB limits it.
//              Then its covariance (protocol 2.0): the 6 x 6 covariance of (t, delta): t the
//              reported translation (m, square frame), delta the rotation's error as a small
//              rotation in the square frame (rad): true square_R_camera = exp([delta]x) *
//              reported square_R_camera (not the rotation vector's own components, whose
//              covariance would need the SO(3) Jacobian of the angle), as
//              6 standard deviations, u10 each, sigma = 2^((raw - 896) / 32) m or rad: 1/32
//                octave steps (rounding within +-1.1 % of sigma, +-2.2 % of the variance), range
//                2^-28 (3.7 nm / 3.7 nrad; raw 0 stands for this and anything smaller) to
//                2^(127/32) = 15.7 (raw 1023, saturating: "no information");
//              15 correlations, i8 each, rho = raw / 127 (LSB 0.0079, rounding +-0.004), the upper
//                triangle row by row ((0,1), (0,2), ... (4,5)); raw -128 is invalid (kBadValue).
//              A log scale because the sigmas span decades (um from the camera, mm along a poor
//              axis); 180 bits for what 21 floats would need 672. Near-singular covariances can
//              come back slightly indefinite after rounding the correlations: the host regularizes.
//   blobs      count 7 (0..64), then per blob: x 16 | y 16 (uq10.6 px) | area 16 (px, saturating) |
//              colour class 4 (the LUT's 16 classes) | peak 8 (DN, 8-bit camera).
//   point      triangulated beacon, stereo rig frame: 3 x i20 LSB 2^-16 m (15 um, +-8 m); stereo
//              errors are mm at 1 m and cm at 4.5 m, so 15 um is far below them.
//   timestamp_us: platform clock at mid-exposure, 1 us (at 1 rad/s one us is 1 urad, below the
//   joint LSB); wraps after 71.6 min, which the host unwraps with the reports' arrival times.
//   A section asked for but not produced is absent, and status says why.
//
// Sizes: the ARID report (ranges, plane, fiducials, pose) is 77 bytes with 4 fiducials and 86
// with 6 (Doty's square); the largest report (every section, 8 fiducials, 64 blobs) is
// kMaxReportBytes = 584.
//
// Cost: O(bytes) bit copies, no heap. Thread/ISR safety: pure. Failure modes: decode returns a
// DecodeStatus (wrong type, wrong length, count or enumeration out of range); encode fails only
// with a too-small output buffer (returns 0).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "shared/protocol.hpp"

namespace kincal::shared {

enum class MessageType : std::uint8_t {
  kParameterWrite = 0x01,     // host -> platform (parameters.hpp)
  kParameterRead = 0x02,      // host -> platform (parameters.hpp)
  kMeasurementReport = 0x81,  // platform -> host
  kParameterData = 0x82,      // platform -> host (parameters.hpp)
};

enum class MeasureStatus : std::uint8_t {
  kOk = 0,            // every section asked for is present
  kNotAvailable = 1,  // this build's measurement step cannot produce some asked-for section
  kNoParameters = 2,  // a needed parameter block is missing
  kCameraFailure = 3,
  kRangerFailure = 4,
  kNoTarget = 5,  // nothing usable in view (too few fiducials, no plane)
};
inline constexpr std::uint8_t kMaxMeasureStatus = 5;

inline constexpr std::size_t kRangers = 4;
inline constexpr std::size_t kMaxFiducials = 8;
inline constexpr std::size_t kMaxBlobs = 64;
inline constexpr std::uint16_t kNoEcho = 0xFFFF;
inline constexpr std::uint8_t kMaxPoseSquares = 15;
inline constexpr std::size_t kPoseDof = 6;                                       // t_x t_y t_z, then the rotation error
inline constexpr std::size_t kPoseCorrelations = kPoseDof * (kPoseDof - 1) / 2;  // upper triangle

struct Fiducial {
  std::uint8_t id = 0;     // 4 bits
  std::uint16_t x_q6 = 0;  // uq10.6 px
  std::uint16_t y_q6 = 0;  // uq10.6 px
};

struct Blob {
  std::uint16_t x_q6 = 0;
  std::uint16_t y_q6 = 0;
  std::uint16_t area_px = 0;
  std::uint8_t colour_class = 0;  // 4 bits
  std::uint8_t peak_dn = 0;
};

struct MeasurementReport {
  std::uint8_t sequence = 0;
  std::uint32_t timestamp_us = 0;
  std::uint8_t sections = 0;  // section:: bits present
  MeasureStatus status = MeasureStatus::kOk;

  std::array<std::uint16_t, kRangers> range_raw{};  // LSB 2^-16 m, kNoEcho
  std::int16_t plane_normal_x_raw = 0;              // LSB 2^-15
  std::int16_t plane_normal_y_raw = 0;              // LSB 2^-15
  std::uint16_t plane_distance_raw = 0;             // LSB 2^-16 m
  std::uint8_t fiducial_count = 0;
  std::array<Fiducial, kMaxFiducials> fiducials{};
  std::array<std::int32_t, 3> translation_raw{};                      // i20, LSB 2^-18 m
  std::array<std::int32_t, 3> rotation_raw{};                         // i18, LSB 2^-15 rad
  std::array<std::uint16_t, kPoseDof> pose_sigma_raw{};               // u10, sigma = 2^((raw - 896) / 32)
  std::array<std::int8_t, kPoseCorrelations> pose_correlation_raw{};  // i8 in [-127, 127], rho = raw / 127
  std::uint8_t pose_squares = 1;  // squares of the strip the pose used, 1..kMaxPoseSquares (pose section only)
  std::uint8_t blob_count = 0;
  std::array<Blob, kMaxBlobs> blobs{};
  std::array<std::int32_t, 3> point_raw{};  // i20, LSB 2^-16 m
};

// Bits of each part, and the largest report: the platform's ISO-TP buffers are sized from it.
namespace report_bits {
inline constexpr std::size_t kHeader = 8 + 8 + 32 + 6 + 4;
inline constexpr std::size_t kRanges = kRangers * 16;
inline constexpr std::size_t kPlane = 16 + 16 + 16;
inline constexpr std::size_t kFiducial = 4 + 16 + 16;
inline constexpr std::size_t kFiducialsHeader = 4;
inline constexpr std::size_t kPoseSigma = 10;
inline constexpr std::size_t kPoseCorrelation = 8;
inline constexpr std::size_t kPoseSquares = 4;
inline constexpr std::size_t kPose =
    kPoseSquares + 3 * 20 + 3 * 18 + kPoseDof * kPoseSigma + kPoseCorrelations * kPoseCorrelation;
inline constexpr std::size_t kBlob = 16 + 16 + 16 + 4 + 8;
inline constexpr std::size_t kBlobsHeader = 7;
inline constexpr std::size_t kPoint = 3 * 20;
inline constexpr std::size_t kMax = kHeader + kRanges + kPlane + kFiducialsHeader + kMaxFiducials * kFiducial + kPose +
                                    kBlobsHeader + kMaxBlobs * kBlob + kPoint;
}  // namespace report_bits
inline constexpr std::size_t kMaxReportBytes = (report_bits::kMax + 7) / 8;
static_assert(kMaxFiducials < (1u << report_bits::kFiducialsHeader), "fiducial count field too narrow");
static_assert(kMaxBlobs < (1u << report_bits::kBlobsHeader), "blob count field too narrow");
static_assert(kMaxPoseSquares < (1u << report_bits::kPoseSquares), "pose squares field too narrow");
static_assert(kMaxReportBytes == 584);

// Bytes of the encoded report (depends on the sections present and the counts).
std::size_t report_size(const MeasurementReport& report);
// Returns the bytes written, or 0 if `out` is too small. Counts above the maxima are clamped, and
// pose_squares to 1..kMaxPoseSquares (a pose rests on at least its reference square).
std::size_t encode(const MeasurementReport& report, std::span<std::uint8_t> out);
DecodeStatus decode(std::span<const std::uint8_t> message, MeasurementReport& report);

// Physical conversions (host side and tests; the firmware works in raw units).
inline constexpr double kRangeLsbM = 1.0 / 65536.0;
inline constexpr double kPlaneNormalLsb = 1.0 / 32768.0;
inline constexpr double kPixelLsbPx = 1.0 / 64.0;
inline constexpr double kTranslationLsbM = 1.0 / 262144.0;
inline constexpr double kRotationLsbRad = 1.0 / 32768.0;
inline constexpr double kPointLsbM = 1.0 / 65536.0;

// The pose covariance's encoding (see the layout above). Pure float/integer arithmetic, no libm
// but sqrtf, the same bits on both targets.
inline constexpr std::uint16_t kPoseSigmaRawMax = 1023;
inline constexpr int kPoseSigmaRawOffset = 896;  // raw of sigma = 1 (2^0)
inline constexpr int kPoseSigmaStepsPerOctave = 32;
inline constexpr int kPoseCorrelationScale = 127;
// Nearest raw of sigma (m or rad) in the log scale; NaN, infinity and values above the range
// saturate at kPoseSigmaRawMax, zero, negative and tiny values give 0.
std::uint16_t quantize_pose_sigma(float sigma);
double pose_sigma(std::uint16_t raw);
// Nearest raw of a correlation coefficient, clamped to [-1, 1]; NaN -> 0.
std::int8_t quantize_pose_correlation(float rho);
// Sets the report's sigma and correlation fields from a 6 x 6 covariance (row-major, order
// t_x t_y t_z delta_x delta_y delta_z as in the layout above; only the upper triangle and
// diagonal are read). A zero variance gives correlations 0 in its row and column.
void set_pose_covariance(std::span<const float, kPoseDof * kPoseDof> covariance, MeasurementReport& report);
// The 6 x 6 covariance the report's fields stand for (row-major, symmetric), as set_pose_covariance
// laid it out.
std::array<double, kPoseDof * kPoseDof> pose_covariance(const MeasurementReport& report);

}  // namespace kincal::shared

#include "shared/measurement_report.hpp"

#include <bit>
#include <cmath>

#include "shared/bit_field.hpp"

namespace kincal::shared {

namespace {

// 2^(j / 64), j = 0..63, rounded to float (python: struct.pack('f', 2 ** (j / 64))): the even
// entries are the sigma scale's steps within an octave, the odd ones the rounding thresholds
// between them.
constexpr std::array<float, 64> kPow2Sixtyfourths = {
    1.0f,        1.01088929f, 1.0218972f,  1.03302491f, 1.04427373f, 1.05564523f, 1.06714046f, 1.07876074f,
    1.09050775f, 1.10238254f, 1.1143868f,  1.12652159f, 1.13878858f, 1.15118921f, 1.1637249f,  1.17639697f,
    1.18920708f, 1.20215678f, 1.21524739f, 1.22848058f, 1.24185777f, 1.25538075f, 1.26905096f, 1.28287005f,
    1.29683959f, 1.31096125f, 1.32523668f, 1.33966756f, 1.35425556f, 1.36900246f, 1.38390994f, 1.39897966f,
    1.41421354f, 1.42961335f, 1.44518077f, 1.46091783f, 1.47682619f, 1.49290776f, 1.50916445f, 1.52559817f,
    1.54221082f, 1.55900443f, 1.5759809f,  1.59314215f, 1.61049032f, 1.62802744f, 1.64575553f, 1.66367662f,
    1.68179286f, 1.70010638f, 1.71861935f, 1.73733389f, 1.75625217f, 1.77537644f, 1.79470909f, 1.81425214f,
    1.8340081f,  1.85397911f, 1.87416768f, 1.89457595f, 1.91520655f, 1.93606174f, 1.95714414f, 1.97845602f};

std::size_t correlation_index(std::size_t i, std::size_t j) {  // i < j
  return i * kPoseDof - i * (i + 1) / 2 + (j - i - 1);
}

std::uint8_t fiducial_count(const MeasurementReport& r) {
  return r.fiducial_count > kMaxFiducials ? static_cast<std::uint8_t>(kMaxFiducials) : r.fiducial_count;
}
std::uint8_t pose_squares(const MeasurementReport& r) {
  if (r.pose_squares < 1) return 1;
  return r.pose_squares > kMaxPoseSquares ? kMaxPoseSquares : r.pose_squares;
}
std::uint8_t blob_count(const MeasurementReport& r) {
  return r.blob_count > kMaxBlobs ? static_cast<std::uint8_t>(kMaxBlobs) : r.blob_count;
}

std::size_t report_bit_count(const MeasurementReport& r) {
  std::size_t bits = report_bits::kHeader;
  if (r.sections & section::kRanges) bits += report_bits::kRanges;
  if (r.sections & section::kPlane) bits += report_bits::kPlane;
  if (r.sections & section::kFiducials)
    bits += report_bits::kFiducialsHeader + fiducial_count(r) * report_bits::kFiducial;
  if (r.sections & section::kPose) bits += report_bits::kPose;
  if (r.sections & section::kBlobs) bits += report_bits::kBlobsHeader + blob_count(r) * report_bits::kBlob;
  if (r.sections & section::kPoint) bits += report_bits::kPoint;
  return bits;
}

}  // namespace

std::uint16_t quantize_pose_sigma(float sigma) {
  if (!(sigma > 0.0f)) return sigma == sigma ? 0 : kPoseSigmaRawMax;
  const std::uint32_t bits = std::bit_cast<std::uint32_t>(sigma);
  const int exponent = static_cast<int>((bits >> 23) & 0xFFu) - 127;
  if (exponent > 8) return kPoseSigmaRawMax;                                      // infinity, and far above 2^4
  if (exponent < -40) return 0;                                                   // denormals, and far below 2^-28
  const float mantissa = std::bit_cast<float>((bits & 0x7FFFFFu) | 0x3F800000u);  // [1, 2)
  int step = 0;
  while (step < kPoseSigmaStepsPerOctave && mantissa >= kPow2Sixtyfourths[static_cast<std::size_t>(2 * step + 1)])
    ++step;
  const int raw = exponent * kPoseSigmaStepsPerOctave + step + kPoseSigmaRawOffset;
  return static_cast<std::uint16_t>(raw < 0 ? 0 : (raw > kPoseSigmaRawMax ? kPoseSigmaRawMax : raw));
}

double pose_sigma(std::uint16_t raw) {
  const unsigned r = raw > kPoseSigmaRawMax ? kPoseSigmaRawMax : raw;
  const unsigned octave = r / static_cast<unsigned>(kPoseSigmaStepsPerOctave);  // 0..31
  const unsigned step = r % static_cast<unsigned>(kPoseSigmaStepsPerOctave);
  constexpr unsigned kOffsetOctaves = static_cast<unsigned>(kPoseSigmaRawOffset / kPoseSigmaStepsPerOctave);
  return static_cast<double>(kPow2Sixtyfourths[2 * step]) * static_cast<double>(1u << octave) /
         static_cast<double>(1u << kOffsetOctaves);
}

std::int8_t quantize_pose_correlation(float rho) {
  if (!(rho == rho)) return 0;
  const float scaled = rho * static_cast<float>(kPoseCorrelationScale);
  if (scaled >= static_cast<float>(kPoseCorrelationScale)) return static_cast<std::int8_t>(kPoseCorrelationScale);
  if (scaled <= -static_cast<float>(kPoseCorrelationScale)) return static_cast<std::int8_t>(-kPoseCorrelationScale);
  return static_cast<std::int8_t>(scaled >= 0.0f ? scaled + 0.5f : scaled - 0.5f);
}

void set_pose_covariance(std::span<const float, kPoseDof * kPoseDof> covariance, MeasurementReport& report) {
  std::array<float, kPoseDof> sigma{};
  for (std::size_t i = 0; i < kPoseDof; ++i) {
    const float variance = covariance[i * kPoseDof + i];
    sigma[i] = variance > 0.0f ? std::sqrt(variance) : (variance == variance ? 0.0f : variance);
    report.pose_sigma_raw[i] = quantize_pose_sigma(sigma[i]);
  }
  for (std::size_t i = 0; i < kPoseDof; ++i)
    for (std::size_t j = i + 1; j < kPoseDof; ++j) {
      const float scale = sigma[i] * sigma[j];
      report.pose_correlation_raw[correlation_index(i, j)] =
          scale > 0.0f ? quantize_pose_correlation(covariance[i * kPoseDof + j] / scale) : std::int8_t{0};
    }
}

std::array<double, kPoseDof * kPoseDof> pose_covariance(const MeasurementReport& report) {
  std::array<double, kPoseDof> sigma{};
  for (std::size_t i = 0; i < kPoseDof; ++i) sigma[i] = pose_sigma(report.pose_sigma_raw[i]);
  std::array<double, kPoseDof * kPoseDof> c{};
  for (std::size_t i = 0; i < kPoseDof; ++i) {
    c[i * kPoseDof + i] = sigma[i] * sigma[i];
    for (std::size_t j = i + 1; j < kPoseDof; ++j) {
      const double rho = static_cast<double>(report.pose_correlation_raw[correlation_index(i, j)]) /
                         static_cast<double>(kPoseCorrelationScale);
      c[i * kPoseDof + j] = c[j * kPoseDof + i] = rho * sigma[i] * sigma[j];
    }
  }
  return c;
}

std::size_t report_size(const MeasurementReport& report) { return (report_bit_count(report) + 7) / 8; }

std::size_t encode(const MeasurementReport& r, std::span<std::uint8_t> out) {
  const std::size_t size = report_size(r);
  if (out.size() < size) return 0;
  BitWriter w(out.first(size));
  w.put(8, static_cast<std::uint8_t>(MessageType::kMeasurementReport));
  w.put(8, r.sequence);
  w.put(32, r.timestamp_us);
  w.put(6, r.sections & section::kAll);
  w.put(4, static_cast<std::uint8_t>(r.status));
  if (r.sections & section::kRanges)
    for (const std::uint16_t range : r.range_raw) w.put(16, range);
  if (r.sections & section::kPlane) {
    w.put_signed(16, r.plane_normal_x_raw);
    w.put_signed(16, r.plane_normal_y_raw);
    w.put(16, r.plane_distance_raw);
  }
  if (r.sections & section::kFiducials) {
    const std::uint8_t n = fiducial_count(r);
    w.put(report_bits::kFiducialsHeader, n);
    for (std::size_t i = 0; i < n; ++i) {
      w.put(4, r.fiducials[i].id);
      w.put(16, r.fiducials[i].x_q6);
      w.put(16, r.fiducials[i].y_q6);
    }
  }
  if (r.sections & section::kPose) {
    w.put(report_bits::kPoseSquares, pose_squares(r));
    for (const std::int32_t t : r.translation_raw) w.put_signed(20, t);
    for (const std::int32_t a : r.rotation_raw) w.put_signed(18, a);
    for (const std::uint16_t sigma : r.pose_sigma_raw) w.put(report_bits::kPoseSigma, sigma);
    for (const std::int8_t rho : r.pose_correlation_raw) w.put_signed(report_bits::kPoseCorrelation, rho);
  }
  if (r.sections & section::kBlobs) {
    const std::uint8_t n = blob_count(r);
    w.put(report_bits::kBlobsHeader, n);
    for (std::size_t i = 0; i < n; ++i) {
      const Blob& b = r.blobs[i];
      w.put(16, b.x_q6);
      w.put(16, b.y_q6);
      w.put(16, b.area_px);
      w.put(4, b.colour_class);
      w.put(8, b.peak_dn);
    }
  }
  if (r.sections & section::kPoint)
    for (const std::int32_t p : r.point_raw) w.put_signed(20, p);
  return w.overflow() ? 0 : size;
}

DecodeStatus decode(std::span<const std::uint8_t> message, MeasurementReport& r) {
  if (message.empty() || message[0] != static_cast<std::uint8_t>(MessageType::kMeasurementReport))
    return DecodeStatus::kWrongId;
  if (message.size() * 8 < report_bits::kHeader) return DecodeStatus::kWrongLength;
  BitReader in(message);
  r = MeasurementReport{};
  in.get(8);
  r.sequence = static_cast<std::uint8_t>(in.get(8));
  r.timestamp_us = static_cast<std::uint32_t>(in.get(32));
  r.sections = static_cast<std::uint8_t>(in.get(6));
  const auto status = in.get(4);
  if (status > kMaxMeasureStatus) return DecodeStatus::kBadValue;
  r.status = static_cast<MeasureStatus>(status);
  if (r.sections & section::kRanges)
    for (std::uint16_t& range : r.range_raw) range = static_cast<std::uint16_t>(in.get(16));
  if (r.sections & section::kPlane) {
    r.plane_normal_x_raw = static_cast<std::int16_t>(in.get_signed(16));
    r.plane_normal_y_raw = static_cast<std::int16_t>(in.get_signed(16));
    r.plane_distance_raw = static_cast<std::uint16_t>(in.get(16));
  }
  if (r.sections & section::kFiducials) {
    const auto n = in.get(report_bits::kFiducialsHeader);
    if (n > kMaxFiducials) return DecodeStatus::kBadValue;
    r.fiducial_count = static_cast<std::uint8_t>(n);
    for (std::size_t i = 0; i < n; ++i) {
      r.fiducials[i].id = static_cast<std::uint8_t>(in.get(4));
      r.fiducials[i].x_q6 = static_cast<std::uint16_t>(in.get(16));
      r.fiducials[i].y_q6 = static_cast<std::uint16_t>(in.get(16));
    }
  }
  if (r.sections & section::kPose) {
    const auto squares = in.get(report_bits::kPoseSquares);
    if (squares == 0) return DecodeStatus::kBadValue;
    r.pose_squares = static_cast<std::uint8_t>(squares);
    for (std::int32_t& t : r.translation_raw) t = static_cast<std::int32_t>(in.get_signed(20));
    for (std::int32_t& a : r.rotation_raw) a = static_cast<std::int32_t>(in.get_signed(18));
    for (std::uint16_t& sigma : r.pose_sigma_raw) sigma = static_cast<std::uint16_t>(in.get(report_bits::kPoseSigma));
    for (std::int8_t& rho : r.pose_correlation_raw) {
      const auto raw = in.get_signed(report_bits::kPoseCorrelation);
      if (raw < -kPoseCorrelationScale) return DecodeStatus::kBadValue;
      rho = static_cast<std::int8_t>(raw);
    }
  }
  if (r.sections & section::kBlobs) {
    const auto n = in.get(report_bits::kBlobsHeader);
    if (n > kMaxBlobs) return DecodeStatus::kBadValue;
    r.blob_count = static_cast<std::uint8_t>(n);
    for (std::size_t i = 0; i < n; ++i) {
      Blob& b = r.blobs[i];
      b.x_q6 = static_cast<std::uint16_t>(in.get(16));
      b.y_q6 = static_cast<std::uint16_t>(in.get(16));
      b.area_px = static_cast<std::uint16_t>(in.get(16));
      b.colour_class = static_cast<std::uint8_t>(in.get(4));
      b.peak_dn = static_cast<std::uint8_t>(in.get(8));
    }
  }
  if (r.sections & section::kPoint)
    for (std::int32_t& p : r.point_raw) p = static_cast<std::int32_t>(in.get_signed(20));
  // Exact length, and the bits padding the last byte are zero.
  if (in.overrun() || message.size() != (in.bit_position() + 7) / 8) return DecodeStatus::kWrongLength;
  if (in.get(static_cast<unsigned>(in.bits_left())) != 0) return DecodeStatus::kBadValue;
  return DecodeStatus::kOk;
}

}  // namespace kincal::shared

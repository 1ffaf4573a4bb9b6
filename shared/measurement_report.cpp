#include "shared/measurement_report.hpp"

#include "shared/bit_field.hpp"

namespace kincal::shared {

namespace {

std::uint8_t fiducial_count(const MeasurementReport& r) {
  return r.fiducial_count > kMaxFiducials ? static_cast<std::uint8_t>(kMaxFiducials) : r.fiducial_count;
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
    for (const std::int32_t t : r.translation_raw) w.put_signed(20, t);
    for (const std::int32_t a : r.rotation_raw) w.put_signed(18, a);
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
    for (std::int32_t& t : r.translation_raw) t = static_cast<std::int32_t>(in.get_signed(20));
    for (std::int32_t& a : r.rotation_raw) a = static_cast<std::int32_t>(in.get_signed(18));
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

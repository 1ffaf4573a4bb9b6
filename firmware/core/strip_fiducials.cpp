#include "firmware/core/strip_fiducials.hpp"

#include <array>
#include <cmath>

namespace kincal::core {

namespace {

// The predicted image of one fiducial: centre pixel and area (px^2). False if it cannot be seen.
struct Prediction {
  Vector2<float> centre_px = Vector2<float>::Zero();
  float area_px2 = 0.0f;
};

bool predict(const CameraIntrinsics& camera, float width_px, float height_px,
             const RigidTransform<float>& camera_T_square, const Vector2<float>& centre_m,
             const Vector2<float>& half_size_m, Prediction& out) {
  if (project_point(camera, camera_T_square * Vector3<float>(centre_m.x(), centre_m.y(), 0.0f), out.centre_px) !=
      CameraStatus::ok)
    return false;
  // Pixel (0, 0) is the centre of the top-left pixel: the frame spans [-0.5, size - 0.5].
  const float u = out.centre_px.x(), v = out.centre_px.y();
  if (!(u >= -0.5f && u <= width_px - 0.5f && v >= -0.5f && v <= height_px - 0.5f)) return false;
  // The rectangle's corners counter-clockwise in the square frame, then the shoelace sum.
  constexpr std::array<float, 4> sx{-1.0f, 1.0f, 1.0f, -1.0f}, sy{-1.0f, -1.0f, 1.0f, 1.0f};
  std::array<Vector2<float>, 4> corner{};
  for (std::size_t i = 0; i < 4; ++i) {
    const Vector3<float> p(centre_m.x() + sx[i] * half_size_m.x(), centre_m.y() + sy[i] * half_size_m.y(), 0.0f);
    if (project_point(camera, camera_T_square * p, corner[i]) != CameraStatus::ok) return false;
  }
  float twice_area = 0.0f;
  for (std::size_t i = 0; i < 4; ++i) {
    const Vector2<float>& a = corner[i];
    const Vector2<float>& b = corner[(i + 1) % 4];
    twice_area += a.x() * b.y() - b.x() * a.y();
  }
  out.area_px2 = 0.5f * std::fabs(twice_area);
  return out.area_px2 > 0.0f;
}

// The nearest acceptable blob within the gate, or blobs.size().
std::size_t nearest_blob(const Prediction& p, std::span<const Blob> blobs, std::span<const std::uint8_t> blob_taken,
                         const StripMatchOptions& options) {
  const float gate_px = options.gate_sides * std::sqrt(p.area_px2);
  float best2 = gate_px * gate_px;
  std::size_t best = blobs.size();
  for (std::size_t i = 0; i < blobs.size(); ++i) {
    const Blob& b = blobs[i];
    if (blob_taken[i] != 0 || (b.flags & (kIncomplete | kTouchesBorder)) != 0) continue;
    const float area = static_cast<float>(b.area_px);
    if (!(area >= options.area_ratio_min * p.area_px2 && area <= options.area_ratio_max * p.area_px2)) continue;
    const float dx = b.x_px.to_float() - p.centre_px.x(), dy = b.y_px.to_float() - p.centre_px.y();
    const float d2 = dx * dx + dy * dy;
    if (d2 <= best2) {
      best2 = d2;
      best = i;
    }
  }
  return best;
}

}  // namespace

StripMatchStatus match_strip_fiducials(const CameraIntrinsics& camera, std::uint16_t width_px, std::uint16_t height_px,
                                       const RigidTransform<float>& camera_T_square,
                                       std::span<const StripFiducial> pattern, std::uint8_t reference_found,
                                       float pitch_m, std::span<const Blob> blobs, std::span<std::uint8_t> blob_taken,
                                       const StripMatchOptions& options, std::span<PlanarCorrespondence> points,
                                       std::size_t point_count, StripMatch& out) noexcept {
  out = StripMatch{};
  if (!(pitch_m >= 0.0f && std::isfinite(pitch_m)) || pattern.size() > kStripMaxPatternFiducials ||
      blob_taken.size() < blobs.size() || width_px == 0 || height_px == 0 || point_count > points.size())
    return StripMatchStatus::bad_arguments;
  std::size_t n = point_count;
  const int steps = pitch_m > 0.0f ? 2 * kStripMaxOffset + 1 : 1;
  for (int step = 0; step < steps && n < points.size(); ++step) {
    // 0 (the reference square), then -1, +1, -2, +2, ...
    const int offset = step == 0 ? 0 : (step % 2 == 1 ? -1 : 1) * ((step + 1) / 2);
    const float shift_m = static_cast<float>(offset) * pitch_m;
    bool matched = false;
    for (std::size_t k = 0; k < pattern.size() && n < points.size(); ++k) {
      if (offset == 0 && (std::size_t{reference_found} >> k & 1u) != 0) continue;
      const Vector2<float> centre_m(pattern[k].centre_m.x() + shift_m, pattern[k].centre_m.y());
      Prediction p;
      if (!predict(camera, static_cast<float>(width_px), static_cast<float>(height_px), camera_T_square, centre_m,
                   pattern[k].half_size_m, p))
        continue;
      const std::size_t i = nearest_blob(p, blobs, blob_taken, options);
      if (i == blobs.size()) continue;
      blob_taken[i] = 1;
      PlanarCorrespondence& c = points[n++];
      c.pixel_px = Vector2<float>(blobs[i].x_px.to_float(), blobs[i].y_px.to_float());
      c.target_m = centre_m;
      c.fiducial_half_size_m = pattern[k].half_size_m;
      matched = true;
      if (offset == 0) ++out.reference_added;
    }
    if (matched && offset != 0) ++out.squares_matched;
  }
  out.points_added = static_cast<std::uint8_t>(n - point_count);
  return StripMatchStatus::ok;
}

}  // namespace kincal::core

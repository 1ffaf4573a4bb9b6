#include "firmware/core/fiducial_id.hpp"

#include <limits>

namespace kincal::core {

namespace {

constexpr std::int64_t kUnit = 16384;  // q14 unit vectors

// Doty's ids and their positions in units of 7s along the (x, y) axes.
struct Slot {
  std::uint8_t id;
  std::int8_t ax, ay;
};
// Perimeter p2 (+y), p3 (-x), p5 (+x), p6 (-y); corner p1 (-x, +y); the flipped corner (+x, -y).
constexpr Slot kSlots[6] = {{2, 0, 1}, {3, -1, 0}, {5, 1, 0}, {6, 0, -1}, {1, -1, 1}, {1, 1, -1}};
constexpr int kCornerSlot = 4, kFlippedCornerSlot = 5;

struct Shape {
  std::int64_t major2, minor2;  // twice the eigenvalues, q8 px^2
  std::int32_t ux, uy;          // major axis, q14 unit vector
};

std::int64_t abs64(std::int64_t v) { return v < 0 ? -v : v; }

// (x, y) scaled to length kUnit; (0, 0) stays (0, 0). The direction is kept to 15 bits, so
// the arithmetic stays in 32 bits (no 64-bit division).
void normalize(std::int64_t x, std::int64_t y, std::int32_t& ux, std::int32_t& uy) {
  while (abs64(x) >= (std::int64_t{1} << 15) || abs64(y) >= (std::int64_t{1} << 15)) {
    x /= 2;
    y /= 2;
  }
  const auto x32 = static_cast<std::int32_t>(x), y32 = static_cast<std::int32_t>(y);
  const auto n = static_cast<std::int32_t>(isqrt_round(static_cast<std::uint64_t>(x32 * x32 + y32 * y32)));
  auto scaled = [n](std::int32_t v) {  // round(v * kUnit / n), ties away from zero
    const std::int32_t a = (v < 0 ? -v : v) * static_cast<std::int32_t>(kUnit);
    const std::int32_t q = (a + n / 2) / n;
    return v < 0 ? -q : q;
  };
  ux = n == 0 ? 0 : scaled(x32);
  uy = n == 0 ? 0 : scaled(y32);
}

Shape shape_of(const Blob& b) {
  const std::int64_t a = b.mu20_px2.raw(), m = b.mu11_px2.raw(), c = b.mu02_px2.raw();
  const auto root = static_cast<std::int64_t>(isqrt_round(static_cast<std::uint64_t>((a - c) * (a - c) + 4 * m * m)));
  Shape s{a + c + root, a + c - root, 0, 0};
  // Eigenvector of the major eigenvalue: (l1 - c, b) or (b, l1 - a), whichever is better conditioned.
  if (a >= c) {
    normalize(s.major2 - 2 * c, 2 * m, s.ux, s.uy);
  } else {
    normalize(2 * m, s.major2 - 2 * a, s.ux, s.uy);
  }
  return s;
}

// major / minor in [lo, hi] (q8 ratios); a minor eigenvalue <= 0 is an infinite ratio.
bool ratio_at_least(const Shape& s, q24_8 lo) { return s.minor2 <= 0 || s.major2 * 256 >= lo.raw() * s.minor2; }
bool ratio_at_most(const Shape& s, q24_8 hi) { return s.minor2 > 0 && s.major2 * 256 <= hi.raw() * s.minor2; }

bool usable(const Blob& b) { return (b.flags & (kIncomplete | kTouchesBorder)) == 0; }

struct Hypothesis {
  std::int32_t ux = 0, uy = 0;  // y axis (q14); x axis = (-uy, ux)
  std::int64_t side_q8 = 0;     // s
  std::int16_t found[6] = {-1, -1, -1, -1, -1, -1};
  int support = -1;
};

bool perimeter_like(const FidModel& model, const Blob& b, std::int64_t side_q8) {
  if (!usable(b)) return false;
  const std::int64_t s2 = side_q8 * side_q8;  // q16
  const std::int64_t area_q16 = std::int64_t{b.area_px} << 16;
  if (area_q16 * 256 < model.area_ratio_min.raw() * s2 || area_q16 * 256 > model.area_ratio_max.raw() * s2) {
    return false;
  }
  return ratio_at_most(shape_of(b), model.perimeter_ratio_max);
}

void examine(const FidModel& model, std::span<const Blob> blobs, std::size_t centre, Hypothesis& h) {
  const Blob& c = blobs[centre];
  h = Hypothesis{};
  h.side_q8 = static_cast<std::int64_t>(isqrt_round(std::uint64_t{c.area_px} << 15));  // sqrt(area / 2) in q8
  const Shape shape = shape_of(c);
  h.ux = shape.ux;
  h.uy = shape.uy;
  if (h.uy < 0 || (h.uy == 0 && h.ux < 0)) {  // Doty's prior: y toward increasing image y
    h.ux = -h.ux;
    h.uy = -h.uy;
  }
  const std::int64_t distance_q8 = model.perimeter_distance_sides * h.side_q8;
  const std::int64_t radius_q8 = (distance_q8 * model.search_radius_fraction.raw()) >> 8;
  const std::int64_t cx = c.x_px.raw() >> 8, cy = c.y_px.raw() >> 8;
  const std::int64_t vx = -h.uy, vy = h.ux;  // the x axis
  h.support = 0;
  for (int k = 0; k < 6; ++k) {
    const std::int64_t px = cx + (distance_q8 * (kSlots[k].ax * vx + kSlots[k].ay * h.ux)) / kUnit;
    const std::int64_t py = cy + (distance_q8 * (kSlots[k].ax * vy + kSlots[k].ay * h.uy)) / kUnit;
    // On the x axis the nearest to the centre wins: a strip's neighbouring square puts its p3
    // (p5) 2s beyond this square's p5 (p3), and s from the centre blob's area can be off enough
    // to put the prediction nearer to it; nothing of the pattern lies between.
    const bool x_axis = kSlots[k].ay == 0;
    std::int64_t best = std::numeric_limits<std::int64_t>::max();
    for (std::size_t i = 0; i < blobs.size(); ++i) {
      if (i == centre) continue;
      const std::int64_t bx = blobs[i].x_px.raw() >> 8, by = blobs[i].y_px.raw() >> 8;
      const std::int64_t dx = bx - px, dy = by - py;
      if (dx * dx + dy * dy > radius_q8 * radius_q8) continue;
      const std::int64_t key = x_axis ? (bx - cx) * (bx - cx) + (by - cy) * (by - cy) : dx * dx + dy * dy;
      if (key <= best && perimeter_like(model, blobs[i], h.side_q8)) {
        best = key;
        h.found[k] = static_cast<std::int16_t>(i);
      }
    }
    if (h.found[k] >= 0) ++h.support;
  }
}

void set_unit(std::int32_t ux, std::int32_t uy, q16_16& x, q16_16& y) {
  x = q16_16::from_raw(ux * 4);  // q14 -> q16
  y = q16_16::from_raw(uy * 4);
}

}  // namespace

FidStatus identify_fiducials(const FidModel& model, std::span<const Blob> blobs, std::span<FidVerdict> verdicts,
                             FidResult& result) noexcept {
  result = FidResult{};
  if (verdicts.size() < blobs.size()) return FidStatus::kVerdictsTooShort;
  for (std::size_t i = 0; i < blobs.size(); ++i) verdicts[i] = FidVerdict::kUnused;
  if (blobs.size() > kFidMaxBlobs) return FidStatus::kTooManyBlobs;

  // Steps 1-3: every centre candidate, with its perimeter fiducials; keep the best supported.
  Hypothesis best, h;
  std::size_t best_centre = blobs.size();
  for (std::size_t i = 0; i < blobs.size(); ++i) {
    if (!usable(blobs[i])) continue;
    const Shape s = shape_of(blobs[i]);
    if (!ratio_at_least(s, model.centre_ratio_min) || !ratio_at_most(s, model.centre_ratio_max)) continue;
    verdicts[i] = FidVerdict::kRejectedWeakerCentre;  // until it wins
    examine(model, blobs, i, h);
    if (h.support > best.support) {
      best = h;
      best_centre = i;
    }
  }
  for (std::size_t i = 0; i < blobs.size(); ++i) {
    if ((blobs[i].flags & kIncomplete) != 0)
      verdicts[i] = FidVerdict::kRejectedIncomplete;
    else if ((blobs[i].flags & kTouchesBorder) != 0)
      verdicts[i] = FidVerdict::kRejectedBorder;
  }
  if (best_centre == blobs.size()) return FidStatus::kNoCentre;

  // Step 3: the corner marker decides between the prior and the flipped orientation.
  const bool corner = best.found[kCornerSlot] >= 0, flipped_corner = best.found[kFlippedCornerSlot] >= 0;
  std::int16_t ids[7] = {-1, -1, -1, -1, -1, -1, -1};  // blob per Doty id 1..6
  ids[4] = static_cast<std::int16_t>(best_centre);
  if (flipped_corner && !corner) {
    best.ux = -best.ux;
    best.uy = -best.uy;
    ids[1] = best.found[kFlippedCornerSlot];
    ids[2] = best.found[3];  // what was -y is +y now
    ids[6] = best.found[0];
    ids[3] = best.found[2];
    ids[5] = best.found[1];
    result.orientation_from_marker = true;
  } else {
    ids[2] = best.found[0];
    ids[3] = best.found[1];
    ids[5] = best.found[2];
    ids[6] = best.found[3];
    if (corner && !flipped_corner) {
      ids[1] = best.found[kCornerSlot];
      result.orientation_from_marker = true;
    } else if (corner && flipped_corner) {
      verdicts[static_cast<std::size_t>(best.found[kCornerSlot])] = FidVerdict::kRejectedAmbiguous;
      verdicts[static_cast<std::size_t>(best.found[kFlippedCornerSlot])] = FidVerdict::kRejectedAmbiguous;
    }
  }

  // Step 4: the identified points, and the axes from the longest vectors along them.
  std::int32_t px[7] = {}, py[7] = {};  // q8 px
  for (std::uint8_t id = 1; id <= 6; ++id) {
    if (ids[id] < 0) continue;
    const auto index = static_cast<std::size_t>(ids[id]);
    const Blob& b = blobs[index];
    verdicts[index] = id == 4 ? FidVerdict::kCentre : (id == 1 ? FidVerdict::kCorner : FidVerdict::kPerimeter);
    result.fiducials[result.count++] = IdentifiedFiducial{id, static_cast<std::uint16_t>(index), b.x_px, b.y_px};
    px[id] = b.x_px.raw() >> 8;
    py[id] = b.y_px.raw() >> 8;
  }
  std::int32_t yx = best.ux, yy = best.uy;
  const int top = ids[2] >= 0 ? 2 : 4, bottom = ids[6] >= 0 ? 6 : 4;
  if (top != bottom) normalize(std::int64_t{px[top]} - px[bottom], std::int64_t{py[top]} - py[bottom], yx, yy);
  std::int32_t xx = -yy, xy = yx;
  const int right = ids[5] >= 0 ? 5 : 4, left = ids[3] >= 0 ? 3 : 4;
  if (right != left) normalize(std::int64_t{px[right]} - px[left], std::int64_t{py[right]} - py[left], xx, xy);
  set_unit(xx, xy, result.x_axis_x, result.x_axis_y);
  set_unit(yx, yy, result.y_axis_x, result.y_axis_y);
  result.fiducial_side_px = q16_16::from_raw(static_cast<std::int32_t>(best.side_q8 << 8));
  result.centre_blob = static_cast<std::uint16_t>(best_centre);

  // Why the other blobs are not fiducials of this square.
  for (std::size_t i = 0; i < blobs.size(); ++i) {
    if (verdicts[i] != FidVerdict::kUnused) continue;
    const std::int64_t s2 = best.side_q8 * best.side_q8, area_q16 = std::int64_t{blobs[i].area_px} << 16;
    if (area_q16 * 256 < model.area_ratio_min.raw() * s2 || area_q16 * 256 > model.area_ratio_max.raw() * s2) {
      verdicts[i] = FidVerdict::kRejectedArea;
    } else if (!ratio_at_most(shape_of(blobs[i]), model.perimeter_ratio_max)) {
      verdicts[i] = FidVerdict::kRejectedShape;
    } else {
      verdicts[i] = FidVerdict::kRejectedPosition;
    }
  }

  // Step 5: three non-collinear points (twice the triangle area > 0.2 (7s)^2).
  if (result.count < 3) return FidStatus::kTooFewFiducials;
  const std::int64_t distance_q8 = model.perimeter_distance_sides * best.side_q8;
  const std::int64_t needed = distance_q8 * distance_q8 / 5;
  std::int64_t widest = 0;
  for (int a = 1; a <= 6; ++a)
    for (int b = a + 1; b <= 6; ++b)
      for (int c = b + 1; c <= 6; ++c) {
        if (ids[a] < 0 || ids[b] < 0 || ids[c] < 0) continue;
        // 64-bit products: q8 differences of fiducials 200 px apart multiply beyond 2^31.
        const std::int64_t bx = px[b] - px[a], by = py[b] - py[a], cx = px[c] - px[a], cy = py[c] - py[a];
        const std::int64_t cross = abs64(bx * cy - by * cx);
        widest = cross > widest ? cross : widest;
      }
  return widest > needed ? FidStatus::kOk : FidStatus::kCollinear;
}

}  // namespace kincal::core

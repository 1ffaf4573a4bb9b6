#include "firmware/core/blob_labeler.hpp"

#include <array>
#include <bit>
#include <cstring>

namespace kincal::core {

namespace {

constexpr std::uint16_t kUnassigned = 0xFFFEu;
constexpr std::uint16_t kClosedRow = 0xFFFFu;

// ---- Foreground tests ---------------------------------------------------------------------
// A pixel p is foreground when key = p ^ invert >= k, with invert 0x00 (bright: p > t, so
// k = t + 1) or 0xFF (dark: p < t, so 255 - p >= 256 - t). k == 256 means no foreground.
struct ForegroundTest {
  std::uint32_t invert8;      // 0 or 0xFF
  std::uint32_t k;            // 1..256
  std::uint32_t add32;        // 256 - k in every byte
  std::uint32_t threshold32;  // t in every byte

  static ForegroundTest make(Polarity polarity, std::uint8_t threshold) {
    ForegroundTest f{};
    const bool bright = polarity == Polarity::kBright;
    f.invert8 = bright ? 0u : 0xFFu;
    f.k = bright ? threshold + 1u : 256u - threshold;
    f.add32 = (256u - f.k) * 0x01010101u;  // 0..255 in every byte
    f.threshold32 = threshold * 0x01010101u;
    return f;
  }
  bool is_foreground(std::uint8_t p) const { return (p ^ invert8) >= k; }
};

// Four pixels at once: a word whose byte i is non-zero exactly where pixel i is foreground.
// On the Cortex-M4 one UQSUB8 (per-byte saturating subtraction: p - t > 0 for bright, t - p > 0
// for dark); elsewhere the carry out of key + (256 - k), computed per byte without carries
// crossing lanes (carry = majority of the two top bits and the carry into bit 7). The two
// differ only in which non-zero value a byte holds, so the labels are the same bits.
template <bool kBright>
std::uint32_t foreground_bytes(const ForegroundTest& f, std::uint32_t w) {
#if defined(__ARM_FEATURE_SIMD32)
  std::uint32_t r;
  if constexpr (kBright) {
    __asm("uqsub8 %0, %1, %2" : "=r"(r) : "r"(w), "r"(f.threshold32));
  } else {
    __asm("uqsub8 %0, %1, %2" : "=r"(r) : "r"(f.threshold32), "r"(w));
  }
  return r;
#else
  const std::uint32_t a = kBright ? w : ~w;
  const std::uint32_t s = (a & 0x7F7F7F7Fu) + (f.add32 & 0x7F7F7F7Fu);
  return ((a & f.add32) | (s & (a | f.add32))) & 0x80808080u;
#endif
}

std::uint32_t load32(const std::uint8_t* p) {
  std::uint32_t w;
  std::memcpy(&w, p, sizeof w);  // one (unaligned) load on the M4 and natively
  return w;
}

// Index of the first foreground pixel at or after x, or width when there is none.
template <bool kBright>
std::uint32_t next_foreground(const ForegroundTest& f, const std::uint8_t* row, std::uint32_t x, std::uint32_t width) {
  while (x + 8 <= width &&
         (foreground_bytes<kBright>(f, load32(row + x)) | foreground_bytes<kBright>(f, load32(row + x + 4))) == 0) {
    x += 8;
  }
  while (x + 4 <= width) {
    const std::uint32_t m = foreground_bytes<kBright>(f, load32(row + x));
    // Little-endian loads: byte i is pixel x + i, so the lowest set bit marks the first one.
    if (m != 0) return x + static_cast<std::uint32_t>(std::countr_zero(m) >> 3);
    x += 4;
  }
  while (x < width && !f.is_foreground(row[x])) ++x;
  return x;
}

// Sum of k^2 for k = 0..n.
std::uint64_t sum_squares(std::uint64_t n) { return n * (n + 1) * (2 * n + 1) / 6; }

// n / d in q16 (as int64), rounded to nearest with ties away from zero. Requires d > 0,
// d < 2^46, |n| < 2^62: the remainder, not n, is scaled.
std::int64_t ratio_q16(std::int64_t n, std::int64_t d) {
  const std::int64_t q = n / d;
  const std::int64_t r = n - q * d;
  return q * 65536 + fixed_detail::round_div(r * 65536, d);
}

q16_16 to_q16(std::int64_t raw) { return q16_16::from_raw(fixed_detail::saturate<std::int32_t>(raw)); }
q24_8 q16_to_q24_8(std::int64_t raw_q16) {
  return q24_8::from_raw(fixed_detail::saturate<std::int32_t>(fixed_detail::round_shift_right(raw_q16, 8)));
}

// Moments of a component about an integer origin (qx, qy), exact in int64.
struct Moments {
  std::int64_t m0, mx, my, mxx, mxy, myy;
};

Moments shifted(std::int64_t m0, std::int64_t mx, std::int64_t my, std::int64_t mxx, std::int64_t mxy, std::int64_t myy,
                std::int64_t qx, std::int64_t qy) {
  return {m0,
          mx - qx * m0,
          my - qy * m0,
          mxx - 2 * qx * mx + qx * qx * m0,
          mxy - qx * my - qy * mx + qx * qy * m0,
          myy - 2 * qy * my + qy * qy * m0};
}

// exp(-t) at t = i/32, i = 0..256, scaled by 2^15: the Gaussian window of the refinement.
// Evaluated by the compiler (constexpr double, IEEE), so both targets hold the same table.
constexpr double exp_neg(double t) {
  double term = 1.0, sum = 1.0;
  for (int i = 1; i < 90; ++i) {
    term *= t / i;
    sum += term;
  }
  return 1.0 / sum;
}
constexpr std::array<std::uint16_t, 258> make_gauss_table() {
  std::array<std::uint16_t, 258> table{};
  for (int i = 0; i <= 256; ++i)
    table[static_cast<std::size_t>(i)] = static_cast<std::uint16_t>(exp_neg(i / 32.0) * 32768.0 + 0.5);
  table[257] = 0;
  return table;
}
constexpr std::array<std::uint16_t, 258> kGaussQ15 = make_gauss_table();
static_assert(kGaussQ15[0] == 32768 && kGaussQ15[32] == 12055);  // exp(-1) * 2^15 = 12054.6

// exp(-t) in q15 (1.0 = 32768) for t in q16, linear between table entries; 0 beyond t = 8.
std::int32_t gauss_q15(std::int64_t t_q16) {
  if (t_q16 >= (std::int64_t{8} << 16)) return 0;
  const auto i = static_cast<std::size_t>(t_q16 >> 11);
  const auto frac = static_cast<std::int32_t>(t_q16 & 0x7FF);
  const std::int32_t a = kGaussQ15[i], b = kGaussQ15[i + 1];
  return a - (((a - b) * frac + 1024) >> 11);
}

// Arithmetic shift so that |v| < 2^44 for the largest of a set of sums (ratio_q16's domain).
int headroom_shift(std::int64_t largest) {
  int shift = 0;
  while (shift < 40 && (largest >> shift) >= (std::int64_t{1} << 44)) ++shift;
  return shift;
}

}  // namespace

LabelStatus BlobLabeler::begin_frame(const LabelerConfig& config, std::span<Blob> out) noexcept {
  in_frame_ = false;
  const std::size_t slots = m_.components.size();
  const std::size_t runs = std::size_t{m_.max_width_px} / 2 + 1;
  if (m_.max_width_px == 0 || m_.max_width_px > kLabelerMaxRows || m_.max_width_px % 4 != 0 || slots == 0 ||
      slots >= kUntrackedSlot - 1 || m_.runs_a.size() < runs || m_.runs_b.size() < runs ||
      m_.free_slots.size() != slots || m_.merged_slots.size() != slots || m_.ring_rows == 0 ||
      m_.ring.size() < std::size_t{m_.ring_rows} * m_.max_width_px || m_.pending.empty() ||
      m_.window_weights.size() != kWindowWeights || m_.pending.size() > 0xFFFF) {
    return LabelStatus::kBadWorkspace;
  }
  if (config.background_guard_px == 0) return LabelStatus::kBadConfig;
  if (config.refine && (config.refine_half_window_px < 2 || config.refine_half_window_px > kMaxRefineHalfWindow_px ||
                        2 * config.refine_half_window_px + 1 > m_.ring_rows ||
                        config.refine_max_extent_px > 2 * config.refine_half_window_px + 1)) {
    return LabelStatus::kBadConfig;
  }
  config_ = config;
  out_ = out;
  summary_ = FrameSummary{};
  prev_ = m_.runs_a;
  cur_ = m_.runs_b;
  prev_count_ = 0;
  merged_count_ = 0;
  pending_count_ = 0;
  next_ring_slot_ = 0;
  free_count_ = static_cast<std::uint16_t>(slots);
  for (std::size_t i = 0; i < slots; ++i) m_.free_slots[i] = static_cast<std::uint16_t>(slots - 1 - i);
  in_frame_ = true;
  return LabelStatus::kOk;
}

LabelStatus BlobLabeler::check_row(std::uint16_t width_px) noexcept {
  LabelStatus status = LabelStatus::kOk;
  if (!in_frame_) return LabelStatus::kNotInFrame;
  if (width_px == 0) {
    status = LabelStatus::kEmptyRow;
  } else if (width_px > m_.max_width_px) {
    status = LabelStatus::kRowTooWide;
  } else if (summary_.rows > 0 && width_px != summary_.width_px) {
    status = LabelStatus::kRowWidthChanged;
  } else if (summary_.rows >= kLabelerMaxRows) {
    status = LabelStatus::kTooManyRows;
  }
  if (status != LabelStatus::kOk) in_frame_ = false;  // the frame is failed: refuse further rows
  return status;
}

LabelStatus BlobLabeler::push_row(std::span<const std::uint8_t> row) noexcept {
  const auto width = static_cast<std::uint16_t>(row.size() > 0xFFFFu ? 0xFFFFu : row.size());
  if (const LabelStatus s = check_row(width); s != LabelStatus::kOk) return s;
  if (config_.refine) {
    // The refinement reads the last rows again: keep this one in the ring.
    std::span<std::uint8_t> slot = row_buffer();
    std::memcpy(slot.data(), row.data(), width);
    label_row(slot.data(), width);
  } else {
    label_row(row.data(), width);
  }
  finish_row();
  return LabelStatus::kOk;
}

std::span<std::uint8_t> BlobLabeler::row_buffer() noexcept {
  return m_.ring.subspan(std::size_t{next_ring_slot_} * m_.max_width_px, m_.max_width_px);
}

LabelStatus BlobLabeler::commit_row(std::uint16_t width_px) noexcept {
  if (const LabelStatus s = check_row(width_px); s != LabelStatus::kOk) return s;
  label_row(row_buffer().data(), width_px);
  finish_row();
  return LabelStatus::kOk;
}

void BlobLabeler::finish_row() noexcept {
  for (std::uint16_t i = closing_begin_; i < closing_end_; ++i) close_component(m_.free_slots[i], false);
  closing_begin_ = closing_end_ = 0;
  if (pending_count_ > 0) run_due_refinements(false);
}

const std::uint8_t* BlobLabeler::ring_row(int y) const noexcept {
  return m_.ring.data() + static_cast<std::size_t>(y % m_.ring_rows) * m_.max_width_px;
}

void BlobLabeler::label_row(const std::uint8_t* row, std::uint16_t width_px) noexcept {
  const ForegroundTest fg = ForegroundTest::make(config_.polarity, config_.threshold);
  const std::uint16_t y = summary_.rows;
  const std::uint32_t width = width_px;
  const std::uint32_t reach = config_.connectivity == Connectivity::kEight ? 1u : 0u;
  const std::uint32_t guard = config_.background_guard_px;
  std::span<OpenComponent> comps = m_.components;
  const std::size_t slot_limit = comps.size();

  auto find = [&](std::uint16_t s) {
    for (std::size_t i = 0; i < slot_limit && comps[s].parent != s; ++i) s = comps[s].parent;
    return s;
  };

  std::uint16_t cur_count = 0;
  std::uint16_t pi = 0;  // first previous-row run that may still touch a run of this row
  if (fg.k <= 255) {
    std::uint32_t x = 0;
    const bool bright = config_.polarity == Polarity::kBright;
    while ((x = bright ? next_foreground<true>(fg, row, x, width) : next_foreground<false>(fg, row, x, width)) <
           width) {
      const std::uint32_t begin = x;
      std::uint32_t sum_i = 0;
      std::uint64_t sum_ix = 0, sum_ixx = 0;
      do {
        const std::uint32_t p = row[x];
        const std::uint32_t px = p * x;
        sum_i += p;
        sum_ix += px;
        sum_ixx += std::uint64_t{px} * x;
        ++x;
      } while (x < width && fg.is_foreground(row[x]));
      const std::uint32_t end = x - 1;  // inclusive

      // Join the previous row's runs that touch [begin - reach, end + reach].
      while (pi < prev_count_ && prev_[pi].x_end + reach < begin) ++pi;
      std::uint16_t slot = kUnassigned;
      bool touches_untracked = false;
      for (std::uint16_t j = pi; j < prev_count_ && prev_[j].x_begin <= end + reach; ++j) {
        if (prev_[j].slot == kUntrackedSlot) {
          touches_untracked = true;
          continue;
        }
        const std::uint16_t root = find(prev_[j].slot);
        if (slot == kUnassigned) {
          slot = root;
        } else if (root != slot) {
          // Two components meet: the one whose first pixel comes first in raster order survives.
          OpenComponent& a = comps[slot];
          OpenComponent& b = comps[root];
          const bool a_first = a.y_min < b.y_min || (a.y_min == b.y_min && a.first_x <= b.first_x);
          const std::uint16_t keep = a_first ? slot : root;
          const std::uint16_t gone = a_first ? root : slot;
          OpenComponent& k = comps[keep];
          const OpenComponent& g = comps[gone];
          k.n += g.n;
          k.bx += g.bx;
          k.by += g.by;
          k.bxx += g.bxx;
          k.bxy += g.bxy;
          k.byy += g.byy;
          k.t0 += g.t0;
          k.tx += g.tx;
          k.ty += g.ty;
          k.txx += g.txx;
          k.txy += g.txy;
          k.tyy += g.tyy;
          k.background_sum_dn += g.background_sum_dn;
          k.background_count += g.background_count;
          k.x_min = g.x_min < k.x_min ? g.x_min : k.x_min;
          k.x_max = g.x_max > k.x_max ? g.x_max : k.x_max;
          k.flags = static_cast<std::uint8_t>(k.flags | g.flags);
          comps[gone].parent = keep;
          m_.merged_slots[merged_count_++] = gone;
          slot = keep;
        }
      }
      if (slot == kUnassigned) {
        if (touches_untracked || free_count_ == 0) {
          slot = kUntrackedSlot;  // part of a component we could not track: never reported
          ++summary_.runs_untracked;
        } else {
          slot = m_.free_slots[--free_count_];
          OpenComponent& c = comps[slot];
          c = OpenComponent{};
          c.parent = slot;
          c.x_min = static_cast<std::uint16_t>(begin);
          c.x_max = static_cast<std::uint16_t>(end);
          c.y_min = y;
          c.first_x = static_cast<std::uint16_t>(begin);
        }
      }
      if (slot != kUntrackedSlot) {
        OpenComponent& c = comps[slot];
        if (touches_untracked) c.flags = static_cast<std::uint8_t>(c.flags | kIncomplete);
        const std::uint32_t n = end - begin + 1;
        const std::uint64_t sx = std::uint64_t{begin + end} * n / 2;
        const std::uint64_t sxx = sum_squares(end) - (begin > 0 ? sum_squares(begin - 1) : 0);
        c.n += n;
        c.bx += sx;
        c.by += std::uint64_t{y} * n;
        c.bxx += sxx;
        c.bxy += sx * y;
        c.byy += std::uint64_t{y} * y * n;
        c.t0 += sum_i;
        c.tx += sum_ix;
        c.ty += std::uint64_t{sum_i} * y;
        c.txx += sum_ixx;
        c.txy += sum_ix * y;
        c.tyy += std::uint64_t{sum_i} * y * y;
        if (begin < c.x_min) c.x_min = static_cast<std::uint16_t>(begin);
        if (end > c.x_max) c.x_max = static_cast<std::uint16_t>(end);
        c.y_max = y;
        c.last_row = y;
        // Local background: the pixels `guard` away from the run's ends, when they are background.
        if (begin >= guard && !fg.is_foreground(row[begin - guard])) {
          c.background_sum_dn += row[begin - guard];
          ++c.background_count;
        }
        if (end + guard < width && !fg.is_foreground(row[end + guard])) {
          c.background_sum_dn += row[end + guard];
          ++c.background_count;
        }
      }
      cur_[cur_count++] = LabelRun{static_cast<std::uint16_t>(begin), static_cast<std::uint16_t>(end), slot};
    }
  }

  // Merges may have redirected runs labelled earlier in this row: point them at their roots.
  for (std::uint16_t i = 0; i < cur_count; ++i) {
    if (cur_[i].slot != kUntrackedSlot) cur_[i].slot = find(cur_[i].slot);
  }
  // A component of the previous row that no run of this row continued is complete. Its slot
  // goes to the free list at once (nothing allocates before the next row); finish_row finalizes
  // it from there, outside this function's frame.
  closing_begin_ = free_count_;
  for (std::uint16_t i = 0; i < prev_count_; ++i) {
    if (prev_[i].slot == kUntrackedSlot) continue;
    const std::uint16_t root = find(prev_[i].slot);
    if (comps[root].last_row != y) {
      comps[root].last_row = y;  // closed: the other runs of this component skip it
      m_.free_slots[free_count_++] = root;
    }
  }
  closing_end_ = free_count_;
  for (std::uint16_t i = 0; i < merged_count_; ++i) m_.free_slots[free_count_++] = m_.merged_slots[i];
  merged_count_ = 0;

  const std::span<LabelRun> done = prev_;
  prev_ = cur_;
  cur_ = done;
  prev_count_ = cur_count;
  summary_.width_px = width_px;
  summary_.rows = static_cast<std::uint16_t>(y + 1);
  next_ring_slot_ = static_cast<std::uint16_t>((next_ring_slot_ + 1) % m_.ring_rows);
}

void BlobLabeler::close_component(std::uint16_t slot, bool last_row) noexcept {
  const OpenComponent& c = m_.components[slot];
  if (c.n < config_.min_area_px) {
    ++summary_.blobs_dropped_small;
    return;
  }
  if (summary_.blobs >= out_.size()) {
    ++summary_.blobs_dropped_output_full;
    return;
  }
  Blob& blob = out_[summary_.blobs];
  blob = Blob{};
  blob.area_px = c.n;
  blob.x_min_px = c.x_min;
  blob.x_max_px = c.x_max;
  blob.y_min_px = c.y_min;
  blob.y_max_px = c.y_max;
  blob.first_x_px = c.first_x;
  blob.flags = c.flags;
  if (c.x_min == 0 || c.x_max + 1 == summary_.width_px || c.y_min == 0 || last_row) {
    blob.flags = static_cast<std::uint8_t>(blob.flags | kTouchesBorder);
  }

  // Moments about the integer part of the binary centroid keep every ratio below small.
  const auto n = static_cast<std::int64_t>(c.n);
  const auto qx = static_cast<std::int64_t>(c.bx / c.n);
  const auto qy = static_cast<std::int64_t>(c.by / c.n);
  const Moments b =
      shifted(n, static_cast<std::int64_t>(c.bx), static_cast<std::int64_t>(c.by), static_cast<std::int64_t>(c.bxx),
              static_cast<std::int64_t>(c.bxy), static_cast<std::int64_t>(c.byy), qx, qy);
  Moments w = shifted(static_cast<std::int64_t>(c.t0), static_cast<std::int64_t>(c.tx), static_cast<std::int64_t>(c.ty),
                      static_cast<std::int64_t>(c.txx), static_cast<std::int64_t>(c.txy),
                      static_cast<std::int64_t>(c.tyy), qx, qy);
  blob.binary_x_px = to_q16(qx * 65536 + ratio_q16(b.mx, n));
  blob.binary_y_px = to_q16(qy * 65536 + ratio_q16(b.my, n));

  // Background in 1/16 DN; weights w = sign * (16 I - b16), so the moments of w are exact.
  std::int64_t b16 = 16 * std::int64_t{config_.threshold};
  if (c.background_count > 0) {
    b16 = fixed_detail::round_div(16 * std::int64_t{c.background_sum_dn}, c.background_count);
  } else {
    blob.flags = static_cast<std::uint8_t>(blob.flags | kBackgroundDefault);
  }
  blob.background_dn = uq8_8::from_raw(static_cast<std::uint16_t>(b16 * 16));
  const std::int64_t sign = config_.polarity == Polarity::kBright ? 1 : -1;
  // w holds the intensity moments; turn them into moments of the weights in place.
  w.m0 = sign * (16 * w.m0 - b16 * b.m0);
  w.mx = sign * (16 * w.mx - b16 * b.mx);
  w.my = sign * (16 * w.my - b16 * b.my);
  w.mxx = sign * (16 * w.mxx - b16 * b.mxx);
  w.mxy = sign * (16 * w.mxy - b16 * b.mxy);
  w.myy = sign * (16 * w.myy - b16 * b.myy);
  if (w.m0 <= 0) {
    w = b;
    blob.flags = static_cast<std::uint8_t>(blob.flags | kWeightInvalid);
  } else {
    blob.weight_sum_dn = static_cast<std::uint32_t>(w.m0 / 16 > 0xFFFFFFFF ? 0xFFFFFFFF : w.m0 / 16);
  }
  const std::int64_t dx = ratio_q16(w.mx, w.m0);
  const std::int64_t dy = ratio_q16(w.my, w.m0);
  blob.weighted_x_px = to_q16(qx * 65536 + dx);
  blob.weighted_y_px = to_q16(qy * 65536 + dy);
  blob.mu20_px2 = q16_to_q24_8(ratio_q16(w.mxx, w.m0) - fixed_detail::round_shift_right(dx * dx, 16));
  blob.mu11_px2 = q16_to_q24_8(ratio_q16(w.mxy, w.m0) - fixed_detail::round_shift_right(dx * dy, 16));
  blob.mu02_px2 = q16_to_q24_8(ratio_q16(w.myy, w.m0) - fixed_detail::round_shift_right(dy * dy, 16));
  blob.x_px = blob.weighted_x_px;
  blob.y_px = blob.weighted_y_px;
  const std::uint32_t index = summary_.blobs++;

  // Spot-like blobs get the Gaussian-window refinement once the window's last row is in.
  const int extent = (c.x_max - c.x_min > c.y_max - c.y_min ? c.x_max - c.x_min : c.y_max - c.y_min) + 1;
  if (!config_.refine || extent > config_.refine_max_extent_px ||
      (blob.flags & (kTouchesBorder | kIncomplete | kWeightInvalid)) != 0) {
    return;
  }
  const int h = config_.refine_half_window_px;
  const auto cx = static_cast<int>((blob.weighted_x_px.raw() + 32768) >> 16);
  const auto cy = static_cast<int>((blob.weighted_y_px.raw() + 32768) >> 16);
  if (cx - h < 0 || cx + h >= summary_.width_px || cy - h < 0 || pending_count_ >= m_.pending.size()) {
    ++summary_.refinements_skipped;
    return;
  }
  // First guess of the Gaussian's variance: the thresholded moments (too small; refined).
  std::int64_t s2_q8 = (std::int64_t{blob.mu20_px2.raw()} + blob.mu02_px2.raw()) / 2;
  const std::int64_t s2_max_q8 = std::int64_t{h} * h * 256 / 9;
  s2_q8 = s2_q8 < 128 ? 128 : (s2_q8 > s2_max_q8 ? s2_max_q8 : s2_q8);
  m_.pending[pending_count_++] = PendingRefinement{index, static_cast<std::int16_t>(cx), static_cast<std::int16_t>(cy),
                                                   static_cast<std::uint16_t>(s2_q8)};
}

void BlobLabeler::run_due_refinements(bool frame_end) noexcept {
  const int newest = summary_.rows - 1;
  const int h = config_.refine_half_window_px;
  std::uint16_t i = 0;
  while (i < pending_count_) {
    const PendingRefinement p = m_.pending[i];
    const bool due = p.centre_y + h <= newest;
    if (!due && !frame_end) {
      ++i;
      continue;
    }
    Blob& blob = out_[p.blob_index];
    // The window's first row must still be in the ring (it is, unless the blob was tall).
    const bool rows_present = due && p.centre_y - h > newest - m_.ring_rows;
    if (rows_present && refine(p, blob)) {
      blob.flags = static_cast<std::uint8_t>(blob.flags | kRefined);
      ++summary_.refinements;
    } else {
      ++summary_.refinements_skipped;
    }
    m_.pending[i] = m_.pending[--pending_count_];
  }
}

bool BlobLabeler::refine(const PendingRefinement& p, Blob& blob) noexcept {
  const int h = config_.refine_half_window_px;
  const int size = 2 * h + 1;
  const int x0 = p.centre_x - h, y0 = p.centre_y - h;
  const std::int32_t sign = config_.polarity == Polarity::kBright ? 1 : -1;

  // Background: the mean of the window's border (8h pixels), in 1/16 DN.
  std::int32_t border = 0;
  for (int j = 0; j < size; ++j) {
    const std::uint8_t* row = ring_row(y0 + j) + x0;
    if (j == 0 || j == size - 1) {
      for (int i = 0; i < size; ++i) border += row[i];
    } else {
      border += row[0] + row[size - 1];
    }
  }
  const auto b16 = static_cast<std::int32_t>(fixed_detail::round_div(16 * border, 8 * h));

  const std::int32_t x_start = blob.weighted_x_px.raw(), y_start = blob.weighted_y_px.raw();
  std::int64_t xhat = x_start, yhat = y_start;       // q16, absolute
  std::int64_t s2 = std::int64_t{p.sigma2_q8} << 8;  // Gaussian window variance, q16 px^2
  const std::int64_t s2_min = 1 << 14, s2_max = std::int64_t{h} * h * 65536 / 9;
  // q15 window weights (1.0 = 32768) per column and per row, in the workspace.
  std::uint16_t* const gx = m_.window_weights.data();
  std::uint16_t* const gy = gx + kWindowWeights / 2;

  for (int iteration = 0; iteration < 16; ++iteration) {
    const std::int64_t inv2s2 = (std::int64_t{1} << 31) / s2;  // 1 / (2 s^2) in q16
    for (int i = 0; i < size; ++i) {
      const std::int64_t ddx = (std::int64_t{x0 + i} << 16) - xhat;
      const std::int64_t ddy = (std::int64_t{y0 + i} << 16) - yhat;
      gx[i] = static_cast<std::uint16_t>(gauss_q15(((ddx * ddx) >> 16) * inv2s2 >> 16));
      gy[i] = static_cast<std::uint16_t>(gauss_q15(((ddy * ddy) >> 16) * inv2s2 >> 16));
    }
    // Weighted sums with offsets from the window centre (integers), then about the estimate.
    std::int64_t s0 = 0, sx = 0, sy = 0, sxx = 0, syy = 0;
    for (int j = 0; j < size; ++j) {
      const std::uint8_t* row = ring_row(y0 + j) + x0;
      std::int64_t a0 = 0, a1 = 0, a2 = 0;
      for (int i = 0; i < size; ++i) {
        const std::int64_t v = std::int64_t{gx[i]} * (sign * (16 * row[i] - b16));
        a0 += v;
        a1 += v * (i - h);
        a2 += v * (i - h) * (i - h);
      }
      const std::int64_t oy = j - h;
      const std::int64_t g = gy[j];
      s0 += g * a0;
      sx += g * a1;
      sxx += g * a2;
      sy += g * oy * a0;
      syy += g * oy * oy * a0;
    }
    if (s0 <= 0) return false;
    const int shift = headroom_shift(s0);
    s0 >>= shift;
    sx >>= shift;
    sy >>= shift;
    sxx >>= shift;
    syy >>= shift;
    if (s0 <= 0) return false;
    const std::int64_t mx = ratio_q16(sx, s0), my = ratio_q16(sy, s0);  // weighted mean, from the centre
    // Weights below the background can nearly cancel s0: a mean outside the window, or second
    // moments beyond its extent, mean this window gives no centroid (and would overflow below).
    const std::int64_t extent_q16 = std::int64_t{size} << 16;
    if (mx > extent_q16 || mx < -extent_q16 || my > extent_q16 || my < -extent_q16) return false;
    const std::int64_t mxx = ratio_q16(sxx, s0), myy = ratio_q16(syy, s0);
    if (mxx > size * extent_q16 || mxx < -size * extent_q16 || myy > size * extent_q16 || myy < -size * extent_q16)
      return false;
    const std::int64_t cx = std::int64_t{p.centre_x} << 16, cy = std::int64_t{p.centre_y} << 16;
    // Weighted variance about the weighted mean, averaged over both axes: for a Gaussian spot of
    // variance s^2 under a Gaussian window of variance w^2 it is s^2 w^2 / (s^2 + w^2).
    const std::int64_t vx = mxx - fixed_detail::round_shift_right(mx * mx, 16);
    const std::int64_t vy = myy - fixed_detail::round_shift_right(my * my, 16);
    const std::int64_t vp = (vx + vy) / 2;
    std::int64_t spot = s2_max;
    if (vp > 0 && s2 - vp > s2 / 8) spot = fixed_detail::round_div(vp * s2, s2 - vp);
    spot = spot < s2_min ? s2_min : (spot > s2_max ? s2_max : spot);
    // The plain update x + (mean - x) moves a fraction s^2/(s^2 + w^2) of the way to the fixed
    // point; stepping by (s^2 + w^2)/w^2 lands on it for a Gaussian spot. Same fixed point.
    const std::int64_t gain_q8 = fixed_detail::round_div((spot + s2) * 256, s2);
    const std::int64_t step_x = fixed_detail::round_shift_right((cx + mx - xhat) * gain_q8, 8);
    const std::int64_t step_y = fixed_detail::round_shift_right((cy + my - yhat) * gain_q8, 8);
    xhat += step_x;
    yhat += step_y;
    s2 = (s2 + spot) / 2;
    const std::int64_t moved_x = xhat - x_start, moved_y = yhat - y_start;
    if (moved_x > 2 * 65536 || moved_x < -2 * 65536 || moved_y > 2 * 65536 || moved_y < -2 * 65536) return false;
    if (iteration >= 2 && step_x < 8 && step_x > -8 && step_y < 8 && step_y > -8) break;
  }
  blob.x_px = to_q16(xhat);
  blob.y_px = to_q16(yhat);
  return true;
}

LabelStatus BlobLabeler::end_frame(FrameSummary& summary) noexcept {
  if (!in_frame_) return LabelStatus::kNotInFrame;
  for (std::uint16_t i = 0; i < prev_count_; ++i) {
    if (prev_[i].slot == kUntrackedSlot) continue;
    std::uint16_t root = prev_[i].slot;  // resolved at the end of the last row
    if (m_.components[root].last_row != kClosedRow) {
      m_.components[root].last_row = kClosedRow;
      m_.free_slots[free_count_++] = root;
      close_component(root, true);
    }
  }
  prev_count_ = 0;
  run_due_refinements(true);
  summary = summary_;
  in_frame_ = false;
  return LabelStatus::kOk;
}

}  // namespace kincal::core

// Synthetic 8-bit images for the labeler's tests, the same bits natively and on the M4: integer
// arithmetic, or double arithmetic restricted to + - * / (correctly rounded on both targets;
// no libm, whose last bits differ). Also a reference labeler: plain flood fill over the whole
// image, the independent check of the streaming one.
#pragma once

#include <cstdint>

#include "tests/firmware/core/splitmix64.hpp"

namespace kincal::test {

// exp(-t) for t >= 0 from + - * / only: exp(-t) = (exp(-t/64))^64 with a Taylor series.
inline double exp_neg(double t) {
  if (t > 60.0) return 0.0;
  const double u = t / 64.0;
  double term = 1.0, sum = 1.0;
  for (int i = 1; i < 14; ++i) {
    term *= u / i;
    sum += term;
  }
  double r = 1.0 / sum;
  for (int i = 0; i < 6; ++i) r *= r;
  return r;
}

template <int W, int H>
struct Image {
  static constexpr int kWidth = W, kHeight = H;
  std::uint8_t px[static_cast<unsigned>(H)][static_cast<unsigned>(W)];
  void fill(std::uint8_t v) {
    for (auto& row : px)
      for (auto& p : row) p = v;
  }
  void rect(int x0, int y0, int x1, int y1, std::uint8_t v) {  // inclusive corners, clipped
    for (int y = y0 < 0 ? 0 : y0; y <= y1 && y < H; ++y)
      for (int x = x0 < 0 ? 0 : x0; x <= x1 && x < W; ++x) px[y][x] = v;
  }
  // Adds amplitude * exp(-r^2 / (2 sigma^2)) (sampled at pixel centres), rounded, clamped.
  void add_spot(double cx, double cy, double sigma, double amplitude) {
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const double dx = x - cx, dy = y - cy;
        const double v = px[y][x] + amplitude * exp_neg((dx * dx + dy * dy) / (2 * sigma * sigma));
        px[y][x] = static_cast<std::uint8_t>(v >= 255.0 ? 255 : (v <= 0.0 ? 0 : static_cast<int>(v + 0.5)));
      }
  }
  void add_noise(Splitmix64& rng, int amplitude) {  // uniform in [-amplitude, amplitude]
    for (auto& row : px)
      for (auto& p : row) {
        const int v = p + rng.below(2 * amplitude + 1) - amplitude;
        p = static_cast<std::uint8_t>(v < 0 ? 0 : (v > 255 ? 255 : v));
      }
  }
};

// Flood-fill reference: labels[y][x] = component index (raster order of first pixel) or -1.
struct ReferenceComponent {
  std::int64_t n = 0, sx = 0, sy = 0;
  int x_min = 1 << 30, x_max = -1, y_min = 1 << 30, y_max = -1, first_x = -1;
};

template <int W, int H, int kMaxComponents>
struct ReferenceLabels {
  int labels[static_cast<unsigned>(H)][static_cast<unsigned>(W)];
  int stack[static_cast<unsigned>(W * H)];
  ReferenceComponent comps[static_cast<unsigned>(kMaxComponents)];
  int count = 0;
  bool overflow = false;

  template <class IsForeground>
  void run(const Image<W, H>& img, IsForeground is_fg, bool eight) {
    count = 0;
    overflow = false;
    for (auto& row : labels)
      for (auto& l : row) l = -1;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        if (labels[y][x] >= 0 || !is_fg(img.px[y][x])) continue;
        if (count == kMaxComponents) {
          overflow = true;
          return;
        }
        ReferenceComponent& c = comps[count];
        c = ReferenceComponent{};
        c.first_x = x;
        int top = 0;
        stack[top++] = y * W + x;
        labels[y][x] = count;
        while (top > 0) {
          const int at = stack[--top];
          const int py = at / W, px = at % W;
          c.n += 1;
          c.sx += px;
          c.sy += py;
          c.x_min = px < c.x_min ? px : c.x_min;
          c.x_max = px > c.x_max ? px : c.x_max;
          c.y_min = py < c.y_min ? py : c.y_min;
          c.y_max = py > c.y_max ? py : c.y_max;
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              if ((dx == 0 && dy == 0) || (!eight && dx != 0 && dy != 0)) continue;
              const int nx = px + dx, ny = py + dy;
              if (nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
              if (labels[ny][nx] >= 0 || !is_fg(img.px[ny][nx])) continue;
              labels[ny][nx] = count;
              stack[top++] = ny * W + nx;
            }
        }
        ++count;
      }
  }
};

}  // namespace kincal::test

// A rendered calibration square (Doty Fig. 5.1 / 7.3) for the FID tests: fiducials of side s
// pixels, the square's axes given as image unit vectors, 4x4 supersampled coverage, dark ink
// on light vellum. Only + - * / in double (the same pixels natively and on the M4).
#pragma once

#include "tests/firmware/core/blob_test_images.hpp"

namespace kincal::test {

struct SquareView {
  double cx, cy;  // image position of the centre fiducial's centre
  double yx, yy;  // unit image vector of the square's +y axis (x axis = (-yy, yx))
  double side_px;
  bool present[7] = {false, true, true, true, true, true, true};  // by Doty id 1..6
};

// Paper coordinates (units of s, y up) of each fiducial's centre, by Doty id.
constexpr double kFiducialX[7] = {0, -7, 0, -7, 0, 7, 0};
constexpr double kFiducialY[7] = {0, 7, 7, 0, 0, 0, -7};

inline void fiducial_image_point(const SquareView& v, int id, double& x, double& y) {
  const double xx = -v.yy, xy = v.yx;
  x = v.cx + v.side_px * (kFiducialX[id] * xx + kFiducialY[id] * v.yx);
  y = v.cy + v.side_px * (kFiducialX[id] * xy + kFiducialY[id] * v.yy);
}

template <int W, int H>
void render_square(Image<W, H>& img, const SquareView& v, int vellum = 200, int ink = 40) {
  const double xx = -v.yy, xy = v.yx;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      // Supersample only pixels within a pixel of a fiducial (soft doubles are slow on the M4).
      const double cdx = x - v.cx, cdy = y - v.cy;
      const double cpx = (cdx * xx + cdy * xy) / v.side_px, cpy = (cdx * v.yx + cdy * v.yy) / v.side_px;
      const double margin = 0.75 / v.side_px;
      bool near = false;
      for (int id = 1; id <= 6; ++id) {
        const double ox = cpx - kFiducialX[id], oy = cpy - kFiducialY[id], hy = id == 4 ? 1.0 : 0.5;
        near =
            near || (v.present[id] && ox > -0.5 - margin && ox < 0.5 + margin && oy > -hy - margin && oy < hy + margin);
      }
      int covered = 0;
      for (int sy = 0; sy < 4 && near; ++sy)
        for (int sx = 0; sx < 4; ++sx) {
          const double dx = x - 0.375 + 0.25 * sx - v.cx, dy = y - 0.375 + 0.25 * sy - v.cy;
          const double px = (dx * xx + dy * xy) / v.side_px, py = (dx * v.yx + dy * v.yy) / v.side_px;
          for (int id = 1; id <= 6; ++id) {
            if (!v.present[id]) continue;
            const double hx = 0.5, hy = id == 4 ? 1.0 : 0.5;
            const double ox = px - kFiducialX[id], oy = py - kFiducialY[id];
            if (ox >= -hx && ox < hx && oy >= -hy && oy < hy) ++covered;
          }
        }
      img.px[y][x] = static_cast<std::uint8_t>(vellum - (vellum - ink) * covered / 16);
    }
}

}  // namespace kincal::test

// A 640x480 calibration-square frame for the M4 benchmarks, rendered a row at a time (so no
// frame buffer is needed): light vellum (200 DN, +-4 DN texture) with Doty's six dark fiducials
// at 120 px per inch (30x30 px, the centre one 30x60, 210 px apart, the corner marker top left),
// edges blurred over one pixel. The centre fiducial's centre is at (cx - 0.5, cy - 0.5) px. With
// pitch_px > 0, the strip's neighbouring squares too, centred pitch_px to the left and right
// (Doty's 4-inch squares: 480 px).
#pragma once

#include <cstdint>

namespace kincal::bench {

inline constexpr int kVgaWidth = 640, kVgaHeight = 480;
inline constexpr int kVgaFiducialSidePx = 30, kVgaPerimeterDistancePx = 210, kVgaSquarePitchPx = 480;

// Row y of the frame with the square centred at (cx, cy), into row[0..kVgaWidth).
inline void render_vga_square_row(int y, int cx, int cy, std::uint8_t* row, int pitch_px = 0) {
  struct Square {
    int x0, y0, x1, y1;  // inclusive
  };
  const int s = kVgaFiducialSidePx, d = kVgaPerimeterDistancePx;
  const Square fiducials[6] = {
      {cx - d - s / 2, cy - d - s / 2, cx - d + s / 2 - 1, cy - d + s / 2 - 1},  // corner marker
      {cx - s / 2, cy - d - s / 2, cx + s / 2 - 1, cy - d + s / 2 - 1},          // top
      {cx - d - s / 2, cy - s / 2, cx - d + s / 2 - 1, cy + s / 2 - 1},          // left
      {cx - s / 2, cy - s, cx + s / 2 - 1, cy + s - 1},                          // centre, 30 x 60
      {cx + d - s / 2, cy - s / 2, cx + d + s / 2 - 1, cy + s / 2 - 1},          // right
      {cx - s / 2, cy + d - s / 2, cx + s / 2 - 1, cy + d + s / 2 - 1},          // bottom
  };
  std::uint32_t hash = static_cast<std::uint32_t>(y) * 2654435761u;
  for (int x = 0; x < kVgaWidth; ++x) {
    hash = hash * 1664525u + 1013904223u;
    int v = 200 + static_cast<int>(hash >> 29) - 4;
    for (int square = pitch_px > 0 ? -1 : 0; square <= (pitch_px > 0 ? 1 : 0); ++square) {
      const int sx = x - square * pitch_px;
      for (const Square& f : fiducials) {
        if (sx >= f.x0 && sx <= f.x1 && y >= f.y0 && y <= f.y1)
          v = 40;
        else if (sx >= f.x0 - 1 && sx <= f.x1 + 1 && y >= f.y0 - 1 && y <= f.y1 + 1)
          v = 120;  // blurred rim
      }
    }
    row[x] = static_cast<std::uint8_t>(v);
  }
}

}  // namespace kincal::bench

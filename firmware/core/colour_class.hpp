// Colour classes for the beacon: a lookup table from a quantized colour to a membership score,
// evaluated per pixel in front of the labeler.
//
// Why: Kapucu & Baysec track a crimson-red beacon; under the rig's lighting its pixels occupy
// a small, oddly shaped region of colour space that no single threshold cuts out. A table
// built on the host from sample pixels (host/vision/colour_table_builder) captures that region
// exactly and costs one load per pixel on the platform.
//
// The table: 16 x 16 x 16 cells over the camera's own colour space —
//   kRgb565   cell (R5 >> 1, G6 >> 2, B5 >> 1): RGB at 4 bits per channel;
//   kYuv422   cell (Y >> 4, U >> 4, V >> 4) of the pixel's Y and its pair's U, V —
// each holding a score 0..255 (0: not the class). classify_* writes the scores as an 8-bit
// row; label it with the bright polarity and the table's threshold (foreground: score >
// threshold). The scores weight the centroid, so a table with soft edges (scores falling off
// toward the class boundary) gives sub-pixel centroids on the beacon's anti-aliased rim.
//
// Parameter block (how the table travels: file on the host, CAN transfer, flash), 4108 bytes,
// little-endian:
//   0  'K' 'C' 'C' 'T'   magic
//   4  version (1), colour space (0 RGB565, 1 YUV422), threshold, 0
//   8  4096 scores, cell index (c0 << 8) | (c1 << 4) | c2
//   4104  CRC-32 (zlib) of bytes 0..4103
// parse_colour_table checks all of it, the reserved byte 7 included (a block it takes is the one
// serialize_colour_table writes back); a bad block is refused with the reason.
//
// Cost: classify one table load per pixel (plus the index arithmetic). Memory: the table,
// 4 KiB, caller-owned (flash or RAM). No heap.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "firmware/core/pixel_formats.hpp"

namespace kincal::core {

enum class ColourSpace : std::uint8_t { kRgb565 = 0, kYuv422 = 1 };

enum class [[nodiscard]] ColourTableStatus : std::uint8_t{
    kOk, kWrongSize, kBadMagic, kUnsupportedVersion, kUnknownColourSpace, kBadCrc, kReservedNotZero,
};

inline constexpr std::size_t kColourCells = 4096;
inline constexpr std::size_t kColourTableBlockBytes = 4 + 4 + kColourCells + 4;
inline constexpr std::uint8_t kColourTableVersion = 1;

struct ColourClassTable {
  ColourSpace space = ColourSpace::kRgb565;
  std::uint8_t threshold = 0;  // foreground: score > threshold
  std::array<std::uint8_t, kColourCells> score{};
};

constexpr std::size_t rgb565_cell(std::uint16_t p) noexcept {
  return (std::size_t{p} >> 12) << 8 | ((std::size_t{p} >> 7) & 0xFu) << 4 | ((std::size_t{p} >> 1) & 0xFu);
}
constexpr std::size_t yuv_cell(std::uint8_t y, std::uint8_t u, std::uint8_t v) noexcept {
  return std::size_t{static_cast<std::uint8_t>(y >> 4)} << 8 | std::size_t{static_cast<std::uint8_t>(u >> 4)} << 4 |
         static_cast<std::uint8_t>(v >> 4);
}

// Scores of every pixel: in.size() (RGB565) or in.size() / 2 (YUV422, whole pixel pairs) bytes.
PixelStatus classify_rgb565(std::span<const std::uint16_t> in, const ColourClassTable& table,
                            std::span<std::uint8_t> out) noexcept;
PixelStatus classify_yuv422(std::span<const std::uint8_t> in, const ColourClassTable& table,
                            std::span<std::uint8_t> out) noexcept;

ColourTableStatus parse_colour_table(std::span<const std::uint8_t> block, ColourClassTable& table) noexcept;
void serialize_colour_table(const ColourClassTable& table,
                            std::span<std::uint8_t, kColourTableBlockBytes> block) noexcept;

}  // namespace kincal::core

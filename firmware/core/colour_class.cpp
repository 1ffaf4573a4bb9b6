#include "firmware/core/colour_class.hpp"

#include "shared/crc32.hpp"

namespace kincal::core {

namespace {

constexpr std::uint8_t kMagic[4] = {'K', 'C', 'C', 'T'};
constexpr std::size_t kCrcOffset = kColourTableBlockBytes - 4;

}  // namespace

PixelStatus classify_rgb565(std::span<const std::uint16_t> in, const ColourClassTable& table,
                            std::span<std::uint8_t> out) noexcept {
  if (out.size() < in.size()) return PixelStatus::kOutputTooShort;
  for (std::size_t i = 0; i < in.size(); ++i) out[i] = table.score[rgb565_cell(in[i])];
  return PixelStatus::kOk;
}

PixelStatus classify_yuv422(std::span<const std::uint8_t> in, const ColourClassTable& table,
                            std::span<std::uint8_t> out) noexcept {
  if (in.size() % 4 != 0) return PixelStatus::kOddYuvRow;  // whole pixel pairs: each needs its U and V
  if (out.size() < in.size() / 2) return PixelStatus::kOutputTooShort;
  for (std::size_t i = 0; i + 4 <= in.size(); i += 4) {  // Y0 U Y1 V: both pixels share U and V
    out[i / 2] = table.score[yuv_cell(in[i], in[i + 1], in[i + 3])];
    out[i / 2 + 1] = table.score[yuv_cell(in[i + 2], in[i + 1], in[i + 3])];
  }
  return PixelStatus::kOk;
}

ColourTableStatus parse_colour_table(std::span<const std::uint8_t> block, ColourClassTable& table) noexcept {
  if (block.size() != kColourTableBlockBytes) return ColourTableStatus::kWrongSize;
  for (std::size_t i = 0; i < 4; ++i)
    if (block[i] != kMagic[i]) return ColourTableStatus::kBadMagic;
  const std::uint32_t stored = std::uint32_t{block[kCrcOffset]} | std::uint32_t{block[kCrcOffset + 1]} << 8 |
                               std::uint32_t{block[kCrcOffset + 2]} << 16 | std::uint32_t{block[kCrcOffset + 3]} << 24;
  if (shared::crc32(block.first(kCrcOffset)) != stored) return ColourTableStatus::kBadCrc;
  if (block[4] != kColourTableVersion) return ColourTableStatus::kUnsupportedVersion;
  if (block[5] > static_cast<std::uint8_t>(ColourSpace::kYuv422)) return ColourTableStatus::kUnknownColourSpace;
  if (block[7] != 0) return ColourTableStatus::kReservedNotZero;
  table.space = static_cast<ColourSpace>(block[5]);
  table.threshold = block[6];
  for (std::size_t i = 0; i < kColourCells; ++i) table.score[i] = block[8 + i];
  return ColourTableStatus::kOk;
}

void serialize_colour_table(const ColourClassTable& table,
                            std::span<std::uint8_t, kColourTableBlockBytes> block) noexcept {
  for (std::size_t i = 0; i < 4; ++i) block[i] = kMagic[i];
  block[4] = kColourTableVersion;
  block[5] = static_cast<std::uint8_t>(table.space);
  block[6] = table.threshold;
  block[7] = 0;
  for (std::size_t i = 0; i < kColourCells; ++i) block[8 + i] = table.score[i];
  const std::uint32_t crc = shared::crc32(std::span<const std::uint8_t>(block).first(kCrcOffset));
  for (std::size_t i = 0; i < 4; ++i) block[kCrcOffset + i] = static_cast<std::uint8_t>(crc >> (8 * i));
}

}  // namespace kincal::core

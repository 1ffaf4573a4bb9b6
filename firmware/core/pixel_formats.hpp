// Camera row formats to the labeler's 8-bit intensity rows.
//
// Why: a DCMI camera delivers RGB565 or YUV422 (YUYV) rows; the labeler works on one byte per
// pixel. The converters write straight into BlobLabeler::row_buffer(), so a colour frame costs
// one pass per row and no frame buffer.
//
// RGB565   one std::uint16_t per pixel in host order (R in bits 15..11, G 10..5, B 4..0; a
//          camera sending big-endian bytes must be swapped first). Luma (ITU-R BT.601 weights)
//          Y = (77 R + 150 G + 29 B + 128) >> 8 of the channels widened to 8 bits by bit
//          replication (R8 = R5 << 3 | R5 >> 2): exact integers, white gives 255.
// YUV422   bytes Y0 U Y1 V for each pixel pair (YUYV, the DCMI default); luma is the Y byte.
//          The row has 2 bytes per pixel; an odd byte count is malformed.
//
// Cost: a few instructions per pixel; no memory besides the two rows.
// Failure: an output shorter than the input's pixel count, or a malformed row: PixelStatus
// error, nothing written.
#pragma once

#include <cstdint>
#include <span>

namespace kincal::core {

enum class [[nodiscard]] PixelStatus : std::uint8_t{kOk, kOutputTooShort, kOddYuvRow};

constexpr std::uint8_t rgb565_luma(std::uint16_t p) noexcept {
  const std::uint32_t r5 = p >> 11, g6 = (p >> 5) & 0x3Fu, b5 = p & 0x1Fu;
  const std::uint32_t r = (r5 << 3) | (r5 >> 2), g = (g6 << 2) | (g6 >> 4), b = (b5 << 3) | (b5 >> 2);
  return static_cast<std::uint8_t>((77 * r + 150 * g + 29 * b + 128) >> 8);
}

// Luma of every pixel; writes in.size() bytes.
PixelStatus rgb565_to_luma(std::span<const std::uint16_t> in, std::span<std::uint8_t> out) noexcept;
// Y of every pixel; writes in.size() / 2 bytes.
PixelStatus yuv422_to_luma(std::span<const std::uint8_t> in, std::span<std::uint8_t> out) noexcept;

}  // namespace kincal::core

#include "firmware/core/pixel_formats.hpp"

namespace kincal::core {

PixelStatus rgb565_to_luma(std::span<const std::uint16_t> in, std::span<std::uint8_t> out) noexcept {
  if (out.size() < in.size()) return PixelStatus::kOutputTooShort;
  for (std::size_t i = 0; i < in.size(); ++i) out[i] = rgb565_luma(in[i]);
  return PixelStatus::kOk;
}

PixelStatus yuv422_to_luma(std::span<const std::uint8_t> in, std::span<std::uint8_t> out) noexcept {
  if (in.size() % 2 != 0) return PixelStatus::kOddYuvRow;
  if (out.size() < in.size() / 2) return PixelStatus::kOutputTooShort;
  for (std::size_t i = 0; i < in.size() / 2; ++i) out[i] = in[2 * i];
  return PixelStatus::kOk;
}

}  // namespace kincal::core

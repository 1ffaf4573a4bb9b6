#include "firmware/app/parameter_store.hpp"

namespace kincal::app::slot_format {

namespace {

std::uint32_t get_u32(std::span<const std::uint8_t> in, std::size_t at) {
  std::uint32_t v = 0;
  for (std::size_t i = 0; i < 4; ++i) v |= std::uint32_t{in[at + i]} << (8 * i);
  return v;
}

}  // namespace

bool parse_header(std::span<const std::uint8_t, kHeaderBytes> bytes, std::size_t max_payload, Header& out) {
  if (get_u32(bytes, 0) != kMagic || bytes[9] != 0) return false;
  out.sequence = get_u32(bytes, 4);
  out.block = bytes[8];
  out.version = static_cast<std::uint16_t>(bytes[10] | (bytes[11] << 8));
  out.length = get_u32(bytes, 12);
  out.crc32 = get_u32(bytes, 16);
  return out.length <= max_payload;
}

}  // namespace kincal::app::slot_format

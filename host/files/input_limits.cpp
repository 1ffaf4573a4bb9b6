#include "host/files/input_limits.hpp"

#include "host/files/input_file.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <fstream>
#include <optional>
#include <utility>

namespace kincal::files {

namespace {

using Size = std::pair<std::int64_t, std::int64_t>;  // width, height

std::int64_t big_endian(const unsigned char* p, int bytes) {
  std::int64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = v * 256 + p[i];
  return v;
}

// PNG: the IHDR chunk is first, width and height at bytes 16..23.
std::optional<Size> png_size(std::istream& in) {
  std::array<unsigned char, 24> h{};
  in.seekg(0);
  if (!in.read(reinterpret_cast<char*>(h.data()), h.size())) return std::nullopt;
  if (h[0] != 0x89 || h[1] != 'P' || h[2] != 'N' || h[3] != 'G') return std::nullopt;
  return Size{big_endian(&h[16], 4), big_endian(&h[20], 4)};
}

// JPEG: walk the marker segments to the first start-of-frame (SOF0..SOF15 but DHT, JPG, DAC).
std::optional<Size> jpeg_size(std::istream& in) {
  in.seekg(0);
  unsigned char m[2] = {};
  if (!in.read(reinterpret_cast<char*>(m), 2) || m[0] != 0xFF || m[1] != 0xD8) return std::nullopt;
  for (int segment = 0; segment < 1000; ++segment) {
    unsigned char h[4] = {};
    if (!in.read(reinterpret_cast<char*>(h), 4) || h[0] != 0xFF) return std::nullopt;
    const int marker = h[1];
    const std::int64_t length = big_endian(&h[2], 2);
    if (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC) {
      unsigned char f[5] = {};
      if (!in.read(reinterpret_cast<char*>(f), 5)) return std::nullopt;
      return Size{big_endian(&f[3], 2), big_endian(&f[1], 2)};
    }
    if (length < 2) return std::nullopt;
    in.seekg(length - 2, std::ios::cur);
  }
  return std::nullopt;
}

// PNM (P1..P6): magic, then width and height as decimal tokens (comments skipped).
std::optional<Size> pnm_size(std::istream& in) {
  in.seekg(0);
  char magic[2] = {};
  if (!in.read(magic, 2) || magic[0] != 'P' || magic[1] < '1' || magic[1] > '6') return std::nullopt;
  std::int64_t v[2] = {};
  for (std::int64_t& x : v) {
    int c = in.get();
    while (c == '#' || c == ' ' || c == '\n' || c == '\r' || c == '\t') {
      if (c == '#')
        while (c != '\n' && c != EOF) c = in.get();
      c = in.get();
    }
    if (c < '0' || c > '9') return std::nullopt;
    for (int digits = 0; c >= '0' && c <= '9' && digits < 12; ++digits, c = in.get()) x = x * 10 + (c - '0');
  }
  return Size{v[0], v[1]};
}

}  // namespace

void check_image_size(const std::string& path, std::int64_t width_px, std::int64_t height_px) {
  if (width_px <= kMaxImageSide && height_px <= kMaxImageSide && width_px * height_px <= kMaxImagePixels) return;
  throw InputLimitError(path + ": image of " + std::to_string(width_px) + " x " + std::to_string(height_px) +
                        " pixels is over the limit of " + std::to_string(kMaxImageSide) + " pixels a side and " +
                        std::to_string(kMaxImagePixels >> 20) + " Mpx");
}

void check_image_header(const std::string& path) {
  check_input_file(path, kImageFile);
  std::ifstream in(path, std::ios::binary);
  if (!in) return;
  std::optional<Size> size = png_size(in);
  if (!size) {
    in.clear();
    size = jpeg_size(in);
  }
  if (!size) {
    in.clear();
    size = pnm_size(in);
  }
  if (size) check_image_size(path, size->first, size->second);
}

bool is_image_file(const std::filesystem::path& path) {
  static constexpr std::array<const char*, 14> kExtensions = {".png",  ".jpg", ".jpeg", ".bmp", ".tif",
                                                              ".tiff", ".pgm", ".ppm",  ".pbm", ".pnm",
                                                              ".webp", ".exr", ".hdr",  ".jp2"};
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return std::find(kExtensions.begin(), kExtensions.end(), ext) != kExtensions.end();
}

}  // namespace kincal::files

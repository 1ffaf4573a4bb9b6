#include "host/files/input_limits.hpp"

#include "host/files/input_file.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
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

// JPEG: walk the marker segments to the first start-of-frame (SOF0..SOF15 but DHT, JPG, DAC),
// every segment however many (a header behind a thousand comments is still read).
std::optional<Size> jpeg_size(std::istream& in) {
  in.seekg(0);
  unsigned char m[2] = {};
  if (!in.read(reinterpret_cast<char*>(m), 2) || m[0] != 0xFF || m[1] != 0xD8) return std::nullopt;
  for (;;) {
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
}

// Whether a JPEG (whose size jpeg_size read, `in` just past its start-of-frame) has its
// end-of-image marker after the scan data. Inside scan data 0xFF is always followed by 0x00 or
// a restart marker, so 0xFF 0xD9 there is the end (a thumbnail's own end lies before the scan,
// in its APP segment, and is not seen here). libjpeg decodes a file cut short without an error
// (its warning "Premature end of JPEG file" names no file) and fills the rest grey.
bool jpeg_ends(std::istream& in) {
  bool after_ff = false;
  std::array<char, 65536> buffer{};
  while (in.read(buffer.data(), buffer.size()) || in.gcount() > 0) {
    for (std::streamsize i = 0; i < in.gcount(); ++i) {
      const auto c = static_cast<unsigned char>(buffer[static_cast<std::size_t>(i)]);
      if (after_ff && c == 0xD9) return true;
      after_ff = c == 0xFF;
    }
  }
  return false;
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

std::int64_t little_endian(const unsigned char* p, int bytes) {
  std::int64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = v * 256 + p[i];
  return v;
}

// BMP: "BM", the info header's size at 14, then width and height (int32, or int16 in the old
// 12-byte core header); a negative height is a top-down image.
std::optional<Size> bmp_size(std::istream& in) {
  std::array<unsigned char, 26> h{};
  in.seekg(0);
  if (!in.read(reinterpret_cast<char*>(h.data()), h.size()) || h[0] != 'B' || h[1] != 'M') return std::nullopt;
  const bool core = little_endian(&h[14], 4) == 12;
  const auto signed_field = [&](int at, int bytes) {
    const std::int64_t v = little_endian(&h[static_cast<std::size_t>(at)], bytes);
    return v >= (std::int64_t{1} << (8 * bytes - 1)) ? v - (std::int64_t{1} << (8 * bytes)) : v;
  };
  return core ? Size{signed_field(18, 2), std::abs(signed_field(20, 2))}
              : Size{signed_field(18, 4), std::abs(signed_field(22, 4))};
}

// TIFF ("II*\0" or "MM\0*"): the first directory's ImageWidth (256) and ImageLength (257), SHORT
// or LONG; the first page is the one OpenCV decodes.
std::optional<Size> tiff_size(std::istream& in) {
  std::array<unsigned char, 8> h{};
  in.seekg(0);
  if (!in.read(reinterpret_cast<char*>(h.data()), h.size())) return std::nullopt;
  const bool little = h[0] == 'I' && h[1] == 'I' && h[2] == 42 && h[3] == 0;
  if (!little && !(h[0] == 'M' && h[1] == 'M' && h[2] == 0 && h[3] == 42)) return std::nullopt;
  const auto number = [little](const unsigned char* p, int bytes) {
    return little ? little_endian(p, bytes) : big_endian(p, bytes);
  };
  in.seekg(number(&h[4], 4));
  unsigned char count_bytes[2] = {};
  if (!in.read(reinterpret_cast<char*>(count_bytes), 2)) return std::nullopt;
  std::int64_t width = -1, length = -1;
  for (std::int64_t i = number(count_bytes, 2); i > 0; --i) {
    std::array<unsigned char, 12> e{};
    if (!in.read(reinterpret_cast<char*>(e.data()), e.size())) return std::nullopt;
    const std::int64_t tag = number(&e[0], 2), type = number(&e[2], 2);
    const std::int64_t value = type == 3 ? number(&e[8], 2) : number(&e[8], 4);
    if (tag == 256) width = value;
    if (tag == 257) length = value;
  }
  if (width < 0 || length < 0) return std::nullopt;
  return Size{width, length};
}

// Whether the file starts like one of the formats whose size the readers above take.
bool known_image_format(std::istream& in) {
  std::array<unsigned char, 4> h{};
  in.clear();
  in.seekg(0);
  if (!in.read(reinterpret_cast<char*>(h.data()), h.size())) return false;
  return (h[0] == 0x89 && h[1] == 'P' && h[2] == 'N' && h[3] == 'G') || (h[0] == 0xFF && h[1] == 0xD8) ||
         (h[0] == 'B' && h[1] == 'M') || (h[0] == 'I' && h[1] == 'I' && h[2] == 42) ||
         (h[0] == 'M' && h[1] == 'M' && h[3] == 42) || (h[0] == 'P' && h[1] >= '1' && h[1] <= '6');
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
  bool jpeg = false;
  if (!size) {
    in.clear();
    size = jpeg_size(in);
    jpeg = size.has_value();
  }
  for (const auto reader : {pnm_size, bmp_size, tiff_size}) {
    if (size) break;
    in.clear();
    size = reader(in);
  }
  if (!size && !known_image_format(in))
    throw InputFileError(path +
                         ": not an image kincal reads (PNG, JPEG, TIFF, BMP or PNM: the formats whose size it "
                         "checks before decoding)");
  if (size) check_image_size(path, size->first, size->second);
  if (jpeg && !jpeg_ends(in)) throw InputFileError(path + ": a JPEG cut short (no end-of-image marker after its data)");
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

// Limits on what kincal reads (issue #16), checked before memory is committed: a 20000 x 20000
// PNG is a few kilobytes on disk and 1.2 GB decoded, and OpenCV's own limit (2^30 pixels) lets
// it through.
//
//   images      PNG, JPEG, TIFF, BMP or PNM only, at most kMaxImageSide pixels a side and
//               kMaxImagePixels pixels, read from the file's header (PNG IHDR, JPEG SOFn, TIFF's
//               first directory, BMP's info header, PNM) before decoding; every decoded image is
//               checked again. Other formats are refused by name: OpenCV's decoders allocate
//               first, and its own limit (OPENCV_IO_MAX_IMAGE_PIXELS) is read when the library
//               loads, before main could set it (a 20 KB TIFF declaring 32000 x 32000 pixels
//               took 3.1 GB; a WebP, HDR or PFM file would too). A JPEG cut short (no
//               end-of-image marker) is refused: libjpeg decodes it grey where the data ends,
//               with a warning naming no file.
//   text files  input_file.hpp: a limit per kind, checked by read_text().
//
// Why read image headers here: OpenCV 4.6 (Debian 12) has no call that reports an image's size
// without decoding it, and its decoders allocate the whole image first.
#pragma once

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace kincal::files {

inline constexpr std::int64_t kMaxImageSide = 16384;
inline constexpr std::int64_t kMaxImagePixels = std::int64_t{64} << 20;  // 64 Mpx: 8192 x 8192

// An input over a limit; the message names the file, its size and the limit.
class InputLimitError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The limits as the commands' --help states them (in step with the numbers above and with
// input_file.hpp's kDatasetFile).
inline constexpr const char* kImageLimitText = "at most 16384 px a side and 64 Mpx";
inline constexpr const char* kTextLimitText = "at most 256 MiB";

// Throws InputLimitError when the image's header states a size over the limits, and
// InputFileError (input_file.hpp) for a path that is not a regular file of at most
// kImageFile.max_bytes, a file that is not PNG, JPEG, TIFF, BMP or PNM, or a JPEG cut short. A
// damaged header of one of these formats passes: the decoder reports it, and check_image_size()
// then checks the decoded size.
void check_image_header(const std::string& path);
void check_image_size(const std::string& path, std::int64_t width_px, std::int64_t height_px);

// Whether a directory's file of this name is read as an image (a directory given as images, and
// outputs kept out of one): .png, .jpg, .jpeg, .bmp, .tif(f), .p[gpbn]m, .webp, .exr, .hdr, .jp2,
// in any case.
bool is_image_file(const std::filesystem::path& path);

}  // namespace kincal::files

// Image files through the firmware core's streaming labeler: the host end of `kincal blobs` and
// `kincal fiducials`, and of the tests and benchmarks that compare the labeler with OpenCV.
//
// An image is read with OpenCV's imread (any format it reads) and fed to the very same
// kincal::core::BlobLabeler the platform runs, row by row: 8-bit grey rows for a threshold, or
// RGB565 / YUV422 rows (the camera's formats, packed here from the decoded colour image) through
// the colour-class table. The automatic threshold is the core's Otsu over a first pass of the
// same rows.
//
// Capacities: rows up to 4096 pixels and 4096 rows (the core's limits); 4096 open components,
// which no image of that width can exceed, so no blob is ever lost to capacity here; a blob
// list sized for the worst case. Memory is allocated per call (host code).
//
// Errors: std::runtime_error with a message naming the file and what is wrong (unreadable,
// not an image, too large, a status of the core).
#pragma once

#include <opencv2/core.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "firmware/core/blob_labeler.hpp"
#include "firmware/core/colour_class.hpp"

namespace kincal::vision {

struct LabelOptions {
  core::Polarity polarity = core::Polarity::kBright;
  std::optional<std::uint8_t> threshold;  // none: Otsu's automatic threshold
  core::Connectivity connectivity = core::Connectivity::kEight;
  std::uint32_t min_area_px = 1;
  bool refine = true;
  std::optional<core::ColourClassTable> colour;  // when set: label the class, not a threshold
};

struct LabelResult {
  std::vector<core::Blob> blobs;  // raster order of each blob's first pixel (as OpenCV labels)
  core::FrameSummary summary;
  std::uint8_t threshold = 0;  // the threshold used (Otsu's when automatic)
  bool threshold_automatic = false;
};

// Reads an image; grey == true converts to 8-bit grey, else 8-bit BGR. Throws naming the file.
cv::Mat read_image(const std::string& path, bool grey);

// Labels an 8-bit single-channel image.
LabelResult label_grey(const cv::Mat& grey, const LabelOptions& options);
// Labels the colour class of an 8-bit BGR image (options.colour must be set), packed into the
// table's colour space (RGB565 or YUV422, BT.601) row by row.
LabelResult label_colour(const cv::Mat& bgr, const LabelOptions& options);

// One BGR pixel as the camera would deliver it.
std::uint16_t bgr_to_rgb565(std::uint8_t b, std::uint8_t g, std::uint8_t r);
void bgr_to_yuv(std::uint8_t b, std::uint8_t g, std::uint8_t r, std::uint8_t& y, std::uint8_t& u, std::uint8_t& v);

}  // namespace kincal::vision

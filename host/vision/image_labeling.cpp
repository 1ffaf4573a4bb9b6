#include "host/vision/image_labeling.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <memory>
#include <stdexcept>

#include "firmware/core/auto_threshold.hpp"
#include "host/files/input_limits.hpp"

namespace kincal::vision {

namespace {

using HostBuffers = core::LabelerBuffers<4096, 4096, 17, 4096>;

const char* status_name(core::LabelStatus s) {
  switch (s) {
    case core::LabelStatus::kOk:
      return "ok";
    case core::LabelStatus::kBadWorkspace:
      return "bad workspace";
    case core::LabelStatus::kBadConfig:
      return "bad configuration";
    case core::LabelStatus::kNotInFrame:
      return "not in a frame";
    case core::LabelStatus::kRowTooWide:
      return "row too wide";
    case core::LabelStatus::kRowWidthChanged:
      return "row width changed";
    case core::LabelStatus::kEmptyRow:
      return "empty row";
    case core::LabelStatus::kTooManyRows:
      return "too many rows";
  }
  return "unknown status";
}

void check(core::LabelStatus s, const char* what) {
  if (s != core::LabelStatus::kOk) throw std::runtime_error(std::string("labeler: ") + what + ": " + status_name(s));
}

void check_size(const cv::Mat& img) {
  if (img.empty()) throw std::runtime_error("empty image");
  if (img.cols > 4096 || img.rows > core::kLabelerMaxRows) {
    throw std::runtime_error("image " + std::to_string(img.cols) + "x" + std::to_string(img.rows) +
                             " exceeds the labeler's 4096x4096 limit");
  }
}

core::LabelerConfig config_for(const LabelOptions& options, std::uint8_t threshold) {
  core::LabelerConfig config;
  config.polarity = options.polarity;
  config.threshold = threshold;
  config.connectivity = options.connectivity;
  config.min_area_px = options.min_area_px;
  config.refine = options.refine;
  config.refine_half_window_px = 8;  // the 17-row ring: spots up to sigma ~2.7 px
  config.refine_max_extent_px = 13;
  return config;
}

// Runs the labeler over the rows that fill_row writes into its row buffer.
template <class FillRow>
LabelResult run(const cv::Mat& img, const core::LabelerConfig& config, FillRow fill_row) {
  auto buffers = std::make_unique<HostBuffers>();
  core::BlobLabeler labeler(buffers->memory());
  LabelResult result;
  // Components are at least a pixel apart: at most one per 2x2 cell (capped at 2^20 records;
  // beyond that the summary counts the dropped ones).
  const std::size_t bound = static_cast<std::size_t>(img.cols / 2 + 1) * static_cast<std::size_t>(img.rows / 2 + 1);
  result.blobs.resize(std::min<std::size_t>(bound, std::size_t{1} << 20));
  check(labeler.begin_frame(config, result.blobs), "begin_frame");
  for (int y = 0; y < img.rows; ++y) {
    fill_row(y, labeler.row_buffer());
    check(labeler.commit_row(static_cast<std::uint16_t>(img.cols)), "commit_row");
  }
  check(labeler.end_frame(result.summary), "end_frame");
  result.blobs.resize(result.summary.blobs);
  std::sort(result.blobs.begin(), result.blobs.end(), [](const core::Blob& a, const core::Blob& b) {
    return a.y_min_px != b.y_min_px ? a.y_min_px < b.y_min_px : a.first_x_px < b.first_x_px;
  });
  result.threshold = config.threshold;
  return result;
}

}  // namespace

cv::Mat read_image(const std::string& path, bool grey) {
  cv::Mat img;
  try {
    files::check_image_header(path);
    img = cv::imread(path, grey ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(path + ": cannot decode the image (" + e.what() + ")");
  }
  if (img.empty()) throw std::runtime_error(path + ": not an image OpenCV can read");
  try {
    check_size(img);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  return img;
}

LabelResult label_grey(const cv::Mat& grey, const LabelOptions& options) {
  if (grey.type() != CV_8UC1) throw std::runtime_error("label_grey needs an 8-bit single-channel image");
  check_size(grey);
  std::uint8_t threshold = 0;
  bool automatic = false;
  if (options.threshold) {
    threshold = *options.threshold;
  } else {
    core::GreyHistogram histogram;
    for (int y = 0; y < grey.rows; ++y) {
      if (histogram.add_row({grey.ptr<std::uint8_t>(y), static_cast<std::size_t>(grey.cols)}) !=
          core::ThresholdStatus::kOk) {
        throw std::runtime_error("histogram: too many pixels");
      }
    }
    std::uint8_t otsu = 0;
    if (core::otsu_threshold(histogram, otsu) != core::ThresholdStatus::kOk) {
      throw std::runtime_error("automatic threshold: the image has a single grey level");
    }
    threshold = options.polarity == core::Polarity::kBright ? otsu : core::dark_threshold(otsu);
    automatic = true;
  }
  LabelResult result = run(grey, config_for(options, threshold), [&](int y, std::span<std::uint8_t> out) {
    std::copy_n(grey.ptr<std::uint8_t>(y), grey.cols, out.begin());
  });
  result.threshold_automatic = automatic;
  return result;
}

std::uint16_t bgr_to_rgb565(std::uint8_t b, std::uint8_t g, std::uint8_t r) {
  return static_cast<std::uint16_t>((r >> 3) << 11 | (g >> 2) << 5 | (b >> 3));
}

void bgr_to_yuv(std::uint8_t b, std::uint8_t g, std::uint8_t r, std::uint8_t& y, std::uint8_t& u, std::uint8_t& v) {
  // ITU-R BT.601, studio range, integer (what camera modules output as YCbCr).
  y = static_cast<std::uint8_t>((66 * r + 129 * g + 25 * b + 128) / 256 + 16);
  u = static_cast<std::uint8_t>((-38 * r - 74 * g + 112 * b + 128) / 256 + 128);
  v = static_cast<std::uint8_t>((112 * r - 94 * g - 18 * b + 128) / 256 + 128);
}

LabelResult label_colour(const cv::Mat& bgr, const LabelOptions& options) {
  if (!options.colour) throw std::runtime_error("label_colour needs a colour-class table");
  if (bgr.type() != CV_8UC3) throw std::runtime_error("label_colour needs an 8-bit BGR image");
  check_size(bgr);
  const core::ColourClassTable& table = *options.colour;
  LabelOptions bright = options;
  bright.polarity = core::Polarity::kBright;  // scores: higher is more the class
  std::vector<std::uint16_t> rgb565(static_cast<std::size_t>(bgr.cols));
  std::vector<std::uint8_t> yuyv(static_cast<std::size_t>(bgr.cols) * 2 + 2);
  return run(bgr, config_for(bright, table.threshold), [&](int y, std::span<std::uint8_t> out) {
    const auto* px = bgr.ptr<cv::Vec3b>(y);
    core::PixelStatus status;
    if (table.space == core::ColourSpace::kRgb565) {
      for (int x = 0; x < bgr.cols; ++x)
        rgb565[static_cast<std::size_t>(x)] = bgr_to_rgb565(px[x][0], px[x][1], px[x][2]);
      status = core::classify_rgb565(rgb565, table, out);
    } else {
      // YUYV: each pixel pair shares the mean of its two U and V; an odd last pixel pairs with itself.
      const int pairs = (bgr.cols + 1) / 2;
      for (int i = 0; i < pairs; ++i) {
        const cv::Vec3b& a = px[2 * i];
        const cv::Vec3b& b = px[2 * i + 1 < bgr.cols ? 2 * i + 1 : 2 * i];
        std::uint8_t y0, u0, v0, y1, u1, v1;
        bgr_to_yuv(a[0], a[1], a[2], y0, u0, v0);
        bgr_to_yuv(b[0], b[1], b[2], y1, u1, v1);
        const auto k = static_cast<std::size_t>(4 * i);
        yuyv[k] = y0;
        yuyv[k + 1] = static_cast<std::uint8_t>((u0 + u1 + 1) / 2);
        yuyv[k + 2] = y1;
        yuyv[k + 3] = static_cast<std::uint8_t>((v0 + v1 + 1) / 2);
      }
      status = core::classify_yuv422(std::span<const std::uint8_t>(yuyv.data(), static_cast<std::size_t>(4 * pairs)),
                                     table, out);
    }
    if (status != core::PixelStatus::kOk) throw std::runtime_error("colour classification failed");
  });
}

}  // namespace kincal::vision

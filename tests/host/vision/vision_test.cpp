// The firmware core's streaming labeler, run on image files by host/vision, against OpenCV on
// real photographs (OpenCV's sample data): the same components as threshold +
// connectedComponentsWithStats over the same foreground, the same binary centroids to 1e-3 px,
// the same Otsu threshold; and the colour-class path and the file errors.
#include <doctest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "host/vision/colour_table_builder.hpp"
#include "host/vision/image_labeling.hpp"

using namespace kincal;

namespace {

const char* const kPhotographs[] = {"left01.jpg", "fruits.jpg",   "baboon.jpg",    "detect_blob.png",
                                    "board.jpg",  "building.jpg", "chessboard.png"};

std::string sample(const char* name) { return std::string(KINCAL_OPENCV_SAMPLES) + "/" + name; }

// Compares one labeling with OpenCV's on the same foreground; returns the number of components.
int compare_with_opencv(const cv::Mat& grey, const vision::LabelOptions& options, const std::string& what) {
  const vision::LabelResult ours = vision::label_grey(grey, options);
  const int t = ours.threshold;
  cv::Mat binary, labels, stats, centroids;
  if (options.polarity == core::Polarity::kBright) {
    cv::threshold(grey, binary, t, 255, cv::THRESH_BINARY);  // I > t
  } else {
    cv::threshold(grey, binary, t - 1, 255, cv::THRESH_BINARY_INV);  // I <= t - 1, i.e. I < t
  }
  const int connectivity = options.connectivity == core::Connectivity::kEight ? 8 : 4;
  const int n = cv::connectedComponentsWithStats(binary, labels, stats, centroids, connectivity, CV_32S) - 1;
  // OpenCV's components keyed by their first pixel in raster order, as ours are.
  std::vector<std::pair<int, int>> first_of_label(static_cast<std::size_t>(n + 1), {-1, -1});
  std::map<std::pair<int, int>, int> first;
  for (int y = 0; y < labels.rows; ++y)
    for (int x = 0; x < labels.cols; ++x) {
      const int l = labels.at<int>(y, x);
      auto& f = first_of_label[static_cast<std::size_t>(l)];
      if (l > 0 && f.first < 0) {
        f = {y, x};
        first.emplace(f, l);
      }
    }

  CHECK_MESSAGE(ours.summary.runs_untracked == 0, what);
  CHECK_MESSAGE(ours.blobs.size() == static_cast<std::size_t>(n), what, ": ", ours.blobs.size(), " vs ", n);
  int mismatches = 0;
  double worst = 0;
  for (const core::Blob& b : ours.blobs) {
    auto it = first.find({b.y_min_px, b.first_x_px});
    bool same = it != first.end();
    if (same) {
      const int l = it->second;
      same = first_of_label[static_cast<std::size_t>(l)] ==
                 std::make_pair(static_cast<int>(b.y_min_px), static_cast<int>(b.first_x_px)) &&
             stats.at<int>(l, cv::CC_STAT_AREA) == static_cast<int>(b.area_px) &&
             stats.at<int>(l, cv::CC_STAT_LEFT) == b.x_min_px && stats.at<int>(l, cv::CC_STAT_TOP) == b.y_min_px &&
             stats.at<int>(l, cv::CC_STAT_WIDTH) == b.x_max_px - b.x_min_px + 1 &&
             stats.at<int>(l, cv::CC_STAT_HEIGHT) == b.y_max_px - b.y_min_px + 1;
      const double ex = std::fabs(centroids.at<double>(l, 0) - b.binary_x_px.to_double());
      const double ey = std::fabs(centroids.at<double>(l, 1) - b.binary_y_px.to_double());
      worst = std::fmax(worst, std::fmax(ex, ey));
    }
    if (!same && ++mismatches <= 3) MESSAGE(what, ": component at (", b.first_x_px, ", ", b.y_min_px, ") differs");
  }
  CHECK_MESSAGE(mismatches == 0, what);
  CHECK_MESSAGE(worst < 1e-3, what, ": worst binary centroid difference ", worst, " px");
  return n;
}

}  // namespace

TEST_CASE("labeler vs OpenCV connectedComponentsWithStats on photographs: same components and centroids") {
  int total = 0;
  for (const char* name : kPhotographs) {
    const std::string path = sample(name);
    REQUIRE_MESSAGE(std::filesystem::exists(path), path, " missing: install opencv-doc (toolchain/setup-debian.sh)");
    const cv::Mat grey = vision::read_image(path, true);
    for (const auto polarity : {core::Polarity::kBright, core::Polarity::kDark}) {
      for (const auto connectivity : {core::Connectivity::kEight, core::Connectivity::kFour}) {
        vision::LabelOptions options;
        options.polarity = polarity;
        options.connectivity = connectivity;
        total += compare_with_opencv(grey, options, std::string(name));
        options.threshold = 200;
        total += compare_with_opencv(grey, options, std::string(name) + " t=200");
      }
    }
  }
  MESSAGE("components compared with OpenCV: ", total);
  CHECK(total > 10000);
}

TEST_CASE("automatic threshold: Otsu as OpenCV's THRESH_OTSU computes it") {
  for (const char* name : kPhotographs) {
    const cv::Mat grey = vision::read_image(sample(name), true);
    cv::Mat ignored;
    const double theirs = cv::threshold(grey, ignored, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
    const vision::LabelResult ours = vision::label_grey(grey, vision::LabelOptions{});
    CHECK(ours.threshold_automatic);
    CHECK_MESSAGE(ours.threshold == theirs, name, ": ours ", int{ours.threshold}, ", OpenCV ", theirs);
  }
}

namespace {

// The crimson beacon (B, G, R = 40, 20, 200 at full light) lit by `light`.
cv::Vec3b crimson(double light) {
  return {static_cast<std::uint8_t>(40 * light), static_cast<std::uint8_t>(20 * light),
          static_cast<std::uint8_t>(200 * light)};
}

// 200 samples of the beacon lit from 0.6 to 1.0.
vision::ColourTableSamples crimson_samples() {
  vision::ColourTableSamples samples;
  for (int i = 0; i < 200; ++i) samples.positive_bgr.push_back(crimson(0.6 + 0.4 * i / 199.0));
  return samples;
}

}  // namespace

TEST_CASE("colour classes: a table built from beacon samples finds the beacon, not the clutter") {
  vision::ColourTableSamples samples = crimson_samples();
  // emplace_back, not an initializer list of cv::Vec3b: GCC 12 -O3 warns maybe-uninitialized on that.
  samples.negative_bgr.emplace_back(90, 90, 90);
  samples.negative_bgr.emplace_back(250, 250, 250);
  samples.negative_bgr.emplace_back(30, 140, 240);
  for (const auto space : {core::ColourSpace::kRgb565, core::ColourSpace::kYuv422}) {
    const core::ColourClassTable table = vision::build_colour_table(samples, space);
    cv::Mat scene(80, 120, CV_8UC3, cv::Scalar(90, 90, 90));
    cv::rectangle(scene, cv::Rect(5, 5, 20, 20), cv::Scalar(250, 250, 250), cv::FILLED);
    cv::rectangle(scene, cv::Rect(10, 55, 25, 15), cv::Scalar(30, 140, 240), cv::FILLED);
    cv::circle(scene, cv::Point(60, 40), 8, cv::Scalar(36, 18, 180), cv::FILLED);
    vision::LabelOptions options;
    options.colour = table;
    const vision::LabelResult r = vision::label_colour(scene, options);
    REQUIRE(r.blobs.size() == 1);
    CHECK(std::fabs(r.blobs[0].x_px.to_double() - 60) < 0.5);
    CHECK(std::fabs(r.blobs[0].y_px.to_double() - 40) < 0.05);
    cv::Mat disc_mask;
    cv::inRange(scene, cv::Scalar(36, 18, 180), cv::Scalar(36, 18, 180), disc_mask);
    const int disc = cv::countNonZero(disc_mask);
    if (space == core::ColourSpace::kRgb565) {
      CHECK(r.blobs[0].area_px == static_cast<std::uint32_t>(disc));  // every disc pixel, nothing else
    } else {
      // YUYV shares chroma between pixel pairs: rim pixels paired with grey may drop out.
      CHECK(r.blobs[0].area_px <= static_cast<std::uint32_t>(disc));
      CHECK(r.blobs[0].area_px >= static_cast<std::uint32_t>(disc * 85 / 100));
    }
  }
  CHECK_THROWS_AS(vision::build_colour_table(vision::ColourTableSamples{}, core::ColourSpace::kRgb565),
                  std::runtime_error);
}

TEST_CASE("colour classes: lighting that changes across the beacon does not move its centroid") {
  // Samples of the beacon under lighting from 0.6 to 1.0; a disc of radius 8 px at (60, 40) lit
  // from 0.81 on its left to 0.89 on its right (0.6 % per pixel: about 6 times the steepest
  // vignetting slope of tests/bench/stereo_colour_bias_bench's frames). Every disc pixel is in the
  // class's flat core, so its weights are equal and the centroid does not move; the score peaked
  // at the samples' mean colour (255 exp(-d^2 / 2), before issue #22's fix) pulled it toward the
  // side lit nearest that mean: 0.13 px in RGB565, 0.014 px in YUV422.
  vision::ColourTableSamples samples = crimson_samples();
  samples.negative_bgr.emplace_back(90, 90, 90);
  // The disc with light slope `per_px` (0: evenly lit at 0.85).
  const auto centroid = [&](core::ColourSpace space, double per_px) {
    cv::Mat scene(80, 120, CV_8UC3, cv::Scalar(90, 90, 90));
    for (int y = 0; y < scene.rows; ++y)
      for (int x = 0; x < scene.cols; ++x)
        if (std::hypot(x - 60, y - 40) <= 8) {
          scene.at<cv::Vec3b>(y, x) = crimson(0.85 + per_px * (x - 60));
        }
    vision::LabelOptions options;
    options.colour = vision::build_colour_table(samples, space);
    const vision::LabelResult r = vision::label_colour(scene, options);
    REQUIRE(r.blobs.size() == 1);
    return cv::Point2d(r.blobs[0].x_px.to_double(), r.blobs[0].y_px.to_double());
  };
  // RGB565: the disc's centre. YUV422: the same as evenly lit (pixel pairs that share chroma
  // with the background drop out of the class on the right rim only, lit or not).
  const cv::Point2d rgb = centroid(core::ColourSpace::kRgb565, 0.005);
  CHECK(std::fabs(rgb.x - 60) < 0.005);
  CHECK(std::fabs(rgb.y - 40) < 0.005);
  const cv::Point2d yuv = centroid(core::ColourSpace::kYuv422, 0.005),
                    yuv_even = centroid(core::ColourSpace::kYuv422, 0);
  CHECK(std::fabs(yuv.x - yuv_even.x) < 0.005);
  CHECK(std::fabs(yuv.y - yuv_even.y) < 0.005);
}

TEST_CASE("colour classes: rim pixels weigh by the beacon's share in them, so the centroid does not lock to pixels") {
  // A crimson disc of radius 6 px on grey 90, each pixel the area-weighted mix of the two (8 x 8
  // sub-samples), at 25 sub-pixel positions. With the scene's grey among the negatives, rim
  // pixels score their share of the beacon; with no negatives the class is the samples' ellipsoid
  // alone and the rim drops out a quarter of the way to the grey: its centroid locks to the grid.
  vision::ColourTableSamples samples = crimson_samples();
  const auto errors_rms = [&](const vision::ColourTableSamples& s) {
    vision::LabelOptions options;
    options.colour = vision::build_colour_table(s, core::ColourSpace::kRgb565);
    double sum = 0;
    int n = 0;
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j) {
        const double cx = 30.1 + 0.2 * i, cy = 20.1 + 0.2 * j;
        cv::Mat scene(40, 60, CV_8UC3, cv::Scalar(90, 90, 90));
        for (int y = 10; y < 31; ++y)
          for (int x = 20; x < 41; ++x) {
            int inside = 0;
            for (int k = 0; k < 64; ++k)
              inside += std::hypot(x - 0.5 + (k % 8 + 0.5) / 8 - cx, y - 0.5 + (k / 8 + 0.5) / 8 - cy) <= 6 ? 1 : 0;
            const double a = inside / 64.0;
            const cv::Vec3b c = crimson(0.85);
            scene.at<cv::Vec3b>(y, x) = {static_cast<std::uint8_t>(std::lround(a * c[0] + (1 - a) * 90)),
                                         static_cast<std::uint8_t>(std::lround(a * c[1] + (1 - a) * 90)),
                                         static_cast<std::uint8_t>(std::lround(a * c[2] + (1 - a) * 90))};
          }
        const vision::LabelResult r = vision::label_colour(scene, options);
        REQUIRE(r.blobs.size() == 1);
        sum += std::pow(r.blobs[0].x_px.to_double() - cx, 2) + std::pow(r.blobs[0].y_px.to_double() - cy, 2);
        ++n;
      }
    return std::sqrt(sum / n);
  };
  const double without_rim = errors_rms(samples);
  for (int i = 0; i < 200; ++i) samples.negative_bgr.emplace_back(90, 90, 90);
  const double with_rim = errors_rms(samples);
  MESSAGE("centroid error RMS: ", with_rim, " px with the rim, ", without_rim, " px without");
  CHECK(with_rim < 0.5 * without_rim);
  CHECK(with_rim < 0.05);
}

TEST_CASE("image files: errors name the file") {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "kincal_vision_test";
  std::filesystem::create_directories(dir);
  const std::string text = (dir / "text.png").string();
  std::ofstream(text) << "not an image";
  try {
    (void)vision::read_image(text, true);
    FAIL("no error for a text file");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find(text) != std::string::npos);
    CHECK(std::string(e.what()).find("not an image") != std::string::npos);
  }
  CHECK_THROWS_WITH_AS(vision::read_image((dir / "missing.png").string(), true), doctest::Contains("no such file"),
                       std::runtime_error);
  CHECK_THROWS_AS(vision::read_image(dir.string(), true), std::runtime_error);  // a directory
  cv::Mat wide(2, 5000, CV_8UC1, cv::Scalar(0));
  CHECK_THROWS_WITH_AS(vision::label_grey(wide, vision::LabelOptions{}), doctest::Contains("4096"), std::runtime_error);
  std::filesystem::remove_all(dir);
}

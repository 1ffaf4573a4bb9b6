#include "tests/host/camera/real_corpus.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace kincal::camera::testing {

namespace {

const std::vector<int> kSampleViews = {1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13, 14};  // there is no 10
constexpr std::array<const char*, 3> kTextures = {"building.jpg", "baboon.jpg", "fruits.jpg"};
constexpr std::array<const char*, 4> kEdges = {"left", "right", "top", "bottom"};
const cv::Size kPattern(9, 6);

std::string sample_path(const std::string& file) { return std::string(KINCAL_OPENCV_SAMPLES) + "/" + file; }

cv::Mat read_grey(const std::string& file) {
  const cv::Mat image = cv::imread(sample_path(file), cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw std::runtime_error(sample_path(file) + ": not read");
  return image;
}

// How far the board reaches towards image edge `side` (its outermost corner's coordinate) and the
// square's side (px) there: the distance from that corner to its nearest grid neighbour.
struct Reach {
  double coordinate_px = 0, square_px = 0;
};
Reach reach(const std::vector<cv::Point2f>& corners, int side) {
  const auto key = [side](const cv::Point2f& p) { return side < 2 ? p.x : p.y; };
  const bool low = side % 2 == 0;
  std::size_t best = 0;
  for (std::size_t i = 1; i < corners.size(); ++i)
    if (low ? key(corners[i]) < key(corners[best]) : key(corners[i]) > key(corners[best])) best = i;
  const int cols = kPattern.width, i = static_cast<int>(best) % cols, j = static_cast<int>(best) / cols;
  double square = 1e9;
  for (const auto& [di, dj] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
    if (i + di < 0 || i + di >= cols || j + dj < 0 || j + dj >= kPattern.height) continue;
    square = std::min(square, cv::norm(corners[best] - corners[static_cast<std::size_t>((j + dj) * cols + i + di)]));
  }
  return {key(corners[best]), square};
}

// The image cropped at `at_px` on image edge `side` (the part beyond it removed).
cv::Mat crop_edge(const cv::Mat& grey, int side, int at_px) {
  cv::Rect keep(0, 0, grey.cols, grey.rows);
  if (side == 0) keep = cv::Rect(at_px, 0, grey.cols - at_px, grey.rows);
  if (side == 1) keep = cv::Rect(0, 0, at_px + 1, grey.rows);
  if (side == 2) keep = cv::Rect(0, at_px, grey.cols, grey.rows - at_px);
  if (side == 3) keep = cv::Rect(0, 0, grey.cols, at_px + 1);
  return grey(keep).clone();
}

// Where a crop on edge `side` cuts `fraction` of a square beyond the board's outermost corner.
int cut_position_px(const Reach& r, int side, double fraction) {
  const double at = side % 2 == 0 ? r.coordinate_px - fraction * r.square_px : r.coordinate_px + fraction * r.square_px;
  return static_cast<int>(side % 2 == 0 ? std::ceil(at) : std::floor(at));
}

}  // namespace

std::vector<RealView> sample_views(const std::string& side) {
  std::vector<RealView> out;
  for (int i : kSampleViews) {
    const std::string file = side + (i < 10 ? "0" : "") + std::to_string(i) + ".jpg";
    out.push_back({file, read_grey(file)});
  }
  return out;
}

std::vector<cv::Point2f> board_corners(const cv::Mat& grey) {
  std::vector<cv::Point2f> corners;
  if (!cv::findChessboardCornersSB(grey, kPattern, corners, cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_ACCURACY))
    corners.clear();
  return corners;
}

cv::Mat background_texture(cv::Size size, int which) {
  const cv::Mat t = read_grey(kTextures[static_cast<std::size_t>(which) % kTextures.size()]);
  cv::Mat out;
  cv::resize(t, out, size, 0, 0, cv::INTER_AREA);
  return out;
}

cv::Mat cut_outer_squares(const cv::Mat& grey, int image_side, double fraction) {
  const std::vector<cv::Point2f> corners = board_corners(grey);
  if (corners.empty()) return {};
  const int at = cut_position_px(reach(corners, image_side), image_side, fraction);
  const int limit = image_side < 2 ? grey.cols : grey.rows;
  if (at <= 0 || at >= limit - 1) return {};
  return crop_edge(grey, image_side, at);
}

cv::Mat board_on_texture(const cv::Mat& grey, const cv::Mat& texture, int feather_px) {
  const std::vector<cv::Point2f> corners = board_corners(grey);
  if (corners.empty()) return {};
  // The outer squares' outer edges: the grid one square beyond its outer corners, traced along
  // each side by the homography of the corners.
  std::vector<cv::Point2f> grid;
  for (int j = 0; j < kPattern.height; ++j)
    for (int i = 0; i < kPattern.width; ++i) grid.emplace_back(static_cast<float>(i), static_cast<float>(j));
  const cv::Mat h = cv::findHomography(grid, corners);
  std::vector<cv::Point2f> outline_grid, outline;
  const float w = static_cast<float>(kPattern.width), ht = static_cast<float>(kPattern.height);
  for (float u = -1; u < w; u += 0.25f) outline_grid.emplace_back(u, -1.0f);
  for (float v = -1; v < ht; v += 0.25f) outline_grid.emplace_back(w, v);
  for (float u = w; u > -1; u -= 0.25f) outline_grid.emplace_back(u, ht);
  for (float v = ht; v > -1; v -= 0.25f) outline_grid.emplace_back(-1.0f, v);
  cv::perspectiveTransform(outline_grid, outline, h);
  std::vector<cv::Point> polygon;
  for (const cv::Point2f& p : outline) polygon.emplace_back(cvRound(p.x), cvRound(p.y));
  cv::Mat mask(grey.size(), CV_32F, cv::Scalar(0));
  cv::fillPoly(mask, std::vector<std::vector<cv::Point>>{polygon}, cv::Scalar(1));
  if (feather_px > 0) cv::GaussianBlur(mask, mask, cv::Size(0, 0), feather_px);
  cv::Mat board, background, out;
  grey.convertTo(board, CV_32F);
  texture.convertTo(background, CV_32F);
  out = board.mul(mask) + background.mul(1 - mask);
  out.convertTo(out, CV_8U);
  return out;
}

cv::Mat rescaled(const cv::Mat& grey, double factor) {
  cv::Mat out;
  cv::resize(grey, out, cv::Size(), factor, factor, factor < 1 ? cv::INTER_AREA : cv::INTER_CUBIC);
  return out;
}

std::vector<RealView> view_variants() {
  std::vector<RealView> out;
  for (const char* side : {"left", "right"}) {
    int k = 0;
    for (const RealView& v : sample_views(side)) {
      for (int edge = 0; edge < 4; ++edge)
        for (const double fraction : {0.25, 0.5, 0.75}) {
          const cv::Mat cut = cut_outer_squares(v.image, edge, fraction);
          if (!cut.empty())
            out.push_back({v.name + " cut " + kEdges[static_cast<std::size_t>(edge)] + " " +
                               std::to_string(fraction).substr(0, 4),
                           cut});
        }
      for (int t = 0; t < 3; ++t)
        for (const int feather : {0, 3}) {
          const cv::Mat on = board_on_texture(v.image, background_texture(v.image.size(), k + t), feather);
          if (!on.empty())
            out.push_back({v.name + " on " + kTextures[static_cast<std::size_t>((k + t) % 3)] + " feather " +
                               std::to_string(feather),
                           on});
        }
      for (const double factor : {0.5, 0.75, 1.5})
        out.push_back({v.name + " x" + std::to_string(factor).substr(0, 4), rescaled(v.image, factor)});
      ++k;
    }
  }
  return out;
}

std::vector<RealSet> calibration_sets() {
  std::vector<RealSet> out;
  for (const char* side : {"left", "right"}) {
    const std::vector<RealView> views = sample_views(side);
    const std::string s(side);
    out.push_back({s, views});
    for (const double factor : {0.5, 1.5}) {
      RealSet set{s + " x" + std::to_string(factor).substr(0, 3), {}};
      for (const RealView& v : views) set.views.push_back({v.name, rescaled(v.image, factor)});
      out.push_back(std::move(set));
    }
    {
      RealSet set{s + " on texture", {}};
      for (std::size_t k = 0; k < views.size(); ++k) {
        const cv::Mat on =
            board_on_texture(views[k].image, background_texture(views[k].image.size(), static_cast<int>(k)), 2);
        set.views.push_back({views[k].name, on.empty() ? views[k].image : on});
      }
      out.push_back(std::move(set));
    }
    {
      // One crop for all: on each image edge half a square beyond the corners of the view second
      // nearest it, so that the nearest view's board is partly outside (a partial board, which no
      // detector finds) and the second's outer squares are cut.
      cv::Rect keep(0, 0, views.front().image.cols, views.front().image.rows);
      std::array<std::vector<int>, 4> at;
      for (const RealView& v : views) {
        const std::vector<cv::Point2f> corners = board_corners(v.image);
        if (corners.empty()) continue;
        for (int edge = 0; edge < 4; ++edge)
          at[static_cast<std::size_t>(edge)].push_back(cut_position_px(reach(corners, edge), edge, 0.5));
      }
      for (int edge = 0; edge < 4; ++edge) {
        std::vector<int>& a = at[static_cast<std::size_t>(edge)];
        std::sort(a.begin(), a.end());
        const int second =
            edge % 2 == 0 ? std::max(0, a[1]) : std::min(edge == 1 ? keep.width - 1 : keep.height - 1, a[a.size() - 2]);
        if (edge == 0) keep.x = second;
        if (edge == 2) keep.y = second;
        if (edge == 1) keep.width = second + 1 - keep.x;
        if (edge == 3) keep.height = second + 1 - keep.y;
      }
      RealSet set{s + " cropped " + std::to_string(keep.width) + "x" + std::to_string(keep.height), {}};
      for (const RealView& v : views) set.views.push_back({v.name, v.image(keep).clone()});
      out.push_back(std::move(set));
    }
  }
  return out;
}

}  // namespace kincal::camera::testing

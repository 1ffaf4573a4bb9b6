// Real photographs in the ways users take them (issue #43): OpenCV's sample views (Debian's
// opencv-doc, left01..14.jpg and right01..14.jpg, a 9x6 chessboard, 640x480; there is no 10) and
// variants made of them, each of which still shows the whole 9x6 board, for the gates that must
// not refuse valid data (the whole-board test, the view-outlier rule, the stereo consensus) and
// the corpus benchmark (tests/bench/camera_corpus_bench.cpp).
//
// Variants of one view (each keeps every one of the board's 54 inner corners in the image):
//   cut     the image cropped so that one image edge runs through the board's outer squares
//           (the row or column of squares beyond the outermost corners), `fraction` of a square
//           beyond the corners nearest that edge: the board "cut by the image edge";
//   texture everything beyond the board's outer squares (their outer edges by the homography of
//           the corners, one square out) replaced by another real photograph (building.jpg,
//           baboon.jpg, fruits.jpg ... from the same folder), so the board has no white margin and
//           lies against clutter; with the seam feathered over `feather_px`;
//   rescale the image resized by a factor (INTER_AREA down, INTER_CUBIC up).
// Sets that share one camera (for calibration): the same crop, texture or scale applied to every
// view of one side; views whose board the crop leaves are left out of the set.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace kincal::camera::testing {

inline constexpr double kSampleSquare_m = 0.025;  // the sample does not say; only ratios matter
inline const char* const kSampleBoard = "chessboard:9x6:0.025";

struct RealView {
  std::string name;  // "left01.jpg", "left01.jpg cut left 0.5", ...
  cv::Mat image;     // 8-bit grey
};

// The 13 views of one side ("left" or "right"), in order.
std::vector<RealView> sample_views(const std::string& side);

// The 9x6 board's inner corners in a view, found by cv::findChessboardCornersSB (exact to about
// 0.1 px: where the variants put their cuts and seams); empty when not found.
std::vector<cv::Point2f> board_corners(const cv::Mat& grey);

// A photograph of the folder as background texture, grey, resized to `size`; `which` picks one of
// several (modulo their number).
cv::Mat background_texture(cv::Size size, int which);

// One view's variants, as described above. Each returns an empty image when the view does not
// allow it (the edge already closer than the cut, the board not found).
cv::Mat cut_outer_squares(const cv::Mat& grey, int image_side,
                          double fraction);  // side 0 left, 1 right, 2 top, 3 bottom
cv::Mat board_on_texture(const cv::Mat& grey, const cv::Mat& texture, int feather_px);
cv::Mat rescaled(const cv::Mat& grey, double factor);

// Every per-view variant of both sides: cuts at 0.25, 0.5 and 0.75 of a square on each of the four
// image edges, the board on three textures (sharp and feathered seams), rescales 0.5, 0.75 and
// 1.5. Named "<view> <variant>".
std::vector<RealView> view_variants();

// Sets sharing one camera: for each side, the views as they are, rescaled by 0.5 and by 1.5, on
// texture, and cropped by the largest common crop that cuts at least one view's outer squares on
// each image edge it can (views whose corners it leaves are dropped).
struct RealSet {
  std::string name;
  std::vector<RealView> views;
};
std::vector<RealSet> calibration_sets();

}  // namespace kincal::camera::testing

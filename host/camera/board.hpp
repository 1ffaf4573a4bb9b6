// Calibration boards and their detection (issue #6): a plain chessboard or a ChArUco board
// (OpenCV 4.6 contrib's cv::aruco API), described by a one-line text the command line takes,
// found in an image as corners with their board coordinates.
//
// Text form (metres):
//   chessboard:COLSxROWS:SQUARE_M                  COLS x ROWS inner corners
//   charuco:COLSxROWS:SQUARE_M:MARKER_M[:DICT]     COLS x ROWS squares; DICT is an OpenCV
//                                                  predefined dictionary such as DICT_4X4_50
//                                                  (the default) or DICT_5X5_100
// Board frame: chessboard inner corner (i, j) at (i * square, j * square, 0), id j * COLS + i
// (as kincal::sim::chessboard draws it); ChArUco corners where cv::aruco::CharucoBoard puts them
// (its chessboardCorners), id as OpenCV numbers them.
//
// Chessboard detection, one pipeline from VGA to 4K:
//  1. find the grid: cv::findChessboardCornersSB (CALIB_CB_NORMALIZE_IMAGE); if it fails,
//     cv::findChessboardCorners (ADAPTIVE_THRESH | NORMALIZE_IMAGE), which finds boards the first
//     misses in large or blurred images. BoardDetection::detector names the one that served.
//  2. refine every corner with cv::cornerSubPix, the same step whichever detector served: half
//     window w = floor(kRefineWindowFraction * s) clamped to [kMinRefineHalfWindow_px,
//     kMaxRefineHalfWindow_px], s the smallest distance between two neighbouring corners
//     (diagonals included) in this view, so the (2w+1)-pixel window's corners stay within half
//     the way to the nearest other corner (0.35 * sqrt 2 < 0.5) and the window holds one corner
//     only, in a 640x480 view as in a 4K one (a fixed 5x5 or 11x11 window is too small for one
//     and spans several corners in the other). Termination: kRefineIterations iterations or a
//     step below kRefineEpsilon_px (OpenCV's tutorial values).
//     On OpenCV's 13 sample views (left01..14.jpg) this gives 0.177 px RMS where OpenCV's own
//     recipe (findChessboardCorners + cornerSubPix 5x5) gives 0.196 px.
//  3. the whole board or nothing: a grid of the given size found inside a larger board (8x6
//     corners of a 9x6 board, a different part in different views) is refused. Beyond each
//     side of the grid, rings of would-be squares are placed by a homography fitted to the
//     three nearest lines of corners; ring 1 is the board's outer squares, ring 2 is white
//     margin on the board given. Each would-be square is sampled in the quarter nearest the
//     board (outer squares are often printed narrower), a window of 1/8 of its side. If ring
//     2's squares alternate like the board's own (their parity contrast reaches
//     kExtensionContrastRatio of the interior's; on OpenCV's 26 sample views: at most 0.17 for
//     the true 9x6 board, at least 0.77 for 8x6 inside it), the board continues
//     there; rings are counted outwards while they do. Such a view is not found, with
//     fitting_board the size that fits ("chessboard:9x6:0.025") and the reason naming it. A
//     side whose ring 2 leaves the image cannot be judged and counts as the board's edge.
//  4. orientation: a chessboard looks the same turned by 180 degrees unless COLS + ROWS is odd
//     (then its two far corner squares differ in colour); for such boards the corners are
//     ordered so that the square diagonally outside corner 0 is the dark one, which keeps the
//     board frame the same in every view (stereo and hand-eye need that). Boards with
//     COLS + ROWS even stay ambiguous: use COLS + ROWS odd, or ChArUco.
// ChArUco detection: cv::aruco::detectMarkers, refineDetectedMarkers, interpolateCornersCharuco
// (with its own cornerSubPix: a window sized to the square would reach the markers' edges).
// Failures: parse_board throws std::invalid_argument quoting the text and saying which field is
// wrong. detect_board does not throw for an image without the board: it returns found = false
// with the reason ("pattern not found", "too few corners (N, at least M)", the wrong size); it throws
// std::invalid_argument for an empty image or one that is not 8-bit.
// Cost: detection is tens of milliseconds for VGA (OpenCV's detectors dominate).
#pragma once

#include <string>
#include <vector>

#include <opencv2/aruco/charuco.hpp>
#include <opencv2/core.hpp>

namespace kincal::camera {

enum class BoardKind { kChessboard, kCharuco };

struct Board {
  BoardKind kind = BoardKind::kChessboard;
  int cols = 0, rows = 0;  // chessboard: inner corners; ChArUco: squares
  double square_m = 0;
  double marker_m = 0;                       // ChArUco only
  std::string dictionary;                    // ChArUco only, e.g. "DICT_4X4_50"
  cv::Ptr<cv::aruco::CharucoBoard> charuco;  // ChArUco only

  // The text form, as parse_board reads it.
  std::string text() const;
  // How many corners the whole board has.
  int corner_count() const;
  // Board-frame position of corner `id` (metres).
  cv::Point3f corner_m(int id) const;
};

Board parse_board(const std::string& text);

// A ChArUco board drawn by OpenCV (CharucoBoard::draw), px_per_square pixels a square, no
// margin: what sim::texture renders and what a user prints. Throws for a chessboard.
cv::Mat draw_charuco(const Board& board, int px_per_square);

inline constexpr double kRefineWindowFraction = 0.35;
inline constexpr int kMinRefineHalfWindow_px = 2;
inline constexpr int kMaxRefineHalfWindow_px = 40;
inline constexpr int kRefineIterations = 30;
inline constexpr double kRefineEpsilon_px = 0.001;
inline constexpr double kExtensionContrastRatio = 0.5;

// Step 2's half window (px) for a view whose closest corners are smallest_spacing_px apart.
int refine_half_window_px(double smallest_spacing_px);

struct BoardDetection {
  std::string view;  // the image's name (file path or frame origin)
  cv::Size image_size;
  bool found = false;
  std::string reason;             // empty when found
  std::string detector;           // the detector that found the corners ("findChessboardCornersSB + cornerSubPix")
  int refine_half_window_px = 0;  // chessboard: step 2's half window
  std::string fitting_board;      // chessboard of the wrong size: the board text that fits; else empty
  std::vector<int> ids;
  std::vector<cv::Point2f> image_px;
  std::vector<cv::Point3f> board_m;
};

// min_corners: fewer detected corners than this is "too few corners" (a chessboard is all or
// nothing; ChArUco boards are often seen in part). Colour images are converted to grey.
BoardDetection detect_board(const Board& board, const cv::Mat& image, const std::string& view, int min_corners = 6);

}  // namespace kincal::camera

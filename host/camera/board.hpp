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
// Chessboard detection: cv::findChessboardCornersSB; if it fails, cv::findChessboardCorners +
// cv::cornerSubPix. A chessboard looks the same turned by 180 degrees unless COLS + ROWS is odd
// (then its two far corner squares differ in colour); for such boards detect_board orders the
// corners so that the square diagonally outside corner 0 is the dark one, which keeps the board
// frame the same in every view (stereo and hand-eye need that). Boards with COLS + ROWS even
// stay ambiguous: use COLS + ROWS odd, or ChArUco.
// ChArUco detection: cv::aruco::detectMarkers, refineDetectedMarkers, interpolateCornersCharuco.
//
// Failures: parse_board throws std::invalid_argument quoting the text and saying which field is
// wrong. detect_board does not throw for an image without the board: it returns found = false
// with the reason ("pattern not found", "too few corners (N, at least M)"); it throws
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

struct BoardDetection {
  std::string view;  // the image's name (file path or frame origin)
  cv::Size image_size;
  bool found = false;
  std::string reason;  // empty when found
  std::vector<int> ids;
  std::vector<cv::Point2f> image_px;
  std::vector<cv::Point3f> board_m;
};

// min_corners: fewer detected corners than this is "too few corners" (a chessboard is all or
// nothing; ChArUco boards are often seen in part). Colour images are converted to grey.
BoardDetection detect_board(const Board& board, const cv::Mat& image, const std::string& view, int min_corners = 6);

}  // namespace kincal::camera

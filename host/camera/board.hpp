// Calibration boards and their detection (issues #6, #22): a plain chessboard, a ChArUco board
// (OpenCV 4.6 contrib's cv::aruco API) or Kalibr's AprilGrid (libapriltag 3, Debian's
// libapriltag-dev), described by a one-line text the command line takes, found in an image as
// corners with their board coordinates.
//
// Text form (metres):
//   chessboard:COLSxROWS:SQUARE_M                  COLS x ROWS inner corners
//   charuco:COLSxROWS:SQUARE_M:MARKER_M[:DICT]     COLS x ROWS squares; DICT is an OpenCV
//                                                  predefined dictionary such as DICT_4X4_50
//                                                  (the default) or DICT_5X5_100
//   aprilgrid:COLSxROWS:TAG_M:SPACING              Kalibr's target (its tagCols x tagRows,
//                                                  tagSize, tagSpacing): COLS x ROWS AprilTags
//                                                  of family 36h11 with a 2-bit black border,
//                                                  TAG_M a side, SPACING * TAG_M apart (0.1 to
//                                                  1), a black square of that gap's side at
//                                                  every tag corner; tag 0 at the bottom left,
//                                                  ids along the rows, upwards (as Kalibr's
//                                                  kalibr_create_target_pdf prints it)
// Board frame: chessboard inner corner (i, j) at (i * square, j * square, 0), id j * COLS + i
// (as kincal::sim::chessboard draws it); ChArUco corners where cv::aruco::CharucoBoard puts them
// (its chessboardCorners), id as OpenCV numbers them. AprilGrid: Kalibr's corner numbering (its
// GridCalibrationTargetAprilgrid): a grid of 2 ROWS x 2 COLS tag corners, corner id R * 2 COLS + C
// with R counted upwards from tag 0's lower edge, so tag t's corners are b, b + 1, b + 2 COLS + 1
// and b + 2 COLS (lower left, lower right, upper right, upper left on the sheet), b = (t / COLS)
// * 4 COLS + (t % COLS) * 2. The frame is Kalibr's turned half a turn about x so that, like the
// other boards, x runs right, y down the sheet and z into it: the origin is the top left tag's
// upper left corner, and a corner at Kalibr's (x, y) is at (x, H - y, 0) here, H the height of
// the tags' grid.
//
// Chessboard detection, one pipeline from VGA to 4K:
//  1. find the grid: cv::findChessboardCornersSB (CALIB_CB_NORMALIZE_IMAGE | CALIB_CB_LARGER,
//     so that it grows the grid to the whole board it lies in, step 3); if it fails,
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
//     corners of a 9x6 board, a different part in different views) is refused (larger_board),
//     with fitting_board the size that fits ("chessboard:9x6:0.025") and the reason naming it
//     when it is measured. And a grid whose own outer corners are not the board's is not found.
//     Three checks:
//     - beyond each side of the grid found (by either detector), ring 1 of would-be squares
//       (placed and sampled as below) is the board's outer squares and must alternate like the
//       board's own: a parity contrast of at least kOuterSquaresContrastRatio of the interior's.
//       On OpenCV's 26 sample views at least 0.66 whichever detector served; -0.04 where
//       findChessboardCorners took left12.jpg's board edge for a tenth line of corners and
//       "found" 10x6 on the 9x6 board. Otherwise the view is not found, the reason naming the
//       side (checked before step 2);
//     - step 1's detector grew the grid beyond the given size: its size is the board's, turned
//       to the orientation that holds the given size (both wider than tall, or both not, when
//       either holds it);
//     - beyond each side of the grid found (by either detector, not grown), a ring of would-be
//       squares is placed by a homography fitted to the three nearest lines of corners; ring 1
//       is the board's outer squares, ring 2 is white margin on the board given. Each would-be
//       square is sampled in the quarter nearest the board (outer squares are often printed
//       narrower), a window of 1/8 of its side. If ring 2's squares alternate like the board's
//       own (their parity contrast reaches kExtensionContrastRatio of the interior's; on
//       OpenCV's 26 sample views: at most 0.17 for the true 9x6 board, at least 0.77 for 8x6
//       inside it), the board continues there. Its size is then measured by growing the
//       smallest grid (3x3, the same detector and flag) to the whole board, when that holds the
//       given size; when that growth stops at the very grid found (its four outer corners within
//       a quarter square), nothing continues and the board is the given one (a building's
//       windows beside OpenCV's left03.jpg pasted on it alternated like squares); else the size
//       is not named (counting rings further out by the same homography
//       named wrong sizes -- 10x4 for 9x4, 7x9 for 7x4 of the 9x6 board -- as the extrapolation
//       leaves the squares). A side whose ring 2 leaves the image cannot be judged and counts
//       as the board's edge.
//     On the 13 left sample views, every grid of 9x4, 7x4, 4x3 and 3x5 corners is refused and
//     every size named is the board's (tests/host/camera/camera_real_test.cpp); the ring check
//     alone let 4x3 pass in 9 of the 13 views.
//  4. orientation: a chessboard looks the same turned by 180 degrees unless COLS + ROWS is odd
//     (then its two far corner squares differ in colour, and turning it changes the colour of
//     every square at a grid position); for such boards the corners are ordered so that the
//     square diagonally outside corner 0 is the dark one -- told by the sign of the parity
//     contrast of all the grid's own squares, not by the two far corner squares, which read
//     within a grey level or two of each other on half-size views -- which keeps the
//     board frame the same in every view (stereo and hand-eye need that). Boards with
//     COLS + ROWS even stay ambiguous: use COLS + ROWS odd, or ChArUco.
//  5. the given size not found (or refused by ring 1): the whole board the view shows is
//     measured -- the smallest grid grown as in step 3, kept when on all four sides ring 1
//     alternates and ring 2 does not, all inside the image, and when it is not the given size --
//     and named in the reason and BoardDetection::seen_board. Not a refusal by itself (a board
//     partly hidden by a hand can look whole and smaller); seen_board_hint (intrinsics.hpp) names
//     the size most views show when a calibration has too few views. Given 10x6, 9x7 or 7x12
//     for the sample board, 10 of the 13 left views and 6 of the 13 right ones name 9x6 (6x9),
//     and no view names another size (right02.jpg's grid grows to a false 9x7, refused by ring 1).
// ChArUco detection: cv::aruco::detectMarkers, refineDetectedMarkers, interpolateCornersCharuco
// (with its own cornerSubPix: a window sized to the square would reach the markers' edges).
// No markers of the given dictionary: each ArUco family's largest dictionary is tried and the
// one that finds the most markers (kMinMarkersToJudgeLayout at least) is named in the reason and
// BoardDetection::seen_board, by the smallest dictionary of its family holding every id seen
// (a sheet of DICT_5X5_100 given with the default DICT_4X4_50: "the view shows markers of
// DICT_5X5_50", whose markers are DICT_5X5_100's first fifty).
// The whole board or nothing: interpolateCornersCharuco places corners by the given board's
// layout whatever sheet the markers come from (a 7x5 sheet given as 5x7, 6x5, 8x5 or 4x3 was
// "found" with wrong board coordinates). So first the markers' layout is checked: with
// kMinMarkersToJudgeLayout markers or more, a layout explains a marker when its id is on it and
// its four corners lie within kLayoutTolerance of the median marker side of where the
// homography from the layout to the image (RANSAC over its markers) puts them. When the given
// board does not explain every marker and another sheet of the same square and marker sizes
// (2 to kMaxCharucoSide squares a side, holding every id seen, smallest first) explains
// kMoreMarkersExplained more, the view is not found, with fitting_board that sheet and the
// reason naming it. (OpenCV 4.6 lays a sheet out with markers on the squares whose x + y is odd,
// numbered along the rows from the top, as checked against CharucoBoard::create's objPoints.)
// AprilGrid detection:
//  1. libapriltag's detector (apriltag_detector_detect: edge-based quad fit, quad_decimate 1,
//     refine_edges on, one thread, up to 2 bits corrected) with its tag36h11 family given
//     Kalibr's 2-bit border (the same codes; the data bits one bit further in), run twice: on
//     the image with its light grown by one pixel (a tag's border touches its corner squares, and
//     where the blurred touching points turn dark the detector sees one dark region, no quad),
//     then on the image itself for the ids the first pass missed. A detector and a family are
//     made for each call (about 70 ms to build the 2-bit decode table) and freed on every path
//     (RAII).
//  2. tags are dropped when their id is seen twice (ambiguous) or when they do not lie where the
//     board's grid puts them (a homography from the board to the image, RANSAC at half a tag's
//     side: a misread id or another object's tag). Tags with ids beyond the board that lie on
//     its grid extended, or tags of the board that fit no grid of COLS columns (fewer than 90 %
//     held), mean a board of another size: the view is not found, with fitting_board the size
//     whose columns hold the tags (and rows enough for the largest id) and the reason naming it.
//     Tags beyond the board off its grid are dropped. A sheet with more rows than the board given
//     and its last rows out of view cannot be told from a partial view and is not refused.
//  3. at least kMinAprilTags tags must remain (a partial view is fine): a homography needs
//     four points and the grid check needs several tags to mean anything (Kalibr's default
//     minTagsForValidObs is 4 too).
//  4. every tag corner (where the tag meets its corner square: a saddle point like a
//     chessboard's) is refined by cv::cornerSubPix as step 2 above, its smallest spacing the
//     smaller of the gap between tags and the tag's 2-bit border (the nearest other edges) for
//     the smallest tag in this view.
// Failures: parse_board throws std::invalid_argument quoting the text and saying which field is
// wrong. detect_board does not throw for an image without the board: it returns found = false
// with the reason ("pattern not found", "too few corners (N, at least M)", "too few tags", the wrong size); it throws
// std::invalid_argument for an empty image or one that is not 8-bit.
// Cost: detection is tens of milliseconds for VGA (OpenCV's detectors dominate); an AprilGrid
// about 200 ms (the decode table and two passes of about 60 ms each).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <opencv2/aruco/charuco.hpp>
#include <opencv2/core.hpp>

namespace kincal::camera {

enum class BoardKind { kChessboard, kCharuco, kAprilGrid };

// The lengths a board text may give (square, marker, tag; metres): a micrometre to ten metres.
// Beyond them OpenCV's pose solves fail on its own assertions (1e300 m and 1e-300 m did), and no
// printed board is that size.
inline constexpr double kMinBoardLength_m = 1e-6;
inline constexpr double kMaxBoardLength_m = 10;

// The text forms parse_board reads, for help texts and messages.
inline constexpr const char* kBoardForms =
    "chessboard:COLSxROWS:SQUARE_M, charuco:COLSxROWS:SQUARE_M:MARKER_M[:DICT] or aprilgrid:COLSxROWS:TAG_M:SPACING";

struct Board {
  BoardKind kind = BoardKind::kChessboard;
  int cols = 0, rows = 0;                    // chessboard: inner corners; ChArUco: squares; AprilGrid: tags
  double square_m = 0;                       // AprilGrid: a tag's side
  double spacing = 0;                        // AprilGrid only: the gap between tags over a tag's side
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

// An AprilGrid sheet as Kalibr prints it, px_per_bit pixels a tag bit (10 bits a tag side), with
// a margin of one gap around the tags (the outer corner squares lie in it): the board frame's
// origin is the upper left corner of pixel (g, g), g = aprilgrid_gap_px. The tags are drawn from
// libapriltag's tag36h11 codes (tag 0 is Kalibr's 0xd5d628584, read row by row from the top
// left, black for 0). Throws std::invalid_argument for another board, px_per_bit < 1, or a gap
// that is not a whole number of pixels at this size.
cv::Mat draw_aprilgrid(const Board& board, int px_per_bit);
int aprilgrid_gap_px(const Board& board, int px_per_bit);

// The range of a --min-corners option (detect_board's min_corners): fewer than four corners are
// no view for OpenCV (solvePnP asserts 4 points; calibrateCamera starts each view from a
// homography, which needs 4); 10000 corners is the largest board a board text gives (100x100).
inline constexpr int kMinViewCorners = 4;
inline constexpr int kMaxViewCorners = 10000;
inline constexpr const char* kMinCornersHelp =
    "fewest corners a view may have (4..10000: OpenCV's pose solve and calibration need 4 corners of a view; 10000 is "
    "the largest board's, a 100x100 chessboard)";

inline constexpr double kRefineWindowFraction = 0.35;
inline constexpr int kMinRefineHalfWindow_px = 2;
inline constexpr int kMaxRefineHalfWindow_px = 40;
inline constexpr int kRefineIterations = 30;
inline constexpr double kRefineEpsilon_px = 0.001;
inline constexpr double kExtensionContrastRatio = 0.5;
inline constexpr double kOuterSquaresContrastRatio = 0.5;
inline constexpr double kRingInsideFraction = 0.75;
inline constexpr double kSquaresAgreeing = 0.8;
inline constexpr int kMinAprilTags = 4;
inline constexpr std::size_t kMinMarkersToJudgeLayout = 4;
inline constexpr double kLayoutTolerance = 1.0 / 3.0;
inline constexpr int kMaxCharucoSide = 30;
inline constexpr int kMoreMarkersExplained = 2;

// Step 2's half window (px) for a view whose closest corners are smallest_spacing_px apart.
int refine_half_window_px(double smallest_spacing_px);

struct BoardDetection {
  std::string view;  // the image's name (file path or frame origin)
  cv::Size image_size;
  bool found = false;
  std::string reason;             // empty when found
  std::string detector;           // the detector that found the corners ("findChessboardCornersSB + cornerSubPix")
  int refine_half_window_px = 0;  // chessboard: step 2's half window
  bool larger_board = false;      // chessboard: the grid found is part of a larger board (step 3)
  std::string fitting_board;      // a board of the wrong size: the board text that fits, if measured; else empty
  std::string seen_board;         // chessboard not found: the whole board of another size the view shows (step 5)
  std::vector<int> ids;
  std::vector<cv::Point2f> image_px;
  std::vector<cv::Point3f> board_m;
};

// min_corners: fewer detected corners than this is "too few corners" (a chessboard is all or
// nothing; ChArUco boards and AprilGrids are often seen in part). Colour images are converted to grey.
BoardDetection detect_board(const Board& board, const cv::Mat& image, const std::string& view, int min_corners = 6);

// detect_board on images[i], named views[i], for every i, side by side on OpenCV's threads (a view
// of a large board takes a second or more), the results in the images' order; the first
// exception one throws is rethrown once all have stopped.
std::vector<BoardDetection> detect_boards(const Board& board, const std::vector<cv::Mat>& images,
                                          const std::vector<std::string>& views, int min_corners = 6);

}  // namespace kincal::camera

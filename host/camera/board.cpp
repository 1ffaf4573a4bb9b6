#include "host/camera/board.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <limits>
#include <memory>
#include <new>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>

#include "host/model/number_text.hpp"

namespace kincal::camera {

namespace {

struct DictionaryName {
  const char* name;
  cv::aruco::PREDEFINED_DICTIONARY_NAME id;
};
constexpr std::array<DictionaryName, 17> kDictionaries = {{
    {"DICT_4X4_50", cv::aruco::DICT_4X4_50},
    {"DICT_4X4_100", cv::aruco::DICT_4X4_100},
    {"DICT_4X4_250", cv::aruco::DICT_4X4_250},
    {"DICT_4X4_1000", cv::aruco::DICT_4X4_1000},
    {"DICT_5X5_50", cv::aruco::DICT_5X5_50},
    {"DICT_5X5_100", cv::aruco::DICT_5X5_100},
    {"DICT_5X5_250", cv::aruco::DICT_5X5_250},
    {"DICT_5X5_1000", cv::aruco::DICT_5X5_1000},
    {"DICT_6X6_50", cv::aruco::DICT_6X6_50},
    {"DICT_6X6_100", cv::aruco::DICT_6X6_100},
    {"DICT_6X6_250", cv::aruco::DICT_6X6_250},
    {"DICT_6X6_1000", cv::aruco::DICT_6X6_1000},
    {"DICT_7X7_50", cv::aruco::DICT_7X7_50},
    {"DICT_7X7_100", cv::aruco::DICT_7X7_100},
    {"DICT_7X7_250", cv::aruco::DICT_7X7_250},
    {"DICT_7X7_1000", cv::aruco::DICT_7X7_1000},
    {"DICT_ARUCO_ORIGINAL", cv::aruco::DICT_ARUCO_ORIGINAL},
}};

// Kalibr's AprilGrid tags: family 36h11 (587 codes), a 2-bit black border, 10 bits a side.
constexpr int kAprilTagCodes = 587;
constexpr int kAprilTagBorderBits = 2;
constexpr int kAprilTagSideBits = 6 + 2 * kAprilTagBorderBits;
constexpr double kGridInlierFraction = 0.9;

std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, sep)) parts.push_back(part);
  return parts;
}

[[noreturn]] void bad_board(const std::string& text, const std::string& why) {
  throw std::invalid_argument("board '" + text + "': " + why + " (expected " + kBoardForms + ")");
}

double positive_length(const std::string& text, const std::string& field, const std::string& value) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(value, &used);
  } catch (const std::exception&) {
    bad_board(text, field + " '" + value + "' is not a number");
  }
  if (used != value.size() || !std::isfinite(v)) bad_board(text, field + " '" + value + "' is not a number");
  if (!(v >= kMinBoardLength_m && v <= kMaxBoardLength_m))
    bad_board(text, field + " '" + value + "' must be " + model::shortest_number_text(kMinBoardLength_m) + " to " +
                        model::shortest_number_text(kMaxBoardLength_m) + " m");
  return v;
}

std::pair<int, int> grid(const std::string& text, const std::string& value, int minimum) {
  const std::vector<std::string> p = split(value, 'x');
  int c = 0, r = 0;
  try {
    std::size_t uc = 0, ur = 0;
    if (p.size() != 2) throw std::invalid_argument("shape");
    c = std::stoi(p[0], &uc);
    r = std::stoi(p[1], &ur);
    if (uc != p[0].size() || ur != p[1].size()) throw std::invalid_argument("shape");
  } catch (const std::exception&) {
    bad_board(text, "size '" + value + "' is not COLSxROWS");
  }
  if (c < minimum || r < minimum || c > 100 || r > 100) {
    bad_board(text, "size '" + value + "' must be " + std::to_string(minimum) + "..100 in each direction");
  }
  return {c, r};
}

// The smallest distance (px) between two neighbouring corners of the grid, diagonal neighbours
// included: the scale of the smallest square in this view.
double smallest_spacing_px(const std::vector<cv::Point2f>& corners, int cols, int rows) {
  double smallest = std::numeric_limits<double>::infinity();
  const auto at = [&](int i, int j) { return corners[static_cast<std::size_t>(j * cols + i)]; };
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < cols; ++i) {
      for (const auto& [di, dj] : {std::pair{1, 0}, std::pair{0, 1}, std::pair{1, 1}, std::pair{-1, 1}}) {
        if (i + di < 0 || i + di >= cols || j + dj >= rows) continue;
        smallest = std::min(smallest, static_cast<double>(cv::norm(at(i + di, j + dj) - at(i, j))));
      }
    }
  }
  return smallest;
}

// Grid coordinates (u, v): inner corner (i, j) at (i, j); square (a, b) spans [a, a+1] x [b, b+1]
// and is of parity (a + b) mod 2 (the same parity is the same colour on a chessboard).
int parity(int a, int b) { return ((a + b) % 2 + 2) % 2; }

// The contrast of a set of squares: mean grey level of the parity-0 squares minus that of the
// parity-1 squares, each sampled in a window of radius_px around centre_px; and the fraction of
// the squares sampled that lie on their parity's side of the midpoint between the two means
// (1 for squares that alternate throughout, about a half for clutter that does so on average).
// Squares whose window leaves the image are skipped; nullopt when fewer than two of either
// parity remain, or fewer than min_inside of all the squares (a ring mostly beyond the image
// edge is not seen clearly enough to judge: a few squares of clutter alternate by chance).
struct SquareSample {
  cv::Point2f centre_px;
  float radius_px;
  int parity;
};
struct Contrast {
  double value = 0, agreeing = 0;
};
std::optional<Contrast> contrast(const cv::Mat& grey, const std::vector<SquareSample>& squares, double min_inside = 0) {
  std::array<double, 2> sum{}, count{};
  std::vector<std::pair<int, double>> sampled;
  for (const SquareSample& s : squares) {
    const int r = std::max(1, static_cast<int>(s.radius_px));
    const cv::Rect window(static_cast<int>(std::lround(s.centre_px.x)) - r,
                          static_cast<int>(std::lround(s.centre_px.y)) - r, 2 * r + 1, 2 * r + 1);
    if ((window & cv::Rect(0, 0, grey.cols, grey.rows)) != window) continue;
    const double mean = cv::mean(grey(window))[0];
    sampled.emplace_back(s.parity, mean);
    sum[static_cast<std::size_t>(s.parity)] += mean;
    count[static_cast<std::size_t>(s.parity)] += 1;
  }
  if (count[0] < 2 || count[1] < 2) return std::nullopt;
  if (count[0] + count[1] < min_inside * static_cast<double>(squares.size())) return std::nullopt;
  const double m0 = sum[0] / count[0], m1 = sum[1] / count[1], mid = 0.5 * (m0 + m1);
  const double agreeing = static_cast<double>(std::count_if(
                              sampled.begin(), sampled.end(),
                              [&](const auto& p) { return (p.second > mid) == ((p.first == 0) == (m0 > m1)); })) /
                          static_cast<double>(sampled.size());
  return Contrast{m0 - m1, agreeing};
}

// How the would-be squares of ring `ring` (1: the board's outer squares, 2: those beyond them)
// beyond one side of the detected grid alternate, as their parity contrast over the interior's
// (see the header): about 1 where they are the board's squares, about 0 where they are margin
// or background; nullopt when that cannot be told (out of the image). The ring is placed by a
// homography fitted to the three lines of corners nearest that side, which follows the lens's
// distortion locally.
struct RingContrast {
  double ratio = 0;     // the ring's parity contrast over the interior's
  double agreeing = 0;  // Contrast::agreeing
  // Whether the ring's squares alternate like the board's own, square by square.
  bool alternates(double min_ratio) const { return ratio >= min_ratio && agreeing >= kSquaresAgreeing; }
};
std::optional<RingContrast> ring_contrast_ratio(const cv::Mat& grey, const std::vector<cv::Point2f>& corners, int cols,
                                                int rows, int side, int ring, double interior_contrast) {
  // side: 0 left (u < 0), 1 right (u > cols - 1), 2 top (v < 0), 3 bottom (v > rows - 1).
  const bool along_u = side < 2;
  const int lines = along_u ? cols : rows, across = along_u ? rows : cols;
  const bool low = side % 2 == 0;
  std::vector<cv::Point2f> grid, image;
  for (int l = 0; l < 3; ++l) {
    const int line = low ? l : lines - 1 - l;
    for (int k = 0; k < across; ++k) {
      const int i = along_u ? line : k, j = along_u ? k : line;
      grid.emplace_back(static_cast<float>(i), static_cast<float>(j));
      image.push_back(corners[static_cast<std::size_t>(j * cols + i)]);
    }
  }
  const cv::Mat h = cv::findHomography(grid, image);
  if (h.empty()) return std::nullopt;
  const auto project = [&h](float u, float v) {
    std::vector<cv::Point2f> out;
    cv::perspectiveTransform(std::vector<cv::Point2f>{{u, v}}, out, h);
    return out[0];
  };
  // The ring's squares: square index a (along the side's normal) and b = -1 .. across - 1.
  const int a = low ? -ring : lines - 2 + ring;
  std::vector<SquareSample> squares;
  for (int b = -1; b < across; ++b) {
    // The quarter of the square nearest the board: outer squares are often cut narrower.
    const float cu = static_cast<float>(a) + (low ? 0.75f : 0.25f), cv_ = static_cast<float>(b) + 0.5f;
    const float u = along_u ? cu : cv_, v = along_u ? cv_ : cu;
    const cv::Point2f centre = project(u, v);
    const float side_px = static_cast<float>(std::min(cv::norm(project(u + 0.5f, v) - project(u - 0.5f, v)),
                                                      cv::norm(project(u, v + 0.5f) - project(u, v - 0.5f))));
    squares.push_back({centre, 0.125f * side_px, parity(along_u ? a : b, along_u ? b : a)});
  }
  const std::optional<Contrast> c = contrast(grey, squares, kRingInsideFraction);
  if (!c) return std::nullopt;
  return RingContrast{c->value / interior_contrast, c->agreeing};
}

// The parity contrast of the detected grid's own squares; nullopt when it is too weak to judge
// rings by (below one grey level) or out of the image.
std::optional<double> interior_contrast(const cv::Mat& grey, const std::vector<cv::Point2f>& corners, int cols,
                                        int rows) {
  std::vector<SquareSample> interior;
  for (int b = 0; b + 1 < rows; ++b) {
    for (int a = 0; a + 1 < cols; ++a) {
      const auto at = [&](int i, int j) { return corners[static_cast<std::size_t>(j * cols + i)]; };
      const cv::Point2f centre = 0.25f * (at(a, b) + at(a + 1, b) + at(a, b + 1) + at(a + 1, b + 1));
      const float side_px =
          static_cast<float>(std::min(cv::norm(at(a + 1, b) - at(a, b)), cv::norm(at(a, b + 1) - at(a, b))));
      interior.push_back({centre, 0.25f * side_px, parity(a, b)});
    }
  }
  const std::optional<Contrast> c = contrast(grey, interior);
  if (!c || std::abs(c->value) < 1.0) return std::nullopt;
  return c->value;
}

// See the header (step 4): for COLS + ROWS odd, turning the board half a turn maps square (a, b)
// to (COLS - 2 - a, ROWS - 2 - b), which changes every square's parity, so the sign of the grid's
// own parity contrast tells the two orientations apart; the corners are put so that the parity-0
// squares (square (0, 0), between corners 0, 1, COLS and COLS + 1, and the one diagonally outside
// corner 0) are the dark ones. All the grid's squares vote: two windows on the far corner squares
// (the rule before) differed by one or two grey levels on OpenCV's right12.jpg and right14.jpg at
// half size and turned those boards half a turn.
void orient_chessboard(const Board& board, const cv::Mat& grey, std::vector<cv::Point2f>& corners) {
  if ((board.cols + board.rows) % 2 == 0) return;
  const std::optional<double> c = interior_contrast(grey, corners, board.cols, board.rows);
  if (c && *c > 0) std::reverse(corners.begin(), corners.end());
}

// The grid's sides, as the messages name them (side indices as in ring_contrast_ratio).
constexpr std::array<const char*, 4> kGridSides = {"first column", "last column", "first row", "last row"};

// The first side of the detected grid with no squares beyond it (ring 1 does not alternate like
// the board's own: the grid's outer corners there are not the board's inner corners, as when a
// detector takes the board's edge for a line of corners), or nullopt when every side that can be
// judged has them.
std::optional<int> side_without_squares(const cv::Mat& grey, const std::vector<cv::Point2f>& corners, int cols,
                                        int rows) {
  const std::optional<double> c = interior_contrast(grey, corners, cols, rows);
  if (!c) return std::nullopt;
  for (int side = 0; side < 4; ++side) {
    const std::optional<RingContrast> ring = ring_contrast_ratio(grey, corners, cols, rows, side, 1, *c);
    if (ring && ring->ratio < kOuterSquaresContrastRatio) return side;
  }
  return std::nullopt;
}

// Whether the detected grid's squares may continue beyond a side of it (the board given is part
// of a larger one): ring 2 alternates there, seen clearly (kRingInsideFraction of it inside the
// image). Only a reason to measure the board (larger_chessboard): clutter beside the board
// alternates by chance.
bool board_may_continue(const cv::Mat& grey, const std::vector<cv::Point2f>& corners, int cols, int rows) {
  const std::optional<double> c = interior_contrast(grey, corners, cols, rows);
  if (!c) return false;
  for (int side = 0; side < 4; ++side) {
    const std::optional<RingContrast> ring = ring_contrast_ratio(grey, corners, cols, rows, side, 2, *c);
    if (ring && ring->alternates(kExtensionContrastRatio)) return true;
  }
  return false;
}

constexpr int kGrowFlags = cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_LARGER;
const cv::Size kGrowSeed(3, 3);  // the smallest grid a larger board is grown from (step 3)

// The size of the grid cv::findChessboardCornersSB found with CALIB_CB_LARGER (its meta array's
// columns and rows), in an orientation that holds `pattern`: the detector numbers the grid its
// own way round, so the orientation like the given size's (both wider than tall, or not) when it
// holds the given grid, else the other; `pattern` itself when neither holds it.
cv::Size whole_chessboard(cv::Size found, cv::Size pattern) {
  const auto holds = [&pattern](cv::Size s) { return s.width >= pattern.width && s.height >= pattern.height; };
  const cv::Size turned(found.height, found.width);
  const bool like_given = (found.width >= found.height) == (pattern.width >= pattern.height);
  const cv::Size first = like_given ? found : turned, second = like_given ? turned : found;
  return holds(first) ? first : holds(second) ? second : pattern;
}

// Whether a grid of cols x rows corners is a whole board, seen clearly: beyond each of its four
// sides ring 1 alternates (the board's outer squares: its outer corners are the board's) and
// ring 2 does not (margin), every ring inside the image.
bool shows_whole_board(const cv::Mat& grey, const std::vector<cv::Point2f>& corners, int cols, int rows) {
  if (cols < 2 || rows < 2 || corners.size() != static_cast<std::size_t>(cols * rows)) return false;
  const std::optional<double> c = interior_contrast(grey, corners, cols, rows);
  if (!c) return false;
  for (int side = 0; side < 4; ++side) {
    const std::optional<RingContrast> outer = ring_contrast_ratio(grey, corners, cols, rows, side, 1, *c);
    const std::optional<RingContrast> beyond = ring_contrast_ratio(grey, corners, cols, rows, side, 2, *c);
    if (!outer || !beyond || !outer->alternates(kOuterSquaresContrastRatio) || beyond->ratio >= kExtensionContrastRatio)
      return false;
  }
  return true;
}

// A grid cv::findChessboardCornersSB grew (CALIB_CB_LARGER) to cols x rows: its size turned like
// `pattern` (whole_chessboard) when it is a whole board seen clearly (shows_whole_board), holds
// `pattern`, is larger, and the same detector finds that size without growing (the size named to
// the user must be one kincal then finds); nullopt otherwise: the growth ran into the board's
// edge, clutter, or out of the image.
std::optional<cv::Size> confirmed_larger(const cv::Mat& grey, const std::vector<cv::Point2f>& grown, int cols, int rows,
                                         cv::Size pattern) {
  const cv::Size whole = whole_chessboard(cv::Size(cols, rows), pattern);
  if (whole == pattern || !shows_whole_board(grey, grown, cols, rows)) return std::nullopt;
  std::vector<cv::Point2f> again;
  if (!cv::findChessboardCornersSB(grey, whole, again, cv::CALIB_CB_NORMALIZE_IMAGE)) return std::nullopt;
  return whole;
}

// Whether two grids of `size` corners (numbered each its own way round, either perhaps turned
// about its diagonal: `b_turned` gives b's size as rows x cols) are the same grid in the image:
// their four outer corners coincide, as a set, within a quarter of the smallest square.
bool same_grid(const std::vector<cv::Point2f>& a, const std::vector<cv::Point2f>& b, cv::Size size, bool b_turned) {
  const auto outer = [](const std::vector<cv::Point2f>& g, cv::Size s) {
    const auto at = [&](int i, int j) { return g[static_cast<std::size_t>(j * s.width + i)]; };
    return std::array<cv::Point2f, 4>{at(0, 0), at(s.width - 1, 0), at(0, s.height - 1), at(s.width - 1, s.height - 1)};
  };
  const double tolerance_px = 0.25 * smallest_spacing_px(a, size.width, size.height);
  const std::array<cv::Point2f, 4> oa = outer(a, size),
                                   ob = outer(b, b_turned ? cv::Size(size.height, size.width) : size);
  return std::all_of(oa.begin(), oa.end(), [&](cv::Point2f p) {
    return std::any_of(ob.begin(), ob.end(), [&](cv::Point2f q) { return cv::norm(p - q) <= tolerance_px; });
  });
}

// The larger board a grid of the given size lies in (step 3): nullopt when its squares do not
// clearly continue (board_may_continue), or when the smallest grid, grown, stops at this very
// grid (the detector's own growth finds no squares beyond it: what alternated beyond it is
// texture, as the windows of a building beside OpenCV's left03.jpg did); else the grown grid's
// size when that is confirmed (confirmed_larger), or `pattern` itself when the size cannot be
// measured.
std::optional<cv::Size> larger_chessboard(const cv::Mat& grey, const std::vector<cv::Point2f>& corners,
                                          cv::Size pattern) {
  if (!board_may_continue(grey, corners, pattern.width, pattern.height)) return std::nullopt;
  std::vector<cv::Point2f> seed;
  cv::Mat meta;
  if (!cv::findChessboardCornersSB(grey, kGrowSeed, seed, kGrowFlags, meta)) return pattern;
  const cv::Size grown(meta.cols, meta.rows), turned(pattern.height, pattern.width);
  if ((grown == pattern || grown == turned) && same_grid(corners, seed, pattern, grown != pattern)) return std::nullopt;
  return confirmed_larger(grey, seed, meta.cols, meta.rows, pattern).value_or(pattern);
}

// The whole chessboard a view shows when the given size was not found in it (see the header): the
// grid grown from the smallest one, when it shows a whole board (shows_whole_board) and is not
// `pattern` (in either orientation); turned like `pattern` (both wider than tall, or not).
// nullopt otherwise.
std::optional<cv::Size> seen_whole_chessboard(const cv::Mat& grey, cv::Size pattern) {
  std::vector<cv::Point2f> corners;
  cv::Mat meta;
  if (!cv::findChessboardCornersSB(grey, kGrowSeed, corners, kGrowFlags, meta)) return std::nullopt;
  const int cols = meta.cols, rows = meta.rows;
  if (!shows_whole_board(grey, corners, cols, rows)) return std::nullopt;
  const cv::Size seen =
      (cols >= rows) == (pattern.width >= pattern.height) ? cv::Size(cols, rows) : cv::Size(rows, cols);
  if (seen == pattern || seen == cv::Size(pattern.height, pattern.width)) return std::nullopt;
  return seen;
}

// The ArUco dictionary a view's markers come from when none are of the given one (see the
// header): each family's largest dictionary (4X4 to 7X7 with 1000 markers, ARUCO_ORIGINAL) is
// tried, the one finding the most markers (at least kMinMarkersToJudgeLayout) kept, and named by
// the smallest dictionary of its family that holds the largest id seen (a family's smaller
// dictionaries are its larger one's first markers). nullopt when none finds enough.
std::optional<std::string> seen_dictionary(const cv::Mat& grey) {
  struct Family {
    std::size_t first, last;  // indices into kDictionaries, smallest to largest
  };
  constexpr std::array<Family, 5> kFamilies = {{{0, 3}, {4, 7}, {8, 11}, {12, 15}, {16, 16}}};
  std::size_t most = 0;
  std::string name;
  for (const Family& f : kFamilies) {
    std::vector<std::vector<cv::Point2f>> corners;
    std::vector<int> ids;
    cv::aruco::detectMarkers(grey, cv::aruco::getPredefinedDictionary(kDictionaries[f.last].id), corners, ids);
    if (ids.size() < kMinMarkersToJudgeLayout || ids.size() <= most) continue;
    most = ids.size();
    const int largest_id = *std::max_element(ids.begin(), ids.end());
    std::size_t k = f.first;
    while (k < f.last && cv::aruco::getPredefinedDictionary(kDictionaries[k].id)->bytesList.rows <= largest_id) ++k;
    name = kDictionaries[k].name;
  }
  if (name.empty()) return std::nullopt;
  return name;
}

// A ChArUco sheet of cols x rows squares as cv::aruco::CharucoBoard lays it out (OpenCV 4.6):
// markers on the squares whose x + y is odd, numbered along the rows from the top; each
// marker's four corners (in squares; clockwise from its top left) at its square's centre
// +- marker_over_square / 2. Index: the marker's id.
std::vector<std::array<cv::Point2f, 4>> charuco_layout(int cols, int rows, double marker_over_square) {
  const float m = static_cast<float>(marker_over_square), margin = 0.5f * (1.0f - m);
  std::vector<std::array<cv::Point2f, 4>> markers;
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x) {
      if ((x + y) % 2 == 0) continue;
      const cv::Point2f tl(static_cast<float>(x) + margin, static_cast<float>(y) + margin);
      markers.push_back({tl, tl + cv::Point2f(m, 0), tl + cv::Point2f(m, m), tl + cv::Point2f(0, m)});
    }
  return markers;
}

// How many detected markers a layout explains: markers whose id it holds and whose four image
// corners lie within tolerance_px of where the homography from the layout's corners to the
// image corners (RANSAC over every marker it holds) puts them. 0 when it holds fewer than 4.
int markers_explained(const std::vector<std::array<cv::Point2f, 4>>& layout,
                      const std::vector<std::vector<cv::Point2f>>& marker_corners, const std::vector<int>& ids,
                      double tolerance_px) {
  std::vector<cv::Point2f> from, to;
  for (std::size_t k = 0; k < ids.size(); ++k) {
    if (ids[k] < 0 || ids[k] >= static_cast<int>(layout.size())) continue;
    for (int c = 0; c < 4; ++c) {
      from.push_back(layout[static_cast<std::size_t>(ids[k])][static_cast<std::size_t>(c)]);
      to.push_back(marker_corners[k][static_cast<std::size_t>(c)]);
    }
  }
  if (from.size() < 16) return 0;
  const cv::Mat h = cv::findHomography(from, to, cv::RANSAC, tolerance_px);
  if (h.empty()) return 0;
  std::vector<cv::Point2f> placed;
  cv::perspectiveTransform(from, placed, h);
  int explained = 0;
  for (std::size_t i = 0; i < placed.size(); i += 4) {
    bool all = true;
    for (std::size_t c = 0; c < 4; ++c) all = all && cv::norm(placed[i + c] - to[i + c]) <= tolerance_px;
    explained += all ? 1 : 0;
  }
  return explained;
}

// The ChArUco sheet (squares) the detected markers lie on, when it is not the board given (see
// the header); nullopt when the given board explains the markers as well as any other, or too
// few markers were seen to judge.
std::optional<cv::Size> fitting_charuco(const Board& board, const std::vector<std::vector<cv::Point2f>>& marker_corners,
                                        const std::vector<int>& ids) {
  if (ids.size() < kMinMarkersToJudgeLayout) return std::nullopt;
  std::vector<double> sides;
  for (const std::vector<cv::Point2f>& m : marker_corners)
    sides.push_back(0.25 *
                    (cv::norm(m[1] - m[0]) + cv::norm(m[2] - m[1]) + cv::norm(m[3] - m[2]) + cv::norm(m[0] - m[3])));
  std::nth_element(sides.begin(), sides.begin() + static_cast<std::ptrdiff_t>(sides.size() / 2), sides.end());
  const double tolerance_px = kLayoutTolerance * sides[sides.size() / 2];
  const double marker_over_square = board.marker_m / board.square_m;
  const int given =
      markers_explained(charuco_layout(board.cols, board.rows, marker_over_square), marker_corners, ids, tolerance_px);
  if (given == static_cast<int>(ids.size())) return std::nullopt;
  const int largest_id = *std::max_element(ids.begin(), ids.end());
  const int dictionary_size = board.charuco->dictionary->bytesList.rows;
  int best = given, best_cols = board.cols, best_rows = board.rows;
  for (int area = 4; area <= kMaxCharucoSide * kMaxCharucoSide; ++area)  // smaller sheets first
    for (int cols = 2; cols <= kMaxCharucoSide; ++cols) {
      const int rows = area / cols;
      if (rows < 2 || rows > kMaxCharucoSide || cols * rows != area || cols * rows / 2 <= largest_id ||
          cols * rows / 2 > dictionary_size)
        continue;
      const int n =
          markers_explained(charuco_layout(cols, rows, marker_over_square), marker_corners, ids, tolerance_px);
      if (n > best) {
        best = n;
        best_cols = cols;
        best_rows = rows;
      }
    }
  if (best < given + kMoreMarkersExplained) return std::nullopt;
  return cv::Size(best_cols, best_rows);
}

// libapriltag's objects, each freed by its own function on every path.
struct FamilyFree {
  void operator()(apriltag_family_t* f) const { tag36h11_destroy(f); }
};
struct DetectorFree {
  void operator()(apriltag_detector_t* d) const { apriltag_detector_destroy(d); }
};
struct DetectionsFree {
  void operator()(zarray_t* z) const { apriltag_detections_destroy(z); }
};
using Family = std::unique_ptr<apriltag_family_t, FamilyFree>;
using Detector = std::unique_ptr<apriltag_detector_t, DetectorFree>;
using Detections = std::unique_ptr<zarray_t, DetectionsFree>;

// libapriltag's tag36h11 with Kalibr's 2-bit border. tag36h11 puts its 6 x 6 data bits at 1..6
// inside a 1-bit black border (width_at_border 8, with the white ring 10); Kalibr's tags carry
// the same codes in the same places with a 2-bit border, so the bits move one further in, the
// black square is 10 bits across and 12 with the white ring. The arrays changed are the
// family's own (tag36h11_destroy frees them).
Family kalibr_family() {
  Family family(tag36h11_create());
  if (!family) throw std::bad_alloc();
  family->width_at_border = kAprilTagSideBits;
  family->total_width = kAprilTagSideBits + 2;
  for (std::uint32_t i = 0; i < family->nbits; ++i) {
    family->bit_x[i] += 1;
    family->bit_y[i] += 1;
  }
  return family;
}

// One decoded tag: its id and its corners in libapriltag's order, which is the tag's lower left,
// lower right, upper right and upper left as it stands on the sheet.
struct Tag {
  int id = 0;
  std::array<cv::Point2f, 4> corner_px;
};

// Two passes, the first on the image with its light grown by one pixel (a 3x3 cross): a tag's
// border touches its corner squares, and where the blurred touching points turn dark the tag
// and its squares are one dark region, no quad (on rendered 6x5 sheets at 4 px a bit the image
// itself gives 0-12 of 30 tags, the grown one 27-30). Growing by two pixels erases 4-pixel
// bits. The second pass, on the image itself, adds the ids the first missed.
std::vector<Tag> find_tags(const cv::Mat& grey) {
  const Family family = kalibr_family();
  const Detector detector(apriltag_detector_create());
  if (!detector) throw std::bad_alloc();
  detector->nthreads = 1;
  detector->quad_decimate = 1;  // quads found at full resolution: these tags are small
  detector->refine_edges = true;
  apriltag_detector_add_family_bits(detector.get(), family.get(), 2);
  std::vector<Tag> tags;
  for (const int grow_px : {1, 0}) {
    // The detector may write into the image it is given (its blur): give it a copy.
    cv::Mat pass;
    if (grow_px > 0) {
      cv::dilate(grey, pass, cv::getStructuringElement(cv::MORPH_CROSS, cv::Size(3, 3)), cv::Point(-1, -1), grow_px);
    } else {
      pass = grey.clone();
    }
    image_u8_t image{pass.cols, pass.rows, static_cast<std::int32_t>(pass.step[0]), pass.data};
    const Detections found(apriltag_detector_detect(detector.get(), &image));
    if (!found) throw std::bad_alloc();
    const std::size_t earlier = tags.size();
    for (int i = 0; i < zarray_size(found.get()); ++i) {
      apriltag_detection_t* d = nullptr;
      zarray_get(found.get(), i, &d);
      const auto end = tags.begin() + static_cast<std::ptrdiff_t>(earlier);
      if (std::any_of(tags.begin(), end, [&](const Tag& t) { return t.id == d->id; })) continue;
      Tag t;
      t.id = d->id;
      for (std::size_t k = 0; k < 4; ++k)
        t.corner_px[k] = cv::Point2f(static_cast<float>(d->p[k][0]), static_cast<float>(d->p[k][1]));
      tags.push_back(t);
    }
  }
  return tags;
}

// Tag `tag`'s corner ids in libapriltag's corner order on a grid of `cols` tags: Kalibr's
// numbering (see the header).
std::array<int, 4> tag_corner_ids(int tag, int cols) {
  const int row_corners = 2 * cols, lower_left = (tag / cols) * 2 * row_corners + (tag % cols) * 2;
  return {lower_left, lower_left + 1, lower_left + row_corners + 1, lower_left + row_corners};
}

// Which tags lie where a grid of `cols` columns (and rows enough for every id) puts them: a
// homography from the board to the image, RANSAC at half the median tag side, holds all four of
// their corners. All held for fewer than two tags (nothing to compare).
std::vector<bool> on_grid(const Board& board, int cols, const std::vector<Tag>& tags, double tag_side_px) {
  if (tags.size() < 2) return std::vector<bool>(tags.size(), true);
  Board shape = board;
  shape.cols = cols;
  shape.rows = 0;
  for (const Tag& t : tags) shape.rows = std::max(shape.rows, t.id / cols + 1);
  std::vector<cv::Point2f> board_xy, image;
  for (const Tag& t : tags) {
    const std::array<int, 4> ids = tag_corner_ids(t.id, cols);
    for (std::size_t k = 0; k < 4; ++k) {
      const cv::Point3f p = shape.corner_m(ids[k]);
      board_xy.emplace_back(p.x, p.y);
      image.push_back(t.corner_px[k]);
    }
  }
  cv::Mat inliers;
  const cv::Mat h = cv::findHomography(board_xy, image, cv::RANSAC, 0.5 * tag_side_px, inliers);
  std::vector<bool> held(tags.size(), false);
  if (h.empty()) return held;
  for (std::size_t i = 0; i < tags.size(); ++i) {
    bool all = true;
    for (int k = 0; k < 4; ++k) all = all && inliers.at<std::uint8_t>(static_cast<int>(4 * i) + k) != 0;
    held[i] = all;
  }
  return held;
}

double held_fraction(const std::vector<bool>& held) {
  if (held.empty()) return 0.0;
  return static_cast<double>(std::count(held.begin(), held.end(), true)) / static_cast<double>(held.size());
}

double smallest_side_px(const Tag& t) {
  double side = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < 4; ++k)
    side = std::min(side, static_cast<double>(cv::norm(t.corner_px[(k + 1) % 4] - t.corner_px[k])));
  return side;
}

// The AprilGrid size whose columns hold the most of these tags (the fewest columns among equals),
// with rows enough for the largest id and at least the board's: empty when none holds
// kGridInlierFraction of them.
std::string fitting_aprilgrid(const Board& board, const std::vector<Tag>& tags, double tag_side_px) {
  int best_cols = 0, largest = 0;
  double best = 0;
  for (const Tag& t : tags) largest = std::max(largest, t.id);
  for (int cols = 2; cols <= 100; ++cols) {
    const double f = held_fraction(on_grid(board, cols, tags, tag_side_px));
    if (f > best + 1e-9) {
      best = f;
      best_cols = cols;
    }
  }
  if (best < kGridInlierFraction) return "";
  Board fits = board;
  fits.cols = best_cols;
  fits.rows = std::max(board.rows, largest / best_cols + 1);
  return fits.text();
}

// AprilGrid detection (see the header): fills d.ids and corners, or d.reason (and
// d.fitting_board) and returns false.
bool detect_aprilgrid(const Board& board, const cv::Mat& grey, BoardDetection& d, std::vector<cv::Point2f>& corners) {
  const std::vector<Tag> tags = find_tags(grey);
  if (tags.empty()) {
    d.reason = "pattern not found (no AprilTags of family 36h11 with a 2-bit border)";
    return false;
  }
  // An id seen twice is ambiguous: drop every copy.
  std::vector<Tag> once, beyond;
  for (const Tag& t : tags) {
    const bool twice = std::count_if(tags.begin(), tags.end(), [&](const Tag& o) { return o.id == t.id; }) > 1;
    if (twice) continue;
    (t.id < board.cols * board.rows ? once : beyond).push_back(t);
  }
  std::vector<double> sides;
  for (const Tag& t : tags) sides.push_back(smallest_side_px(t));
  std::nth_element(sides.begin(), sides.begin() + static_cast<std::ptrdiff_t>(sides.size() / 2), sides.end());
  const double median_side_px = sides[sides.size() / 2];
  const std::vector<bool> held = on_grid(board, board.cols, once, median_side_px);
  // Tags beyond the board that lie on its grid extended: the sheet has more rows.
  std::vector<Tag> extended = once;
  extended.insert(extended.end(), beyond.begin(), beyond.end());
  const std::vector<bool> extended_held = on_grid(board, board.cols, extended, median_side_px);
  int beyond_on_grid = 0;
  for (std::size_t i = once.size(); i < extended.size(); ++i) beyond_on_grid += extended_held[i] ? 1 : 0;
  const bool other_columns = once.size() >= 2 && held_fraction(held) < kGridInlierFraction;
  if (other_columns || (!beyond.empty() && 2 * beyond_on_grid > static_cast<int>(beyond.size()))) {
    const std::string size = std::to_string(board.cols) + "x" + std::to_string(board.rows);
    d.reason = other_columns ? "the tags do not lie on a grid of " + std::to_string(board.cols) + " columns"
                             : std::to_string(beyond_on_grid) + " tag(s) with ids beyond the " + size + " board's " +
                                   std::to_string(board.cols * board.rows) + " lie on its grid";
    d.fitting_board = fitting_aprilgrid(board, extended, median_side_px);
    if (!d.fitting_board.empty() && d.fitting_board != board.text()) {
      d.reason += ": the board is " + d.fitting_board + ", give --board " + d.fitting_board;
    } else {
      d.fitting_board.clear();
    }
    return false;
  }
  std::vector<Tag> kept;
  for (std::size_t i = 0; i < once.size(); ++i)
    if (held[i]) kept.push_back(once[i]);
  const std::size_t dropped = tags.size() - kept.size();
  if (static_cast<int>(kept.size()) < kMinAprilTags) {
    d.reason = "too few tags (" + std::to_string(kept.size()) + " of the board, at least " +
               std::to_string(kMinAprilTags) + ")";
    return false;
  }
  // The nearest other edges to a tag corner: the next corner of its corner square (the gap) and
  // the inner edge of the tag's 2-bit border.
  double smallest_px = std::numeric_limits<double>::infinity();
  for (const Tag& t : kept) {
    smallest_px = std::min(smallest_px, smallest_side_px(t));
    const std::array<int, 4> ids = tag_corner_ids(t.id, board.cols);
    for (std::size_t k = 0; k < 4; ++k) {
      d.ids.push_back(ids[k]);
      corners.push_back(t.corner_px[k]);
    }
  }
  const double border_fraction = static_cast<double>(kAprilTagBorderBits) / kAprilTagSideBits;
  d.refine_half_window_px = refine_half_window_px(smallest_px * std::min(board.spacing, border_fraction));
  cv::cornerSubPix(
      grey, corners, cv::Size(d.refine_half_window_px, d.refine_half_window_px), cv::Size(-1, -1),
      cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, kRefineIterations, kRefineEpsilon_px));
  const std::string window = std::to_string(2 * d.refine_half_window_px + 1);
  d.detector = "apriltag_detector_detect (tag36h11, 2-bit border) + cornerSubPix " + window + "x" + window;
  if (dropped > 0) d.detector += " (" + std::to_string(dropped) + " tag(s) dropped: off the grid or seen twice)";
  return true;
}

}  // namespace

std::string Board::text() const {
  std::ostringstream out;
  out << (kind == BoardKind::kChessboard ? "chessboard:"
          : kind == BoardKind::kCharuco  ? "charuco:"
                                         : "aprilgrid:")
      << cols << 'x' << rows << ':' << square_m;
  if (kind == BoardKind::kCharuco) out << ':' << marker_m << ':' << dictionary;
  if (kind == BoardKind::kAprilGrid) out << ':' << spacing;
  return out.str();
}

int refine_half_window_px(double smallest_spacing_px) {
  if (!std::isfinite(smallest_spacing_px)) return kMinRefineHalfWindow_px;
  return std::clamp(static_cast<int>(kRefineWindowFraction * smallest_spacing_px), kMinRefineHalfWindow_px,
                    kMaxRefineHalfWindow_px);
}

int Board::corner_count() const {
  switch (kind) {
    case BoardKind::kChessboard:
      return cols * rows;
    case BoardKind::kCharuco:
      return (cols - 1) * (rows - 1);
    case BoardKind::kAprilGrid:
      return 4 * cols * rows;
  }
  return 0;
}

cv::Point3f Board::corner_m(int id) const {
  if (id < 0 || id >= corner_count()) throw std::out_of_range("board corner id " + std::to_string(id));
  if (kind == BoardKind::kCharuco) return charuco->chessboardCorners[static_cast<std::size_t>(id)];
  if (kind == BoardKind::kAprilGrid) {
    // Kalibr's grid of tag corners: column C, row R counted upwards, two a tag each way.
    const int c = id % (2 * cols), r = id / (2 * cols);
    const double pitch_m = (1 + spacing) * square_m, height_m = rows * square_m + (rows - 1) * spacing * square_m;
    const double kalibr_y_m = (r / 2) * pitch_m + (r % 2) * square_m;
    return {static_cast<float>((c / 2) * pitch_m + (c % 2) * square_m), static_cast<float>(height_m - kalibr_y_m),
            0.0f};
  }
  return {static_cast<float>((id % cols) * square_m), static_cast<float>((id / cols) * square_m), 0.0f};
}

Board parse_board(const std::string& text) {
  const std::vector<std::string> f = split(text, ':');
  Board b;
  if (f.size() == 3 && f[0] == "chessboard") {
    b.kind = BoardKind::kChessboard;
    std::tie(b.cols, b.rows) = grid(text, f[1], 3);  // OpenCV's detector needs 3 or more each way
    b.square_m = positive_length(text, "square size", f[2]);
    return b;
  }
  if ((f.size() == 4 || f.size() == 5) && f[0] == "charuco") {
    b.kind = BoardKind::kCharuco;
    std::tie(b.cols, b.rows) = grid(text, f[1], 3);
    b.square_m = positive_length(text, "square size", f[2]);
    b.marker_m = positive_length(text, "marker size", f[3]);
    if (b.marker_m >= b.square_m) bad_board(text, "the marker must be smaller than the square");
    b.dictionary = f.size() == 5 ? f[4] : "DICT_4X4_50";
    const auto d = std::find_if(kDictionaries.begin(), kDictionaries.end(),
                                [&](const DictionaryName& n) { return b.dictionary == n.name; });
    if (d == kDictionaries.end()) bad_board(text, "unknown dictionary '" + b.dictionary + "'");
    const cv::Ptr<cv::aruco::Dictionary> dictionary = cv::aruco::getPredefinedDictionary(d->id);
    const int markers = b.cols * b.rows / 2;
    if (markers > dictionary->bytesList.rows) {
      bad_board(text, "the board needs " + std::to_string(markers) + " markers, " + b.dictionary + " has " +
                          std::to_string(dictionary->bytesList.rows));
    }
    b.charuco = cv::aruco::CharucoBoard::create(b.cols, b.rows, static_cast<float>(b.square_m),
                                                static_cast<float>(b.marker_m), dictionary);
    return b;
  }
  if (f.size() == 4 && f[0] == "aprilgrid") {
    b.kind = BoardKind::kAprilGrid;
    std::tie(b.cols, b.rows) = grid(text, f[1], 2);
    b.square_m = positive_length(text, "tag size", f[2]);
    std::size_t used = 0;
    try {
      b.spacing = std::stod(f[3], &used);
    } catch (const std::exception&) {
      bad_board(text, "spacing '" + f[3] + "' is not a number");
    }
    if (used != f[3].size() || !(b.spacing >= 0.1 && b.spacing <= 1.0))
      bad_board(text, "spacing '" + f[3] + "' must be 0.1 to 1 (the gap between tags over a tag's side)");
    if (b.cols * b.rows > kAprilTagCodes) {
      bad_board(text, "the board needs " + std::to_string(b.cols * b.rows) + " tags, family 36h11 has " +
                          std::to_string(kAprilTagCodes));
    }
    return b;
  }
  if (f.empty() || (f[0] != "chessboard" && f[0] != "charuco" && f[0] != "aprilgrid"))
    bad_board(text, "unknown board type");
  bad_board(text, "wrong number of fields");
}

cv::Mat draw_charuco(const Board& board, int px_per_square) {
  if (board.kind != BoardKind::kCharuco)
    throw std::invalid_argument("draw_charuco: " + board.text() + " is not ChArUco");
  if (px_per_square < 8) throw std::invalid_argument("draw_charuco: px_per_square must be >= 8");
  cv::Mat image;
  board.charuco->draw(cv::Size(board.cols * px_per_square, board.rows * px_per_square), image, 0, 1);
  return image;
}

int aprilgrid_gap_px(const Board& board, int px_per_bit) {
  if (board.kind != BoardKind::kAprilGrid)
    throw std::invalid_argument("draw_aprilgrid: " + board.text() + " is not an AprilGrid");
  if (px_per_bit < 1) throw std::invalid_argument("draw_aprilgrid: px_per_bit must be >= 1");
  const double gap = board.spacing * kAprilTagSideBits * px_per_bit;
  if (std::abs(gap - std::round(gap)) > 1e-6) {
    throw std::invalid_argument("draw_aprilgrid: a gap of " + std::to_string(gap) + " px at " +
                                std::to_string(px_per_bit) + " px a bit is not whole pixels");
  }
  return static_cast<int>(std::lround(gap));
}

cv::Mat draw_aprilgrid(const Board& board, int px_per_bit) {
  const int gap = aprilgrid_gap_px(board, px_per_bit), tag = kAprilTagSideBits * px_per_bit, pitch = tag + gap;
  cv::Mat sheet(board.rows * pitch + gap, board.cols * pitch + gap, CV_8UC1, cv::Scalar(255));
  const Family family = kalibr_family();
  for (int id = 0; id < board.cols * board.rows; ++id) {
    // Tag id at column id % cols, row id / cols counted upwards from the sheet's bottom.
    const cv::Point origin(gap + (id % board.cols) * pitch, gap + (board.rows - 1 - id / board.cols) * pitch);
    sheet(cv::Rect(origin, cv::Size(tag, tag))).setTo(0);
    const std::uint64_t code = family->codes[id];
    for (std::uint32_t i = 0; i < family->nbits; ++i) {
      if (((code >> (family->nbits - 1 - i)) & 1U) == 0) continue;  // as apriltag_to_image draws it: 1 is white
      const cv::Point bit(static_cast<int>(family->bit_x[i]), static_cast<int>(family->bit_y[i]));
      sheet(cv::Rect(origin + bit * px_per_bit, cv::Size(px_per_bit, px_per_bit))).setTo(255);
    }
  }
  for (int r = 0; r <= board.rows; ++r)
    for (int c = 0; c <= board.cols; ++c) sheet(cv::Rect(c * pitch, r * pitch, gap, gap)).setTo(0);
  return sheet;
}

std::vector<BoardDetection> detect_boards(const Board& board, const std::vector<cv::Mat>& images,
                                          const std::vector<std::string>& views, int min_corners) {
  if (images.size() != views.size()) throw std::invalid_argument("detect_boards: one view name per image");
  std::vector<BoardDetection> out(images.size());
  std::vector<std::exception_ptr> failure(images.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(images.size())), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      const auto k = static_cast<std::size_t>(i);
      try {
        out[k] = detect_board(board, images[k], views[k], min_corners);
      } catch (...) {
        failure[k] = std::current_exception();
      }
    }
  });
  for (const std::exception_ptr& f : failure)
    if (f) std::rethrow_exception(f);
  return out;
}

BoardDetection detect_board(const Board& board, const cv::Mat& image, const std::string& view, int min_corners) {
  if (image.empty()) throw std::invalid_argument(view + ": empty image");
  if (image.depth() != CV_8U) throw std::invalid_argument(view + ": not an 8-bit image");
  cv::Mat grey;
  if (image.channels() == 1) {
    grey = image;
  } else {
    cv::cvtColor(image, grey, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  }
  BoardDetection d;
  d.view = view;
  d.image_size = grey.size();
  std::vector<cv::Point2f> corners;
  // Squares of fewer than 4 pixels are not detected, and OpenCV's chessboard detectors assert on
  // images smaller than their windows.
  const int min_side_px = 4 * (std::max(board.cols, board.rows) + 1);
  if (grey.cols < min_side_px || grey.rows < min_side_px) {
    d.reason = "image " + std::to_string(grey.cols) + "x" + std::to_string(grey.rows) + " too small for the " +
               board.text() + " board (at least " + std::to_string(min_side_px) + " px a side)";
    return d;
  }
  if (board.kind == BoardKind::kChessboard) {
    const cv::Size pattern(board.cols, board.rows);
    const std::string given = std::to_string(board.cols) + "x" + std::to_string(board.rows);
    // A larger board found (step 3): refused, naming the whole board when it was measured.
    const auto refuse_larger = [&](cv::Size whole) {
      d.larger_board = true;
      if (whole == pattern) {
        d.reason = "the board is larger than " + given +
                   " (its squares continue beyond the corners found; its size could not be measured in this view)";
        return d;
      }
      Board larger = board;
      larger.cols = whole.width;
      larger.rows = whole.height;
      d.fitting_board = larger.text();
      d.reason = "the board has " + std::to_string(whole.width) + "x" + std::to_string(whole.height) +
                 " inner corners, not " + given + " (its squares continue beyond the corners found): give --board " +
                 d.fitting_board;
      return d;
    };
    // The given size not found: the whole board of another size the view shows, named (step 5).
    const auto note_seen_board = [&] {
      const std::optional<cv::Size> seen = seen_whole_chessboard(grey, pattern);
      if (!seen) return;
      Board other = board;
      other.cols = seen->width;
      other.rows = seen->height;
      d.seen_board = other.text();
      d.reason += "; the view shows a whole chessboard of " + std::to_string(seen->width) + "x" +
                  std::to_string(seen->height) + " inner corners";
    };
    cv::Mat meta;
    bool found = cv::findChessboardCornersSB(grey, pattern, corners, kGrowFlags, meta);
    if (found && cv::Size(meta.cols, meta.rows) != pattern) {
      // Grown beyond the given size: a larger board only when the grown grid shows it clearly;
      // else the growth ran into the board's edge or clutter, and the given size is looked for alone.
      if (const std::optional<cv::Size> whole = confirmed_larger(grey, corners, meta.cols, meta.rows, pattern))
        return refuse_larger(*whole);
      found = cv::findChessboardCornersSB(grey, pattern, corners, cv::CALIB_CB_NORMALIZE_IMAGE);
    }
    if (found) {
      d.detector = "findChessboardCornersSB";
    } else if (cv::findChessboardCorners(grey, pattern, corners,
                                         cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE)) {
      d.detector = "findChessboardCorners";
    } else {
      d.reason = "pattern not found";
      note_seen_board();
      return d;
    }
    if (const std::optional<int> side = side_without_squares(grey, corners, board.cols, board.rows)) {
      d.reason = "pattern not found: the " + given + " grid " + d.detector + " found has no squares beyond its " +
                 kGridSides[static_cast<std::size_t>(*side)] + " (its corners there are not the board's)";
      note_seen_board();
      return d;
    }
    d.refine_half_window_px = refine_half_window_px(smallest_spacing_px(corners, board.cols, board.rows));
    cv::cornerSubPix(
        grey, corners, cv::Size(d.refine_half_window_px, d.refine_half_window_px), cv::Size(-1, -1),
        cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, kRefineIterations, kRefineEpsilon_px));
    const std::string window = std::to_string(2 * d.refine_half_window_px + 1);
    d.detector += " + cornerSubPix " + window + "x" + window;
    if (const std::optional<cv::Size> whole = larger_chessboard(grey, corners, pattern)) return refuse_larger(*whole);
    orient_chessboard(board, grey, corners);
    for (int id = 0; id < board.corner_count(); ++id) d.ids.push_back(id);
  } else if (board.kind == BoardKind::kAprilGrid) {
    if (!detect_aprilgrid(board, grey, d, corners)) return d;
  } else {
    std::vector<std::vector<cv::Point2f>> marker_corners, rejected;
    std::vector<int> marker_ids;
    const cv::Ptr<cv::aruco::DetectorParameters> parameters = cv::aruco::DetectorParameters::create();
    cv::aruco::detectMarkers(grey, board.charuco->dictionary, marker_corners, marker_ids, parameters, rejected);
    if (marker_ids.empty()) {
      d.reason = "pattern not found (no markers of " + board.dictionary + ")";
      if (const std::optional<std::string> seen = seen_dictionary(grey)) {
        Board other = board;
        other.dictionary = *seen;
        d.seen_board = other.text();
        d.reason += "; the view shows markers of " + *seen;
      }
      return d;
    }
    if (const std::optional<cv::Size> sheet = fitting_charuco(board, marker_corners, marker_ids)) {
      Board fits = board;
      fits.cols = sheet->width;
      fits.rows = sheet->height;
      d.fitting_board = fits.text();
      d.reason = "the markers lie as on a sheet of " + std::to_string(fits.cols) + "x" + std::to_string(fits.rows) +
                 " squares, not " + std::to_string(board.cols) + "x" + std::to_string(board.rows) + ": give --board " +
                 d.fitting_board;
      return d;
    }
    const cv::Ptr<cv::aruco::Board> plain = board.charuco;
    cv::aruco::refineDetectedMarkers(grey, plain, marker_corners, marker_ids, rejected);
    cv::aruco::interpolateCornersCharuco(marker_corners, marker_ids, grey, board.charuco, corners, d.ids);
    d.detector = "detectMarkers + refineDetectedMarkers + interpolateCornersCharuco";
  }
  if (static_cast<int>(corners.size()) < min_corners) {
    d.reason = "too few corners (" + std::to_string(corners.size()) + ", at least " + std::to_string(min_corners) + ")";
    d.ids.clear();
    return d;
  }
  d.found = true;
  d.image_px = std::move(corners);
  for (int id : d.ids) d.board_m.push_back(board.corner_m(id));
  return d;
}

}  // namespace kincal::camera

#include "host/camera/board.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

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

std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, sep)) parts.push_back(part);
  return parts;
}

[[noreturn]] void bad_board(const std::string& text, const std::string& why) {
  throw std::invalid_argument(
      "board '" + text + "': " + why +
      " (expected chessboard:COLSxROWS:SQUARE_M or charuco:COLSxROWS:SQUARE_M:MARKER_M[:DICT])");
}

double positive_length(const std::string& text, const std::string& field, const std::string& value) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(value, &used);
  } catch (const std::exception&) {
    bad_board(text, field + " '" + value + "' is not a number");
  }
  if (used != value.size() || !(v > 0) || !std::isfinite(v)) bad_board(text, field + " '" + value + "' must be > 0 m");
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

// Mean grey level in a small window around `centre` (clipped to the image).
double mean_near(const cv::Mat& grey, cv::Point2f centre, float radius_px) {
  const int r = std::max(1, static_cast<int>(radius_px));
  const cv::Rect window(static_cast<int>(std::lround(centre.x)) - r, static_cast<int>(std::lround(centre.y)) - r,
                        2 * r + 1, 2 * r + 1);
  const cv::Rect clipped = window & cv::Rect(0, 0, grey.cols, grey.rows);
  return clipped.area() > 0 ? cv::mean(grey(clipped))[0] : 128.0;
}

// See the header: for COLS + ROWS odd, put corner 0 next to the dark far-corner square.
void orient_chessboard(const Board& board, const cv::Mat& grey, std::vector<cv::Point2f>& corners) {
  if ((board.cols + board.rows) % 2 == 0) return;
  const std::size_t n = corners.size(), cols = static_cast<std::size_t>(board.cols);
  const cv::Point2f c0 = corners[0], c_last = corners[n - 1];
  const cv::Point2f outside_first = c0 - 0.5f * (corners[1] - c0) - 0.5f * (corners[cols] - c0);
  const cv::Point2f outside_last = c_last + 0.5f * (c_last - corners[n - 2]) + 0.5f * (c_last - corners[n - 1 - cols]);
  const float radius = 0.15f * static_cast<float>(cv::norm(corners[1] - c0));
  if (mean_near(grey, outside_first, radius) > mean_near(grey, outside_last, radius)) {
    std::reverse(corners.begin(), corners.end());
  }
}

}  // namespace

std::string Board::text() const {
  std::ostringstream out;
  out << (kind == BoardKind::kChessboard ? "chessboard:" : "charuco:") << cols << 'x' << rows << ':' << square_m;
  if (kind == BoardKind::kCharuco) out << ':' << marker_m << ':' << dictionary;
  return out.str();
}

int Board::corner_count() const { return kind == BoardKind::kChessboard ? cols * rows : (cols - 1) * (rows - 1); }

cv::Point3f Board::corner_m(int id) const {
  if (id < 0 || id >= corner_count()) throw std::out_of_range("board corner id " + std::to_string(id));
  if (kind == BoardKind::kCharuco) return charuco->chessboardCorners[static_cast<std::size_t>(id)];
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
  if (f.empty() || (f[0] != "chessboard" && f[0] != "charuco")) bad_board(text, "unknown board type");
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
    bool found = cv::findChessboardCornersSB(grey, pattern, corners, cv::CALIB_CB_NORMALIZE_IMAGE);
    if (!found) {
      found = cv::findChessboardCorners(grey, pattern, corners,
                                        cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
      if (found) {
        cv::cornerSubPix(grey, corners, cv::Size(5, 5), cv::Size(-1, -1),
                         cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-3));
      }
    }
    if (!found) {
      d.reason = "pattern not found";
      return d;
    }
    orient_chessboard(board, grey, corners);
    for (int id = 0; id < board.corner_count(); ++id) d.ids.push_back(id);
  } else {
    std::vector<std::vector<cv::Point2f>> marker_corners, rejected;
    std::vector<int> marker_ids;
    const cv::Ptr<cv::aruco::DetectorParameters> parameters = cv::aruco::DetectorParameters::create();
    cv::aruco::detectMarkers(grey, board.charuco->dictionary, marker_corners, marker_ids, parameters, rejected);
    if (marker_ids.empty()) {
      d.reason = "pattern not found (no markers of " + board.dictionary + ")";
      return d;
    }
    const cv::Ptr<cv::aruco::Board> plain = board.charuco;
    cv::aruco::refineDetectedMarkers(grey, plain, marker_corners, marker_ids, rejected);
    cv::aruco::interpolateCornersCharuco(marker_corners, marker_ids, grey, board.charuco, corners, d.ids);
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

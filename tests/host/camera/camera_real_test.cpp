// Issue #22 on real photographs: OpenCV's own sample views (Debian's opencv-doc, 13 views of a
// 9x6 chessboard per camera, 640x480) against OpenCV's documented recipe computed here, the
// wrong-board and shifted-pair gates. Registered only where opencv-doc is installed.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "host/camera/board.hpp"
#include "host/camera/calibration_file.hpp"
#include "host/camera/intrinsics.hpp"
#include "host/camera/stereo.hpp"
#include "tests/host/camera/error_text.hpp"
#include "tests/host/camera/real_corpus.hpp"

using namespace kincal::camera;

namespace {

const std::vector<int> kSampleViews = {1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13, 14};  // there is no 10

std::string sample(const char* side, int i) {
  return std::string(KINCAL_OPENCV_SAMPLES) + "/" + side + (i < 10 ? "0" : "") + std::to_string(i) + ".jpg";
}

std::vector<BoardDetection> detect_samples(const Board& board, const char* side) {
  std::vector<BoardDetection> out;
  for (int i : kSampleViews) {
    const std::string path = sample(side, i);
    out.push_back(detect_board(board, cv::imread(path, cv::IMREAD_GRAYSCALE), path));
  }
  return out;
}

// OpenCV's recipe (modules/calib3d/misc/python/test/test_calibration.py): findChessboardCorners
// with its default flags, cornerSubPix (5, 5) with (EPS + COUNT, 30, 0.1), calibrateCamera.
double recipe_rms_px() {
  std::vector<std::vector<cv::Point3f>> board;
  std::vector<std::vector<cv::Point2f>> image;
  std::vector<cv::Point3f> grid;
  for (int j = 0; j < 6; ++j)
    for (int i = 0; i < 9; ++i) grid.emplace_back(static_cast<float>(i), static_cast<float>(j), 0.0f);
  for (int i : kSampleViews) {
    const cv::Mat grey = cv::imread(sample("left", i), cv::IMREAD_GRAYSCALE);
    std::vector<cv::Point2f> corners;
    if (!cv::findChessboardCorners(grey, cv::Size(9, 6), corners)) continue;
    cv::cornerSubPix(grey, corners, cv::Size(5, 5), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.1));
    board.push_back(grid);
    image.push_back(corners);
  }
  cv::Mat k, d;
  std::vector<cv::Mat> r, t;
  return cv::calibrateCamera(board, image, cv::Size(640, 480), k, d, r, t);
}

}  // namespace

TEST_CASE("OpenCV's 13 sample views calibrate at least as well as OpenCV's own recipe") {
  const IntrinsicCalibration c = calibrate_intrinsics(detect_samples(parse_board("chessboard:9x6:0.025"), "left"));
  const double recipe_px = recipe_rms_px();
  MESSAGE(describe(c) << "OpenCV's recipe: " << recipe_px << " px");
  CHECK(c.views_used == 13);  // every view passes the outlier gate
  CHECK(c.rms_px <= recipe_px);
  for (const ViewReport& v : c.views) CHECK(contains(v.detector, "+ cornerSubPix"));
}

// A camera file nobody here wrote: OpenCV's calibration sample's output for these views
// (opencv-doc's left_intrinsics.yml: its distortion a 5x1 column, with OpenCV's own extra keys)
// reads as OpenCV's FileStorage reads it.
TEST_CASE("OpenCV's own camera file of the sample views reads as OpenCV reads it") {
  const std::string path = std::string(KINCAL_OPENCV_SAMPLES) + "/left_intrinsics.yml";
  const CameraModel loaded = load_camera(path);
  cv::FileStorage fs(path, cv::FileStorage::READ);
  cv::Mat k, d;
  fs["camera_matrix"] >> k;
  fs["distortion_coefficients"] >> d;
  REQUIRE(d.total() == 5);
  CHECK(loaded.image_size == cv::Size(static_cast<int>(fs["image_width"]), static_cast<int>(fs["image_height"])));
  CHECK(cv::norm(cv::Mat(loaded.camera_matrix), k) == 0.0);
  for (int i = 0; i < 5; ++i) CHECK(loaded.distortion[static_cast<std::size_t>(i)] == d.at<double>(i));
  // The stereo sample's intrinsics file beside it holds two cameras: named as such.
  const std::string pair = std::string(KINCAL_OPENCV_SAMPLES) + "/intrinsics.yml";
  CHECK(error_of([&] { (void)load_camera(pair); }) ==
        pair +
            ": a stereo pair's file (M1 D1 M2 D2, as OpenCV's stereo_calib writes them), not one camera's: give "
            "the camera's own file (kincal camera calibrate writes one)");
}

TEST_CASE("the intrinsics' standard deviations agree with OpenCV's stdDeviationsIntrinsics on the 13 views") {
  const std::vector<BoardDetection> d = detect_samples(parse_board("chessboard:9x6:0.025"), "left");
  const IntrinsicCalibration c = calibrate_intrinsics(d);
  std::vector<std::vector<cv::Point3f>> board;
  std::vector<std::vector<cv::Point2f>> image;
  for (const BoardDetection& v : d) {
    board.push_back(v.board_m);
    image.push_back(v.image_px);
  }
  cv::Mat k, dist, opencv_std, std_extrinsics, per_view;
  std::vector<cv::Mat> r, t;
  cv::calibrateCamera(board, image, cv::Size(640, 480), k, dist, r, t, opencv_std, std_extrinsics, per_view);
  // OpenCV divides the squared residuals by N - n (corners less parameters), kincal by 2N - n
  // (residuals less parameters; host/camera/uncertainty.hpp): the rest must agree.
  const double n = c.uncertainty.parameters, corners = c.uncertainty.corners;
  CHECK(c.uncertainty.corners == 13 * 54);
  CHECK(c.uncertainty.parameters == 9 + 6 * 13);
  const double dof_ratio = std::sqrt((2 * corners - n) / (corners - n));
  // calibrateCamera's RMS is per corner: SSR = N rms^2.
  CHECK(c.uncertainty.corner_sigma_px ==
        doctest::Approx(c.rms_px * std::sqrt(corners / (2 * corners - n))).epsilon(1e-6));
  for (int i = 0; i < 9; ++i) {
    const double ratio = c.std_dev[static_cast<std::size_t>(i)] * dof_ratio / opencv_std.at<double>(i);
    MESSAGE("parameter " << i << ": kincal " << c.std_dev[static_cast<std::size_t>(i)] << ", OpenCV "
                         << opencv_std.at<double>(i) << ", ratio with the same sigma 1 + " << ratio - 1);
    CHECK(ratio == doctest::Approx(1.0).epsilon(1e-5));
  }
}

TEST_CASE("a chessboard of the wrong size is refused, naming the size that fits") {
  const std::vector<BoardDetection> d = detect_samples(parse_board("chessboard:8x6:0.025"), "left");
  const std::string message = error_of([&] { (void)calibrate_intrinsics(d); });
  CHECK(contains(message, "has 9x6 inner corners, not 8x6"));
  CHECK(contains(message, "give --board chessboard:9x6:0.025"));
  CHECK(contains(message, "left0"));
  // The right size passes the same check in every view of both cameras.
  const Board right_size = parse_board("chessboard:9x6:0.025");
  for (const char* side : {"left", "right"}) {
    for (const BoardDetection& v : detect_samples(right_size, side)) CHECK_MESSAGE(v.found, v.view << ": " << v.reason);
  }
}

// The class, not the example: every smaller grid of the 9x6 board that a view finds is refused,
// and no view names a size other than the board's own (the rings counted by the local homography
// named 10x4 for 9x4 and 7x9 for 7x4: the size now comes from OpenCV's grown grid, or is not named).
TEST_CASE("every smaller grid of the board is refused, naming only the board's own size") {
  for (const std::string given : {"9x4", "7x4", "4x3", "3x5"}) {
    const Board board = parse_board("chessboard:" + given + ":0.025");
    const std::vector<BoardDetection> d = detect_samples(board, "left");
    for (const BoardDetection& v : d) {
      CHECK_MESSAGE(!v.found, v.view << " accepted " << given);
      if (v.fitting_board.empty()) continue;
      const std::string whole = board.cols >= board.rows ? "chessboard:9x6:0.025" : "chessboard:6x9:0.025";
      CHECK_MESSAGE(v.fitting_board == whole, v.view << ": " << given << " named " << v.fitting_board);
    }
    CHECK(std::any_of(d.begin(), d.end(), [](const BoardDetection& v) { return v.larger_board; }));
    const std::string message = error_of([&] { refuse_wrong_board(d); });
    CHECK_MESSAGE((contains(message, "inner corners, not " + given) || contains(message, "larger than " + given)),
                  message);
  }
}

// The other half of the class: a size larger than the board (a row or a column too many, or
// both) is found in no view -- findChessboardCorners took left12.jpg's board edge for a tenth
// line of corners and "found" 10x6, refused now for the missing squares beyond that line -- and
// calibration names the whole board the views show. Each view names only the board's own size.
TEST_CASE("every larger size is found in no view, and the size the views show is named") {
  for (const std::string given : {"10x6", "9x7", "7x12"}) {
    const Board board = parse_board("chessboard:" + given + ":0.025");
    const std::string whole = board.cols >= board.rows ? "chessboard:9x6:0.025" : "chessboard:6x9:0.025";
    for (const char* side : {"left", "right"}) {
      const std::vector<BoardDetection> d = detect_samples(board, side);
      for (const BoardDetection& v : d) {
        CHECK_MESSAGE(!v.found, v.view << " accepted " << given);
        CHECK_MESSAGE((v.seen_board.empty() || v.seen_board == whole),
                      v.view << ": " << given << " saw " << v.seen_board);
      }
      const std::string message = error_of([&] { (void)calibrate_intrinsics(d); });
      CHECK_MESSAGE(contains(message, "give --board " + whole + "?"), message);
    }
  }
  const std::string left12 = sample("left", 12);
  const BoardDetection edge = detect_board(parse_board("chessboard:10x6:0.025"), cv::imread(left12), left12);
  CHECK_MESSAGE(contains(edge.reason, "has no squares beyond its first column"), edge.reason);
}

TEST_CASE("a right list shifted by one, or out of order any other way, is refused, naming the first pair") {
  const Board board = parse_board("chessboard:9x6:0.025");
  const std::vector<BoardDetection> left = detect_samples(board, "left"), right = detect_samples(board, "right");
  const CameraModel left_camera = calibrate_intrinsics(left).camera, right_camera = calibrate_intrinsics(right).camera;
  const StereoCalibration s = calibrate_stereo(left, right, left_camera, right_camera);
  CHECK(s.baseline_m == doctest::Approx(0.083).epsilon(0.02));

  const std::vector<BoardDetection> left_first(left.begin(), left.end() - 1),
      right_shifted(right.begin() + 1, right.end());
  const std::string message =
      error_of([&] { (void)calibrate_stereo(left_first, right_shifted, left_camera, right_camera); });
  CHECK(contains(message, "pair " + sample("left", 1) + " / " + sample("right", 2) + " disagrees with the others"));
  CHECK(contains(message, "shifted or mismatched"));
  CHECK(contains(message, "no two pairs agree"));

  // The class, not the example: every way a list can lose its order is refused, naming the first
  // pair out of step. Sample views are 1..9, 11..14 (index 4 is view 5).
  const auto refused = [&](const std::vector<BoardDetection>& l, const std::vector<BoardDetection>& r) {
    return error_of([&] { (void)calibrate_stereo(l, r, left_camera, right_camera); });
  };
  const auto without = [](std::vector<BoardDetection> v, std::size_t i) {
    v.erase(v.begin() + static_cast<std::ptrdiff_t>(i));
    return v;
  };
  {  // the left list misses view 5 part-way: the first four pairs still agree, and are named
    const std::vector<BoardDetection> l = without(left, 4), r(right.begin(), right.end() - 1);
    const std::string m = refused(l, r);
    CHECK_MESSAGE(contains(m, "pair " + sample("left", 6) + " / " + sample("right", 5) +
                                  " disagrees with the others: its right_T_left (from its own board poses) differs "
                                  "from that of pair "),
                  m);
    CHECK_MESSAGE(contains(m, "no majority agrees: the largest group that does is 4 pairs (" + sample("left", 1) +
                                  " / " + sample("right", 1)),
                  m);
  }
  {  // shifted by two
    const std::string m = refused({left.begin(), left.end() - 2}, {right.begin() + 2, right.end()});
    CHECK_MESSAGE(contains(m, "pair " + sample("left", 1) + " / " + sample("right", 3) + " disagrees"), m);
  }
  {  // two pairs swapped in the right list: the others agree, the two are named first
    std::vector<BoardDetection> r = right;
    std::swap(r[1], r[2]);
    const std::string m = refused(left, r);
    CHECK_MESSAGE(contains(m, "pair " + sample("left", 2) + " / " + sample("right", 3) + " disagrees"), m);
    CHECK_MESSAGE(contains(m, "2 of 13 pairs disagree: the left"), m);
  }
  {  // the right list reversed
    const std::string m = refused(left, {right.rbegin(), right.rend()});
    CHECK_MESSAGE(contains(m, "disagrees with the others"), m);
  }
  // Left and right given the wrong way round make a valid rig the other way round: calibrated,
  // and the printout says the right camera is on the left.
  const StereoCalibration swapped = calibrate_stereo(right, left, right_camera, left_camera);
  CHECK(swapped.baseline_m == doctest::Approx(s.baseline_m).epsilon(0.01));
  CHECK(contains(describe(swapped), "to the left of the left camera"));
  CHECK_FALSE(contains(describe(s), "to the left of the left camera"));
}

// Issue #43, a whole board next to the image edge or against texture is the board: each left
// view cropped so that an image edge runs through the board's outer squares (half a square
// beyond its outermost corners, on each of the four edges), and pasted without its white margin
// onto each of three other photographs (sharp seam and feathered), is found at its true size in
// every view; the old ring test called the board larger in some (9x7 grown into the cut squares;
// "its squares continue" where a building's windows beside left03.jpg alternated like squares).
// Given a wrong size, the same views still refuse the calibration, naming the board's own.
TEST_CASE("a board cut by the image edge or against texture is found at its true size; wrong sizes still refused") {
  namespace corpus = kincal::camera::testing;
  std::vector<corpus::RealView> views;
  int k = 0;
  for (const corpus::RealView& v : corpus::sample_views("left")) {
    for (int edge = 0; edge < 4; ++edge) {
      const cv::Mat cut = corpus::cut_outer_squares(v.image, edge, 0.5);
      if (!cut.empty()) views.push_back({v.name + " cut " + std::to_string(edge), cut});
    }
    for (int t = 0; t < 3; ++t)
      for (const int feather : {0, 3})
        views.push_back(
            {v.name + " on texture " + std::to_string(k + t) + " feather " + std::to_string(feather),
             corpus::board_on_texture(v.image, corpus::background_texture(v.image.size(), k + t), feather)});
    ++k;
  }
  REQUIRE(views.size() >= 100);
  std::vector<cv::Mat> images;
  std::vector<std::string> names;
  for (const corpus::RealView& v : views) {
    images.push_back(v.image);
    names.push_back(v.name);
  }
  const std::vector<BoardDetection> right_size = detect_boards(parse_board(corpus::kSampleBoard), images, names);
  for (const BoardDetection& d : right_size) CHECK_MESSAGE(d.found, d.view << ": " << d.reason);
  CHECK_NOTHROW(refuse_wrong_board(right_size));
  for (const std::string given : {"8x6", "9x5"}) {
    const std::vector<BoardDetection> d = detect_boards(parse_board("chessboard:" + given + ":0.025"), images, names);
    const std::string message = error_of([&] { refuse_wrong_board(d); });
    CHECK_MESSAGE(contains(message, "give --board chessboard:9x6:0.025"), given << ": " << message);
  }
}

// Issue #43, the board's frame is the same in every view at any image size (step 4 of
// host/camera/board.hpp): at half size the two windows on the far corner squares differed by a
// grey level or two on right12.jpg and right14.jpg and turned their boards half a turn, and the
// stereo consistency gate refused the half-size pairs. Now corner 0 of every view at half and one
// and a half size is where it is at full size, the half-size pairs calibrate to the full-size
// baseline, and the same lists shifted by one are still refused.
TEST_CASE("the board's orientation holds at every image size; the half-size stereo pairs calibrate") {
  namespace corpus = kincal::camera::testing;
  const Board board = parse_board(corpus::kSampleBoard);
  std::vector<std::vector<BoardDetection>> half(2);
  for (std::size_t side = 0; side < 2; ++side) {
    std::vector<cv::Mat> full_images, half_images, larger_images;
    std::vector<std::string> names;
    for (const corpus::RealView& v : corpus::sample_views(side == 0 ? "left" : "right")) {
      full_images.push_back(v.image);
      half_images.push_back(corpus::rescaled(v.image, 0.5));
      larger_images.push_back(corpus::rescaled(v.image, 1.5));
      names.push_back(v.name);
    }
    const std::vector<BoardDetection> full = detect_boards(board, full_images, names);
    half[side] = detect_boards(board, half_images, names);
    const std::vector<BoardDetection> larger = detect_boards(board, larger_images, names);
    for (std::size_t k = 0; k < full.size(); ++k) {
      REQUIRE_MESSAGE(full[k].found, full[k].view << ": " << full[k].reason);
      for (const auto& [scaled, factor] :
           {std::pair<const BoardDetection*, float>{&half[side][k], 0.5f}, std::pair{&larger[k], 1.5f}}) {
        if (!scaled->found) continue;  // a view the smaller image loses is no orientation
        // Pixel centres at integers: x_scaled = (x + 0.5) * factor - 0.5.
        const cv::Point2f expected = (full[k].image_px[0] + cv::Point2f(0.5f, 0.5f)) * factor - cv::Point2f(0.5f, 0.5f);
        CHECK_MESSAGE(cv::norm(scaled->image_px[0] - expected) < 2.0, names[k] << " x" << factor << ": corner 0 at "
                                                                               << scaled->image_px[0]
                                                                               << ", at full size " << expected);
      }
    }
  }
  const CameraModel left_camera = calibrate_intrinsics(half[0]).camera,
                    right_camera = calibrate_intrinsics(half[1]).camera;
  const StereoCalibration s = calibrate_stereo(half[0], half[1], left_camera, right_camera);
  CHECK(s.baseline_m == doctest::Approx(0.083).epsilon(0.03));
  const std::string message = error_of([&] {
    (void)calibrate_stereo({half[0].begin(), half[0].end() - 1}, {half[1].begin() + 1, half[1].end()}, left_camera,
                           right_camera);
  });
  CHECK_MESSAGE(contains(message, "disagrees with the others"), message);
  CHECK_MESSAGE(contains(message, "shifted or mismatched"), message);
}

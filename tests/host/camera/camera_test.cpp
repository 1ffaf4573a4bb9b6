#include <doctest/doctest.h>

#include <unistd.h>
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "host/camera/board.hpp"
#include "host/camera/calibration_file.hpp"
#include "host/camera/hand_eye.hpp"
#include "host/camera/intrinsics.hpp"
#include "host/camera/number_text.hpp"
#include "host/camera/robot_poses.hpp"
#include "host/camera/stereo.hpp"
#include "host/camera/uncertainty.hpp"
#include "host/model/number_text.hpp"
#include "shared/parameters.hpp"
#include "tests/host/camera/camera_scenes.hpp"
#include "tests/host/camera/error_text.hpp"

namespace fs = std::filesystem;
using namespace kincal;
using namespace kincal::camera;

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180;
constexpr int kViews = 12;

using scenes::model_of;
using scenes::projected;

sim::CameraSpec spec_of_right() {
  sim::CameraSpec s = scenes::test_camera();
  s.fx_px = 598;
  s.fy_px = 597;
  s.cx_px = 316;
  s.cy_px = 244;
  s.distortion = {-0.15, 0.05, -0.0004, 0.0006, 0.0};
  return s;
}

std::vector<BoardDetection> detect_rendered(const Board& board, const sim::CameraSpec& camera,
                                            const std::vector<Eigen::Isometry3d>& camera_T_board,
                                            const std::string& prefix) {
  const sim::PlanarTarget target = scenes::target_of(board);
  std::vector<BoardDetection> out;
  for (std::size_t i = 0; i < camera_T_board.size(); ++i) {
    const cv::Mat image = scenes::render(camera, camera_T_board[i], target, 100 + i);
    out.push_back(detect_board(board, image, prefix + std::to_string(i)));
  }
  return out;
}

// The 12 chessboard views of the test camera, rendered and detected once for every test case.
const std::vector<BoardDetection>& chessboard_views() {
  static const std::vector<BoardDetection> views = [] {
    const Board board = parse_board(scenes::chessboard_text());
    return detect_rendered(board, scenes::test_camera(), scenes::board_views(board, kViews), "view");
  }();
  return views;
}

// n board views of the test camera projected with 0.1 px noise drawn from `rng`, named v0, v1, ...
std::vector<BoardDetection> projected_views(const Board& board, int n, cv::RNG& rng) {
  const CameraModel truth = model_of(scenes::test_camera());
  std::vector<BoardDetection> detections;
  for (const Eigen::Isometry3d& v : scenes::board_views(board, n)) {
    detections.push_back(projected(board, truth, v, "v" + std::to_string(detections.size()), rng));
  }
  return detections;
}

double rotation_error_rad(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.rotation().transpose() * b.rotation()).angle();
}

struct TempDir {
  fs::path path;
  TempDir() : path(fs::temp_directory_path() / ("kincal_camera_" + std::to_string(getpid()))) {
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  std::string file(const std::string& name) const { return (path / name).string(); }
};

}  // namespace

TEST_CASE("board texts parse, print back and name what is wrong") {
  const Board chess = parse_board("chessboard:9x6:0.03");
  CHECK(chess.kind == BoardKind::kChessboard);
  CHECK(chess.corner_count() == 54);
  CHECK(chess.corner_m(10).x == doctest::Approx(0.03));
  CHECK(chess.corner_m(10).y == doctest::Approx(0.03));
  CHECK(parse_board(chess.text()).text() == chess.text());
  const Board charuco = parse_board("charuco:7x5:0.04:0.03");
  CHECK(charuco.dictionary == "DICT_4X4_50");
  CHECK(charuco.corner_count() == 24);
  CHECK(parse_board(charuco.text()).text() == charuco.text());

  CHECK(contains(error_of([] { parse_board("chessboard:9x6"); }), "board 'chessboard:9x6': wrong number of fields"));
  CHECK(contains(error_of([] { parse_board("chessboard:9by6:0.03"); }), "size '9by6' is not COLSxROWS"));
  CHECK(contains(error_of([] { parse_board("chessboard:9x6:-1"); }), "square size '-1' must be 1e-06 to 10 m"));
  // Lengths OpenCV's pose solves fail on (its assertion's text, naming no input, was the message).
  CHECK(contains(error_of([] { parse_board("chessboard:9x6:1e300"); }), "square size '1e300' must be 1e-06 to 10 m"));
  CHECK(contains(error_of([] { parse_board("aprilgrid:6x6:nan:0.3"); }), "tag size 'nan' is not a number"));
  CHECK(contains(error_of([] { parse_board("charuco:7x5:0.04:0.05"); }), "marker must be smaller than the square"));
  CHECK(contains(error_of([] { parse_board("charuco:7x5:0.04:0.03:DICT_9X9"); }), "unknown dictionary 'DICT_9X9'"));
  CHECK(contains(error_of([] { parse_board("charuco:20x20:0.04:0.03:DICT_4X4_50"); }),
                 "needs 200 markers, DICT_4X4_50 has 50"));
  CHECK(contains(error_of([] { parse_board("circles:4x11:0.02"); }), "unknown board type"));
}

TEST_CASE("an image without the board is rejected with its reason") {
  const cv::Mat blank(480, 640, CV_8UC1, cv::Scalar(128));
  const BoardDetection chess = detect_board(parse_board(scenes::chessboard_text()), blank, "blank.png");
  CHECK_FALSE(chess.found);
  CHECK(chess.reason == "pattern not found");
  const BoardDetection charuco = detect_board(parse_board(scenes::charuco_text()), blank, "blank.png");
  CHECK_FALSE(charuco.found);
  CHECK(charuco.reason == "pattern not found (no markers of DICT_4X4_50)");
  CHECK(contains(error_of([] { (void)detect_board(parse_board(scenes::chessboard_text()), cv::Mat(), "x.png"); }),
                 "x.png: empty image"));
}

TEST_CASE("intrinsic calibration on rendered chessboards recovers the simulated camera") {
  const Board board = parse_board(scenes::chessboard_text());
  const sim::CameraSpec truth = scenes::test_camera();
  std::vector<BoardDetection> detections = chessboard_views();
  detections.push_back(detect_board(board, cv::Mat(480, 640, CV_8UC1, cv::Scalar(90)), "blank"));
  std::vector<BoardDetection> with_small = detections;
  with_small.push_back(detections.front());
  with_small.back().view = "small";
  with_small.back().image_size = cv::Size(320, 240);
  CHECK(contains(error_of([&] { (void)calibrate_intrinsics(with_small); }),
                 "1 images are not 640x480 like view0 (another camera or another resolution):\n  small: 320x240"));

  const IntrinsicCalibration c = calibrate_intrinsics(detections);
  MESSAGE(describe(c));
  CHECK(c.views_used == 12);
  CHECK(c.views[12].rejection == "pattern not found");
  CHECK(contains(c.views[0].detector, "+ cornerSubPix"));
  const cv::Matx33d& k = c.camera.camera_matrix;
  CHECK(std::abs(k(0, 0) / truth.fx_px - 1) < 0.005);
  CHECK(std::abs(k(1, 1) / truth.fy_px - 1) < 0.005);
  CHECK(std::abs(k(0, 2) - truth.cx_px) < 3.0);
  CHECK(std::abs(k(1, 2) - truth.cy_px) < 3.0);
  CHECK(std::abs(c.camera.distortion[0] - truth.distortion[0]) < 0.03);
  CHECK(std::abs(c.camera.distortion[2] - truth.distortion[2]) < 0.002);
  CHECK(std::abs(c.camera.distortion[3] - truth.distortion[3]) < 0.002);
  CHECK(c.rms_px < 0.3);
  // The standard deviations are positive and say the focal length is known to a fraction of 0.5 %.
  for (double s : c.std_dev) CHECK(s > 0);
  CHECK(c.std_dev[0] < 0.005 * truth.fx_px);
  for (const std::string& w : c.warnings) CHECK_FALSE(contains(w, "cover"));
}

TEST_CASE("intrinsic calibration warns on poor coverage and refuses too few views") {
  const Board board = parse_board(scenes::chessboard_text());
  const CameraModel truth = model_of(scenes::test_camera());
  cv::RNG rng(7);
  // The board far away, always in the middle and hardly tilted.
  std::vector<BoardDetection> detections;
  for (int i = 0; i < 6; ++i) {
    Eigen::Isometry3d camera_T_board = Eigen::Isometry3d::Identity();
    camera_T_board.linear() = Eigen::AngleAxisd(0.05 * i, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
    camera_T_board.translation() = Eigen::Vector3d(-0.12, -0.075, 1.5 + 0.05 * i);
    detections.push_back(projected(board, truth, camera_T_board, "far" + std::to_string(i), rng));
  }
  const IntrinsicCalibration c = calibrate_intrinsics(detections);
  std::string warnings;
  for (const std::string& w : c.warnings) warnings += w + "\n";
  CHECK(contains(warnings, "only 6 views used; 10 or more"));
  CHECK(contains(warnings, "% of the image (cells of 8x6), less than 50 %"));
  CHECK(contains(warnings, "the board is never tilted more than"));

  std::vector<BoardDetection> two(detections.begin(), detections.begin() + 2);
  two.push_back(detect_board(board, cv::Mat(480, 640, CV_8UC1, cv::Scalar(90)), "blank.png"));
  const std::string message = error_of([&] { (void)calibrate_intrinsics(two); });
  CHECK(contains(message, "2 usable views of 3, at least 3 needed"));
  CHECK(contains(message, "blank.png: pattern not found"));
}

TEST_CASE("beyond max_views views (a video), the most spread over the image, distances and tilts are solved on") {
  const Board board = parse_board(scenes::chessboard_text());
  const CameraModel truth = model_of(scenes::test_camera());
  cv::RNG rng(11);
  // 10 views spread as a calibration wants, then 60 of a board held nearly still in the middle
  // (moved a few millimetres each: more than a near-duplicate), as a video gives them.
  std::vector<BoardDetection> detections;
  const std::vector<Eigen::Isometry3d> spread = scenes::board_views(board, 10);
  for (std::size_t i = 0; i < spread.size(); ++i)
    detections.push_back(projected(board, truth, spread[i], "spread" + std::to_string(i), rng));
  for (int i = 0; i < 60; ++i) {
    Eigen::Isometry3d still = Eigen::Isometry3d::Identity();
    still.translation() = Eigen::Vector3d(-0.12 + 0.003 * (i % 8), -0.075 + 0.003 * (i / 8), 0.6);
    detections.push_back(projected(board, truth, still, "still" + std::to_string(i), rng));
  }
  IntrinsicOptions options;
  options.max_views = 16;
  const IntrinsicCalibration c = calibrate_intrinsics(detections, options);
  CHECK(c.views_used == 16);
  for (int i = 0; i < 10; ++i) CHECK(c.views[static_cast<std::size_t>(i)].used);
  int not_needed = 0;
  for (const ViewReport& v : c.views)
    not_needed += contains(v.rejection, "not needed: 70 views passed, and the 16 most spread over the image") ? 1 : 0;
  CHECK(not_needed == 54);
  CHECK(std::abs(c.camera.camera_matrix(0, 0) - truth.camera_matrix(0, 0)) < 0.01 * truth.camera_matrix(0, 0));
  options.max_views = 100;  // the default: all 70 solved on
  CHECK(calibrate_intrinsics(detections, options).views_used == 70);
}

// Issue #43, rejection that never costs: the outlier gate leaves a view out only where that lowers
// the other views' held-out error. Two close views fill the frame with noisier corners (0.7 px:
// defocus, large squares) -- residuals 7 times the others' without being wrong: they alone reach
// the image's corners, and leaving one out raises the held-out error. A view with half its
// corners displaced 3 px (a bent board) has the same RMS and is left out: without it the other
// views are predicted better. Both numbers are printed either way.
TEST_CASE("intrinsic calibration's outlier gate keeps close views with large residuals, leaves out a bent board") {
  const Board board = parse_board("chessboard:9x6:0.03");
  const cv::Mat k = (cv::Mat_<double>(3, 3) << 600, 0, 320, 0, 600, 240, 0, 0, 1);
  const cv::Mat d = (cv::Mat_<double>(1, 5) << -0.1, 0.05, 0, 0, 0);
  cv::RNG rng(5);
  const auto view = [&](cv::Vec3d r, cv::Vec3d t, const std::string& name, double sigma_px) {
    BoardDetection out;
    out.view = name;
    out.image_size = {640, 480};
    out.found = true;
    std::vector<cv::Point3f> centred;
    for (int id = 0; id < board.corner_count(); ++id) {
      out.ids.push_back(id);
      out.board_m.push_back(board.corner_m(id));
      centred.push_back(board.corner_m(id) - cv::Point3f(0.12f, 0.075f, 0.0f));
    }
    cv::projectPoints(centred, r, t, k, d, out.image_px);
    for (cv::Point2f& p : out.image_px) {
      p.x += static_cast<float>(rng.gaussian(sigma_px));
      p.y += static_cast<float>(rng.gaussian(sigma_px));
      REQUIRE((p.x > 0 && p.y > 0 && p.x < 639 && p.y < 479));
    }
    return out;
  };
  std::vector<BoardDetection> views;
  for (int i = 0; i < 12; ++i) {  // 0.55-0.65 m, tilted 23 degrees in turning directions, near the centre
    const double a = 0.52 * i;
    views.push_back(view({0.4 * std::cos(a), 0.4 * std::sin(a), 0.1 * (i % 3 - 1)},
                         {0.06 * std::cos(1.3 * i), 0.04 * std::sin(1.7 * i), 0.55 + 0.05 * (i % 3)},
                         "far" + std::to_string(i), 0.1));
  }
  views.push_back(view({0.05, -0.05, 0.0}, {0, 0, 0.25}, "close0", 0.7));
  views.push_back(view({-0.08, 0.1, 0.02}, {0.005, 0, 0.26}, "close1", 0.7));
  BoardDetection bent = view({0.3, 0.2, 0}, {0.02, -0.03, 0.6}, "bent", 0.1);
  for (std::size_t i = 27; i < bent.image_px.size(); ++i) bent.image_px[i].y += 3.0f;
  views.push_back(bent);

  const IntrinsicCalibration c = calibrate_intrinsics(views);
  MESSAGE(describe(c));
  CHECK(c.views_used == 14);
  for (const ViewReport& v : c.views) {
    CAPTURE(v.view);
    if (v.view.rfind("close", 0) == 0) {
      CHECK(v.used);
      CHECK(v.rms_px > 0.5);  // a candidate: beyond 3 times the median view's and the 0.5 px floor
      CHECK(contains(v.outlier_test, "kept: RMS "));
      CHECK(contains(v.outlier_test, "but the other views' held-out RMS (3-fold leave-views-out) is "));
    } else if (v.view == "bent") {
      CHECK_FALSE(v.used);
      CHECK(contains(v.rejection, "an outlier: RMS "));
      CHECK(contains(v.rejection, " and the other views' held-out RMS (3-fold leave-views-out) is "));
    } else {
      CHECK(v.used);
      CHECK(v.outlier_test.empty());
    }
  }
  CHECK(contains(describe(c), "view close0: 54 corners, RMS "));
  // The held-out numbers the printout gives agree with the decision: with > without for the bent
  // board, with < without for the close views.
  const auto numbers = [](const std::string& text) {
    const std::size_t at = text.find(" px with it, ");
    const std::size_t from = text.rfind(' ', at - 1) + 1;
    return std::pair{std::stod(text.substr(from, at - from)), std::stod(text.substr(at + 13))};
  };
  for (const ViewReport& v : c.views) {
    if (v.view == "bent") {
      const auto [with, without] = numbers(v.rejection);
      CHECK(without < with);
    } else if (!v.outlier_test.empty()) {
      const auto [with, without] = numbers(v.outlier_test);
      CHECK(without >= with);
    }
  }
}

TEST_CASE("ChArUco boards drawn by OpenCV are detected with ids and calibrate the camera") {
  const Board board = parse_board(scenes::charuco_text());
  const sim::CameraSpec truth = scenes::test_camera();
  const std::vector<BoardDetection> detections =
      detect_rendered(board, truth, scenes::board_views(board, 8), "charuco");
  for (const BoardDetection& d : detections) {
    CHECK_MESSAGE(d.found, d.view << ": " << d.reason);
    CHECK(d.ids.size() >= 12);
  }
  const IntrinsicCalibration c = calibrate_intrinsics(detections);
  MESSAGE(describe(c));
  CHECK(std::abs(c.camera.camera_matrix(0, 0) / truth.fx_px - 1) < 0.01);
  CHECK(c.rms_px < 0.5);
}

// The class the chessboard's wrong size stands for: interpolateCornersCharuco would place the
// corners by whatever layout it is given. Every other layout of the sheet's markers is refused,
// naming the sheet; a view of part of the sheet is still found.
TEST_CASE("ChArUco views of another sheet are refused, naming the sheet the markers lie on") {
  const Board board = parse_board(scenes::charuco_text());
  const sim::CameraSpec truth = scenes::test_camera();
  const std::vector<Eigen::Isometry3d> poses = scenes::board_views(board, 8);
  const cv::Mat image = scenes::render(truth, poses[0], scenes::target_of(board), 7);
  REQUIRE(detect_board(board, image, "whole.png").found);
  const std::string sheet = board.text();
  for (const std::string wrong : {"5x7", "6x5", "8x5", "7x4", "5x5", "4x3"}) {
    CAPTURE(wrong);
    const Board given = parse_board("charuco:" + wrong + sheet.substr(sheet.find(':', 8)));
    const BoardDetection d = detect_board(given, image, "whole.png");
    CHECK_FALSE(d.found);
    CHECK(d.fitting_board == sheet);
    CHECK(contains(d.reason, "give --board " + sheet));
  }
  for (const BoardDetection& d : detect_rendered(board, truth, poses, "charuco"))
    CHECK_MESSAGE(d.fitting_board.empty(), d.view << ": " << d.reason);
}

// The same class for the dictionary: a sheet printed from another ArUco family (or the original
// ArUco markers) has no markers of the given dictionary; the view names the one it shows.
TEST_CASE("ChArUco views of another dictionary name the dictionary the markers come from") {
  const sim::CameraSpec truth = scenes::test_camera();
  const std::string sheet = "charuco:7x5:0.04:0.03:";
  for (const std::string printed : {"DICT_5X5_100", "DICT_6X6_250", "DICT_ARUCO_ORIGINAL"}) {
    CAPTURE(printed);
    const Board board = parse_board(sheet + printed);
    const cv::Mat image = scenes::render(truth, scenes::board_views(board, 1)[0], scenes::target_of(board), 7);
    const BoardDetection d = detect_board(parse_board(sheet + "DICT_4X4_50"), image, "other.png");
    CHECK_FALSE(d.found);
    const std::string named = printed == "DICT_ARUCO_ORIGINAL" ? printed : printed.substr(0, 9) + "50";
    CHECK(d.seen_board == sheet + named);
    CHECK(contains(d.reason, "no markers of DICT_4X4_50); the view shows markers of " + named));
    const std::string message = error_of([&] { (void)calibrate_intrinsics({d, d, d}); });
    CHECK(contains(message, "3 of 3 views show a board " + sheet + named + ": give --board " + sheet + named + "?"));
  }
}

TEST_CASE("AprilGrid texts parse, number the corners as Kalibr does and name what is wrong") {
  const Board april = parse_board("aprilgrid:6x5:0.04:0.3");
  CHECK(april.kind == BoardKind::kAprilGrid);
  CHECK(april.corner_count() == 120);
  CHECK(parse_board(april.text()).text() == april.text());
  // Kalibr's numbering over a 10 x 12 grid of tag corners, rows counted upwards: corner 0 is tag
  // 0's lower left at the bottom of the sheet (y down here), 1 its lower right, 12 and 13 its
  // upper left and right, 2 tag 1's lower left; the top left tag's upper left is the origin.
  const double height = 5 * 0.04 + 4 * 0.012;
  CHECK(april.corner_m(0).x == doctest::Approx(0.0));
  CHECK(april.corner_m(0).y == doctest::Approx(height));
  CHECK(april.corner_m(1).x == doctest::Approx(0.04));
  CHECK(april.corner_m(12).y == doctest::Approx(height - 0.04));
  CHECK(april.corner_m(13).x == doctest::Approx(0.04));
  CHECK(april.corner_m(2).x == doctest::Approx(0.052));
  CHECK(april.corner_m(108).x == doctest::Approx(0.0));
  CHECK(april.corner_m(108).y == doctest::Approx(0.0).epsilon(1e-6));
  CHECK(contains(error_of([] { parse_board("aprilgrid:6x5:0.04"); }), "wrong number of fields"));
  CHECK(contains(error_of([] { parse_board("aprilgrid:6x5:0.04:3"); }), "spacing '3' must be 0.1 to 1"));
  CHECK(contains(error_of([] { parse_board("aprilgrid:6x5:0.04:wide"); }), "spacing 'wide' is not a number"));
  CHECK(contains(error_of([] { parse_board("aprilgrid:1x5:0.04:0.3"); }), "must be 2..100"));
  CHECK(contains(error_of([] { parse_board("aprilgrid:30x30:0.04:0.3"); }), "needs 900 tags, family 36h11 has 587"));
  CHECK(contains(error_of([] { (void)draw_aprilgrid(parse_board("aprilgrid:6x5:0.04:0.25"), 1); }),
                 "a gap of 2.500000 px at 1 px a bit is not whole pixels"));
  CHECK(contains(error_of([] { (void)draw_aprilgrid(parse_board(scenes::chessboard_text()), 4); }),
                 "is not an AprilGrid"));
}

TEST_CASE("AprilGrid sheets are found to a fraction of a pixel and calibrate the camera") {
  const Board board = parse_board(scenes::aprilgrid_text());
  const sim::CameraSpec truth = scenes::test_camera();
  const CameraModel camera = model_of(truth);
  std::vector<Eigen::Isometry3d> views = scenes::board_views(board, 8);
  // Two more: the sheet turned 15 degrees further away (about 45 degrees from the line of sight),
  // and half of it out of the image.
  Eigen::Isometry3d oblique = views[1];
  oblique.linear() = oblique.linear() * Eigen::AngleAxisd(15 * kDeg, Eigen::Vector3d::UnitY()).toRotationMatrix();
  views.push_back(oblique);
  Eigen::Isometry3d partial = views[0];
  partial.translation().x() -= 0.2;
  views.push_back(partial);
  const std::vector<BoardDetection> detections = detect_rendered(board, truth, views, "april");
  double sum_sq = 0;
  std::size_t n = 0;
  for (std::size_t v = 0; v < detections.size(); ++v) {
    const BoardDetection& d = detections[v];
    REQUIRE_MESSAGE(d.found, d.view << ": " << d.reason);
    CHECK(contains(d.detector, "cornerSubPix"));
    cv::RNG no_noise(1);
    const BoardDetection exact = projected(board, camera, views[v], d.view, no_noise, 0.0);
    // Every tag wholly inside the image is found (a tag's corner squares may reach out of it).
    std::size_t inside = 0;
    for (int tag = 0; tag < board.cols * board.rows; ++tag) {
      const int lower_left = (tag / board.cols) * 4 * board.cols + (tag % board.cols) * 2;
      bool all = true;
      for (const int id : {lower_left, lower_left + 1, lower_left + 2 * board.cols, lower_left + 2 * board.cols + 1}) {
        const cv::Point2f p = exact.image_px[static_cast<std::size_t>(id)];
        all = all && p.x >= 0 && p.y >= 0 && p.x <= 639 && p.y <= 479;
      }
      inside += all ? 1 : 0;
    }
    double view_sq = 0;
    for (std::size_t i = 0; i < d.ids.size(); ++i) {
      const cv::Point2f e = d.image_px[i] - exact.image_px[static_cast<std::size_t>(d.ids[i])];
      view_sq += static_cast<double>(e.dot(e));
    }
    MESSAGE(d.view << ": " << d.ids.size() / 4 << " of " << inside << " tags inside the image, corner RMS "
                   << std::sqrt(view_sq / static_cast<double>(d.ids.size())) << " px, " << d.detector);
    CHECK(d.ids.size() / 4 + 3 >= inside);
    sum_sq += view_sq;
    n += d.ids.size();
  }
  const double rms_px = std::sqrt(sum_sq / static_cast<double>(n));
  MESSAGE("AprilGrid corner error against the truth: " << rms_px << " px RMS over " << n << " corners");
  // Measured 0.169 px (0.13-0.17 px a view at about 3 px a tag bit, 0.30 px in the oblique view).
  CHECK(rms_px < 0.22);
  const IntrinsicCalibration c = calibrate_intrinsics(detections);
  MESSAGE(describe(c));
  CHECK(std::abs(c.camera.camera_matrix(0, 0) / truth.fx_px - 1) < 0.005);
  CHECK(std::abs(c.camera.camera_matrix(1, 1) / truth.fy_px - 1) < 0.005);
  CHECK(std::abs(c.camera.camera_matrix(0, 2) - truth.cx_px) < 3.0);
  CHECK(std::abs(c.camera.camera_matrix(1, 2) - truth.cy_px) < 3.0);
  CHECK(std::abs(c.camera.distortion[0] - truth.distortion[0]) < 0.03);
  CHECK(c.rms_px < 0.3);
}

TEST_CASE("AprilGrid views of another size, without tags or with too few are refused with the reason") {
  const Board board = parse_board(scenes::aprilgrid_text());
  const sim::CameraSpec truth = scenes::test_camera();
  const Eigen::Isometry3d whole = scenes::board_views(board, 8)[0];
  const cv::Mat image = scenes::render(truth, whole, scenes::target_of(board), 7);
  // One column too few, one row too few, one column too many.
  for (const char* wrong : {"aprilgrid:5x5:0.04:0.3", "aprilgrid:6x4:0.04:0.3", "aprilgrid:7x5:0.04:0.3"}) {
    CAPTURE(wrong);
    const BoardDetection d = detect_board(parse_board(wrong), image, "whole.png");
    CHECK_FALSE(d.found);
    CHECK(d.fitting_board == "aprilgrid:6x5:0.04:0.3");
    CHECK(contains(d.reason, "give --board aprilgrid:6x5:0.04:0.3"));
    MESSAGE(d.reason);
  }
  // Another family's tags and a blank image hold no tag of the board.
  const cv::Mat blank(480, 640, CV_8UC1, cv::Scalar(128));
  CHECK(detect_board(board, blank, "blank.png").reason ==
        "pattern not found (no AprilTags of family 36h11 with a 2-bit border)");
  const BoardDetection charuco = detect_board(
      board, scenes::render(truth, whole, scenes::target_of(parse_board(scenes::charuco_text())), 7), "charuco.png");
  CHECK_FALSE(charuco.found);
  MESSAGE(charuco.reason);
  // Three tags in view: too few.
  cv::Mat three(480, 640, CV_8UC1, cv::Scalar(255));
  const cv::Mat sheet = draw_aprilgrid(board, 4);
  const int gap = aprilgrid_gap_px(board, 4), pitch = 40 + gap;
  sheet(cv::Rect(0, 0, 3 * pitch + gap, pitch + gap)).copyTo(three(cv::Rect(100, 100, 3 * pitch + gap, pitch + gap)));
  const BoardDetection few = detect_board(board, three, "three.png");
  CHECK_FALSE(few.found);
  CHECK(few.reason == "too few tags (3 of the board, at least 4)");
}

TEST_CASE("stereo calibration recovers the baseline and rectifies") {
  const Board board = parse_board(scenes::chessboard_text());
  const std::vector<Eigen::Isometry3d> left_views = scenes::board_views(board, kViews);
  std::vector<Eigen::Isometry3d> right_views;
  for (const Eigen::Isometry3d& v : left_views) right_views.push_back(scenes::left_T_right().inverse() * v);
  const std::vector<BoardDetection>& left = chessboard_views();
  const std::vector<BoardDetection> right = detect_rendered(board, spec_of_right(), right_views, "right");
  const IntrinsicCalibration left_intrinsics = calibrate_intrinsics(left),
                             right_intrinsics = calibrate_intrinsics(right);
  const CameraModel& left_camera = left_intrinsics.camera;
  const CameraModel& right_camera = right_intrinsics.camera;
  const double baseline_m = scenes::left_T_right().translation().norm();

  for (const bool refine : {false, true}) {
    CAPTURE(refine);
    StereoOptions options;
    options.refine_intrinsics = refine;
    options.left_intrinsics = &left_intrinsics.uncertainty;
    options.right_intrinsics = &right_intrinsics.uncertainty;
    const StereoCalibration s = calibrate_stereo(left, right, left_camera, right_camera, options);
    MESSAGE(describe(s));
    CHECK(std::abs(s.baseline_m / baseline_m - 1) < 0.01);
    // The pose's covariance with the intrinsics' share when the intrinsics are held, none else.
    REQUIRE(s.pose_uncertainty.has_value() == !refine);
    if (!refine) {
      const cv::Vec3d along = s.right_t_left_m / s.baseline_m;
      const double sigma_m = std::sqrt((along.t() * s.pose_uncertainty->covariance.get_minor<3, 3>(3, 3) * along)(0));
      CHECK(std::abs(s.baseline_m - baseline_m) < 4 * sigma_m);
      CHECK(contains(describe(s), "baseline sigma (with the intrinsics' uncertainty): "));
    }
    cv::Vec3d rotation;
    cv::Rodrigues(s.right_R_left, rotation);
    CHECK(cv::norm(rotation) == doctest::Approx(3 * kDeg).epsilon(0.05));
    CHECK(s.rms_px < 0.4);
    // Rectified: the right projection carries -f * baseline in its x translation.
    CHECK(-s.projection_right(0, 3) / s.projection_right(0, 0) == doctest::Approx(s.baseline_m).epsilon(1e-6));
  }

  std::vector<BoardDetection> short_right(right.begin(), right.end() - 1);
  CHECK(contains(error_of([&] { (void)calibrate_stereo(left, short_right, left_camera, right_camera); }),
                 "12 left views but 11 right views"));
  std::vector<BoardDetection> bad_right = right;
  for (std::size_t i = 0; i < 10; ++i)
    bad_right[i] = detect_board(board, cv::Mat(480, 640, CV_8UC1, cv::Scalar(128)), "blank");
  const std::string message = error_of([&] { (void)calibrate_stereo(left, bad_right, left_camera, right_camera); });
  CHECK(contains(message, "2 usable pairs of 12, at least 3 needed"));
  CHECK(contains(message, "view0 / blank: blank: pattern not found"));
}

TEST_CASE("stereo pose covariance: right_T_left's spread over noisy corners, with the intrinsics' share") {
  // Each trial: both cameras calibrated from their own noisy corners (sigma 0.2 px), then the
  // pair with those intrinsics held, and with the true intrinsics; the error of right_T_left
  // against the truth in units of the predicted covariance (chi-square, 6 dof: mean 6).
  const Board board = parse_board(scenes::chessboard_text());
  const CameraModel left_truth = model_of(scenes::test_camera()), right_truth = model_of(spec_of_right());
  const std::vector<Eigen::Isometry3d> views = scenes::board_views(board, kViews);
  const Eigen::Isometry3d right_T_left = scenes::left_T_right().inverse();
  cv::Matx33d true_r;
  cv::eigen2cv(Eigen::Matrix3d(right_T_left.linear()), true_r);
  cv::Vec3d true_rotation;
  cv::Rodrigues(true_r, true_rotation);
  const cv::Vec3d true_t(right_T_left.translation().x(), right_T_left.translation().y(),
                         right_T_left.translation().z());
  const auto chi2 = [&](const StereoCalibration& s, const StereoPoseCovariance& c) {
    cv::Vec3d rotation;
    cv::Rodrigues(s.right_R_left, rotation);
    const cv::Vec3d dr = rotation - true_rotation, dt = s.right_t_left_m - true_t;
    const cv::Vec6d e(dr[0], dr[1], dr[2], dt[0], dt[1], dt[2]);
    return (e.t() * c.covariance.inv(cv::DECOMP_CHOLESKY) * e)(0);
  };
  constexpr int kTrials = 20;
  cv::RNG rng(22);
  double with = 0, without = 0, known = 0, sigma = 0;
  for (int trial = 0; trial < kTrials; ++trial) {
    std::vector<BoardDetection> left, right;
    for (std::size_t i = 0; i < views.size(); ++i) {
      left.push_back(projected(board, left_truth, views[i], "left" + std::to_string(i), rng, 0.2));
      right.push_back(projected(board, right_truth, right_T_left * views[i], "right" + std::to_string(i), rng, 0.2));
    }
    std::vector<StereoView> pairs;
    for (std::size_t i = 0; i < views.size(); ++i)
      pairs.push_back({&left[i].board_m, &left[i].image_px, &right[i].image_px});
    const IntrinsicCalibration lc = calibrate_intrinsics(left), rc = calibrate_intrinsics(right);
    const StereoCalibration s = calibrate_stereo(left, right, lc.camera, rc.camera);
    with += chi2(s, stereo_pose_covariance(lc.camera, rc.camera, s.right_R_left, s.right_t_left_m, pairs,
                                           &lc.uncertainty, &rc.uncertainty)) /
            kTrials;
    without += chi2(s, stereo_pose_covariance(lc.camera, rc.camera, s.right_R_left, s.right_t_left_m, pairs)) / kTrials;
    const StereoCalibration t = calibrate_stereo(left, right, left_truth, right_truth);
    const StereoPoseCovariance c =
        stereo_pose_covariance(left_truth, right_truth, t.right_R_left, t.right_t_left_m, pairs);
    known += chi2(t, c) / kTrials;
    sigma += c.corner_sigma_px / kTrials;
  }
  MESSAGE("mean chi-square of right_T_left's error: " << with << " with the estimated intrinsics and their share, "
                                                      << without << " without their share, " << known
                                                      << " with the true intrinsics; corner sigma " << sigma << " px");
  CHECK(sigma == doctest::Approx(0.2).epsilon(0.05));
  // 20 trials: the mean of chi-square(6) has a standard deviation of 0.77.
  for (const double mean : {with, known}) {
    CHECK(mean > 3.8);
    CHECK(mean < 8.8);
  }
  CHECK(without > 10 * with);  // the intrinsics' error dominates right_T_left's
}

TEST_CASE("hand-eye calibration on rendered views recovers gripper_T_camera") {
  const Board board = parse_board(scenes::chessboard_text());
  const std::vector<Eigen::Isometry3d> views = scenes::board_views(board, kViews);
  const std::vector<Eigen::Isometry3d> poses = scenes::gripper_poses(views);
  const std::vector<BoardDetection>& detections = chessboard_views();
  std::vector<HandEyeView> input;
  for (std::size_t i = 0; i < views.size(); ++i) input.push_back({detections[i].view, poses[i], detections[i]});
  const CameraModel camera = model_of(scenes::test_camera());

  const HandEyeCalibration h = calibrate_hand_eye(input, camera);
  MESSAGE(describe(h));
  CHECK(h.poses_used == kViews);
  CHECK((h.gripper_T_camera.translation() - scenes::gripper_T_camera().translation()).norm() < 0.002);
  CHECK(rotation_error_rad(h.gripper_T_camera, scenes::gripper_T_camera()) < 0.2 * kDeg);
  CHECK((h.base_T_target.translation() - scenes::base_T_target().translation()).norm() < 0.002);
  CHECK(h.rms_after_px <= h.rms_before_px);
  CHECK(h.rms_after_px < 0.3);
  REQUIRE(h.methods.size() == 5);
  REQUIRE(h.robot_world.size() == 2);
  for (const HandEyeEstimate& e : h.methods) {
    CAPTURE(e.method);
    CHECK((e.gripper_T_camera.translation() - scenes::gripper_T_camera().translation()).norm() < 0.01);
    CHECK(e.rotation_rms_rad < 0.5 * kDeg);
  }
  for (const HandEyeEstimate& e : h.robot_world) {
    CAPTURE(e.method);
    CHECK((e.gripper_T_camera.translation() - scenes::gripper_T_camera().translation()).norm() < 0.01);
  }
}

TEST_CASE("hand-eye checks refuse weak pose sets and detect a swapped convention") {
  const Board board = parse_board(scenes::chessboard_text());
  const CameraModel camera = model_of(scenes::test_camera());
  const Eigen::Isometry3d base_T_target = scenes::base_T_target();
  const Eigen::Isometry3d gripper_T_camera = scenes::gripper_T_camera();
  cv::RNG rng(3);
  const auto views_from = [&](const std::vector<Eigen::Isometry3d>& board_T_camera) {
    std::vector<HandEyeView> views;
    for (std::size_t i = 0; i < board_T_camera.size(); ++i) {
      const std::string name = "pose" + std::to_string(i);
      views.push_back({name, base_T_target * board_T_camera[i] * gripper_T_camera.inverse(),
                       projected(board, camera, board_T_camera[i].inverse(), name, rng)});
    }
    return views;
  };
  const Eigen::Isometry3d first = scenes::board_views(board, 1).front().inverse();  // board_T_camera

  SUBCASE("too few poses") {
    const std::vector<Eigen::Isometry3d> some(scenes::board_views(board, 3));
    std::vector<Eigen::Isometry3d> board_T_camera;
    for (const Eigen::Isometry3d& v : some) board_T_camera.push_back(v.inverse());
    CHECK(contains(error_of([&] { (void)calibrate_hand_eye(views_from(board_T_camera), camera); }),
                   "3 usable poses of 3, at least 5 needed"));
  }
  SUBCASE("translations only") {
    std::vector<Eigen::Isometry3d> board_T_camera;
    for (int i = 0; i < 6; ++i) {
      board_T_camera.push_back(Eigen::Translation3d(0.01 * i, -0.008 * i, 0.005 * (i % 3)) * first);
    }
    const std::string message = error_of([&] { (void)calibrate_hand_eye(views_from(board_T_camera), camera); });
    CAPTURE(message);
    CHECK(contains(message, "the largest rotation between two poses is 0.0 degrees; at least 20.0 degrees"));
  }
  SUBCASE("rotations about one axis") {
    std::vector<Eigen::Isometry3d> board_T_camera;
    const Eigen::Vector3d centre(0.12, 0.075, 0);
    for (int i = 0; i < 6; ++i) {
      board_T_camera.push_back(Eigen::Translation3d(centre) * Eigen::AngleAxisd(0.3 * i, Eigen::Vector3d::UnitZ()) *
                               Eigen::Translation3d(-centre) * first);
    }
    const std::string message = error_of([&] { (void)calibrate_hand_eye(views_from(board_T_camera), camera); });
    CAPTURE(message);
    CHECK(contains(message, "nearly parallel axes (largest angle between two axes 0.0 degrees, at least 20.0"));
  }
  SUBCASE("swapped convention") {
    std::vector<Eigen::Isometry3d> board_T_camera;
    for (const Eigen::Isometry3d& v : scenes::board_views(board, 8)) board_T_camera.push_back(v.inverse());
    std::vector<HandEyeView> views = views_from(board_T_camera);
    for (HandEyeView& v : views) v.robot_pose = v.robot_pose.inverse();  // gripper_T_base given as base_T_gripper
    const std::string message = error_of([&] { (void)calibrate_hand_eye(views, camera); });
    CHECK(contains(message, "the robot poses fit as base2gripper (gripper_T_base), not as gripper2base as given"));

    HandEyeOptions options;
    options.convention = PoseConvention::kBaseToGripper;
    const HandEyeCalibration h = calibrate_hand_eye(views, camera, options);
    CHECK((h.gripper_T_camera.translation() - gripper_T_camera.translation()).norm() < 0.001);
    CHECK(rotation_error_rad(h.gripper_T_camera, gripper_T_camera) < 0.1 * kDeg);
  }
  // Issue #43: poor data give an answer with a warning; a refusal is kept for plain mistakes.
  const auto board_views_of = [&](int n) {
    std::vector<Eigen::Isometry3d> board_T_camera;
    for (const Eigen::Isometry3d& v : scenes::board_views(board, n)) board_T_camera.push_back(v.inverse());
    return views_from(board_T_camera);
  };
  // The scale a warning names: the number after "with the board's lengths ".
  const auto warned_scale = [](const HandEyeCalibration& h) {
    for (const std::string& w : h.warnings) {
      const std::size_t at = w.find("with the board's lengths ");
      if (at != std::string::npos) return std::stod(w.substr(at + 25));
    }
    return 0.0;
  };
  SUBCASE("a board given at another size: the result, and a warning naming the scale") {
    const std::vector<HandEyeView> views = board_views_of(8);
    for (double k : {1.2, 1 / 1.2}) {  // the square given 1.2 times too small, or too large
      CAPTURE(k);
      std::vector<HandEyeView> scaled = views;
      for (HandEyeView& v : scaled)
        for (cv::Point3f& p : v.detection.board_m) p *= static_cast<float>(1 / k);
      const HandEyeCalibration h = calibrate_hand_eye(scaled, camera);
      MESSAGE(describe(h));
      REQUIRE(h.warnings.size() == 2);
      CHECK(contains(h.warnings[0], "fit less well than a good set: AX = XB residual "));
      CHECK(warned_scale(h) == doctest::Approx(k).epsilon(0.01));
      CHECK(contains(h.warnings[1], "or the board's square size is (the data suggest "));
      // The AX = XB methods' rotation does not depend on the board's size.
      CHECK(rotation_error_rad(h.methods[1].gripper_T_camera, gripper_T_camera) < 1 * kDeg);
      CHECK(h.translation_sigma_m[0] > 0);
    }
  }
  SUBCASE("factory intrinsics 13 % off in focal length: the result, and a warning naming the focal length") {
    const std::vector<HandEyeView> views = board_views_of(8);
    CameraModel factory = camera;
    factory.camera_matrix(0, 0) *= 1.13;
    factory.camera_matrix(1, 1) *= 1.13;
    const HandEyeCalibration h = calibrate_hand_eye(views, factory);
    MESSAGE(describe(h));
    for (const std::string& w : h.warnings) MESSAGE("warning: " << w);
    REQUIRE(h.warnings.size() == 1);  // the residuals are within a good set's: only the scale shows it
    // The focal length the data suggest is within 4 % of the true one.
    CHECK(warned_scale(h) * 1.13 == doctest::Approx(1.0).epsilon(0.04));
    CHECK(contains(h.warnings[0], "either the camera's focal length is off (the data suggest fx "));
    CHECK(rotation_error_rad(h.gripper_T_camera, gripper_T_camera) < 2 * kDeg);
    CHECK(h.methods_spread_m > 0);
  }
  SUBCASE("poses shifted against the images are refused, naming the shift") {
    const std::vector<HandEyeView> views = board_views_of(10);
    for (int shift : {1, 2, 3}) {
      CAPTURE(shift);
      std::vector<HandEyeView> shifted(views.begin(), views.end() - shift);
      for (std::size_t i = 0; i < shifted.size(); ++i)
        shifted[i].robot_pose = views[i + static_cast<std::size_t>(shift)].robot_pose;
      const std::string message = error_of([&] { (void)calibrate_hand_eye(shifted, camera); });
      CAPTURE(message);
      CHECK(contains(message, "the robot poses and the images do not belong together: AX = XB residual "));
      // Named as shifted while enough poses remain to tell (5); beyond 10 degrees refused anyway.
      CHECK(contains(message, shift < 3 ? "fits the pose " + std::to_string(shift) : "rotations beyond 10.0 degrees"));
      CHECK(contains(message, "a poses file of another run, rows out of order"));
    }
    // Rows rotated (poses of other images throughout): refused as well.
    std::vector<HandEyeView> rotated = views;
    for (std::size_t i = 0; i < views.size(); ++i) rotated[i].robot_pose = views[(i + 3) % views.size()].robot_pose;
    const std::string message = error_of([&] { (void)calibrate_hand_eye(rotated, camera); });
    CAPTURE(message);
    CHECK(contains(message, "do not belong together"));
  }
  SUBCASE("views of another board") {
    // As intrinsic and stereo calibration do: views whose detector found part of a larger board
    // refuse the set when enough show it (2 and a quarter of them), naming the view and the board
    // that fits; one view alone is left out with its reason.
    std::vector<HandEyeView> views = board_views_of(8);
    const auto flag = [&](std::size_t i) {
      views[i].detection.found = false;
      views[i].detection.larger_board = true;
      views[i].detection.fitting_board = "chessboard:10x7:0.02";
      views[i].detection.reason = "the board has 10x7 inner corners";
    };
    flag(2);
    const HandEyeCalibration h = calibrate_hand_eye(views, camera);
    CHECK(h.poses_used == 7);
    CHECK(h.views[2].rejection == "the board has 10x7 inner corners");
    flag(5);
    const std::string message = error_of([&] { (void)calibrate_hand_eye(views, camera); });
    CAPTURE(message);
    CHECK(contains(message, "pose2: the board has 10x7 inner corners (2 of 8 views show another board)"));
  }
}

// Issue #43: a motion capture's (or a worn arm's) poses carry noise of their own. Held exact, that
// noise is pushed into gripper_T_camera; with corrections whose width is estimated from the data,
// the hand-eye lies closer to the truth, and exact poses leave the result as it was.
TEST_CASE("hand-eye with noisy robot poses: the poses' noise is estimated and kept out of gripper_T_camera") {
  const Board board = parse_board(scenes::chessboard_text());
  const CameraModel camera = model_of(scenes::test_camera());
  const Eigen::Isometry3d base_T_target = scenes::base_T_target(), truth = scenes::gripper_T_camera();
  constexpr int kPoses = 16, kTrials = 8;
  constexpr double kRotationSigma_rad = 0.2 * kDeg, kTranslationSigma_m = 0.002;
  std::vector<Eigen::Isometry3d> board_T_camera;
  for (const Eigen::Isometry3d& v : scenes::board_views(board, kPoses)) board_T_camera.push_back(v.inverse());
  cv::RNG rng(43);
  // The views with each pose moved by a turn and a shift in the gripper frame, sigma per axis.
  const auto views_with_noise = [&](double rotation_sigma_rad, double translation_sigma_m) {
    std::vector<HandEyeView> views;
    for (int i = 0; i < kPoses; ++i) {
      const std::string name = "pose" + std::to_string(i);
      const Eigen::Vector3d turn(rng.gaussian(rotation_sigma_rad), rng.gaussian(rotation_sigma_rad),
                                 rng.gaussian(rotation_sigma_rad));
      const Eigen::Vector3d shift(rng.gaussian(translation_sigma_m), rng.gaussian(translation_sigma_m),
                                  rng.gaussian(translation_sigma_m));
      Eigen::Isometry3d noise = Eigen::Isometry3d::Identity();
      if (turn.norm() > 0) noise.linear() = Eigen::AngleAxisd(turn.norm(), turn.normalized()).toRotationMatrix();
      noise.translation() = shift;
      const Eigen::Isometry3d pose = base_T_target * board_T_camera[static_cast<std::size_t>(i)] * truth.inverse();
      views.push_back({name, pose * noise,
                       projected(board, camera, board_T_camera[static_cast<std::size_t>(i)].inverse(), name, rng)});
    }
    return views;
  };
  HandEyeOptions exact;
  exact.correct_poses = false;
  exact.max_rotation_rms_rad = exact.max_translation_rms_m = 1;  // the warnings are not judged here

  SUBCASE("noisy poses: closer to the truth than with the poses held exact, the noise recovered") {
    HandEyeOptions corrected = exact;
    corrected.correct_poses = true;
    double held2 = 0, corrected2 = 0, held_turn2 = 0, corrected_turn2 = 0, rotation_sigma = 0, translation_sigma = 0;
    for (int trial = 0; trial < kTrials; ++trial) {
      const std::vector<HandEyeView> views = views_with_noise(kRotationSigma_rad, kTranslationSigma_m);
      const HandEyeCalibration h = calibrate_hand_eye(views, camera, exact);
      const HandEyeCalibration c = calibrate_hand_eye(views, camera, corrected);
      held2 += (h.gripper_T_camera.translation() - truth.translation()).squaredNorm() / kTrials;
      corrected2 += (c.gripper_T_camera.translation() - truth.translation()).squaredNorm() / kTrials;
      held_turn2 += std::pow(rotation_error_rad(h.gripper_T_camera, truth), 2) / kTrials;
      corrected_turn2 += std::pow(rotation_error_rad(c.gripper_T_camera, truth), 2) / kTrials;
      rotation_sigma += c.noise.pose_rotation_rad / kTrials;
      translation_sigma += c.noise.pose_translation_m / kTrials;
      CHECK(h.noise.pose_rotation_rad == 0);
    }
    MESSAGE("gripper_T_camera error RMS over "
            << kTrials << " trials: poses held exact " << std::sqrt(held2) * 1e3 << " mm / "
            << std::sqrt(held_turn2) / kDeg << " degrees; corrected " << std::sqrt(corrected2) * 1e3 << " mm / "
            << std::sqrt(corrected_turn2) / kDeg << " degrees; pose sigma found " << rotation_sigma / kDeg
            << " degrees, " << translation_sigma * 1e3 << " mm");
    CHECK(std::sqrt(corrected2) < 0.7 * std::sqrt(held2));
    CHECK(std::sqrt(corrected_turn2) < 0.7 * std::sqrt(held_turn2));
    CHECK(rotation_sigma == doctest::Approx(kRotationSigma_rad).epsilon(0.25));
    CHECK(translation_sigma == doctest::Approx(kTranslationSigma_m).epsilon(0.25));
  }
  SUBCASE("exact poses: the corrections stay at zero and the result is the exact-pose one") {
    const std::vector<HandEyeView> views = views_with_noise(0, 0);
    const HandEyeCalibration h = calibrate_hand_eye(views, camera, exact);
    const HandEyeCalibration c = calibrate_hand_eye(views, camera);
    MESSAGE(describe(c));
    CHECK(c.noise.pose_rotation_rad < 1e-5);
    CHECK(c.noise.pose_translation_m < 1e-5);
    CHECK(c.noise.corner_px == doctest::Approx(0.1).epsilon(0.1));
    CHECK((c.gripper_T_camera.translation() - h.gripper_T_camera.translation()).norm() < 1e-5);
    CHECK(rotation_error_rad(c.gripper_T_camera, h.gripper_T_camera) < 1e-5);
  }
}

TEST_CASE("calibration files round-trip in OpenCV YAML and name bad keys") {
  TempDir dir;
  const Board board = parse_board(scenes::chessboard_text());
  const CameraModel truth = model_of(scenes::test_camera());
  cv::RNG rng(11);
  const std::vector<BoardDetection> detections = projected_views(board, 6, rng);
  const IntrinsicCalibration c = calibrate_intrinsics(detections);
  save_camera(dir.file("camera.yaml"), c, board.text());
  const CameraModel loaded = load_camera(dir.file("camera.yaml"));
  CHECK(loaded.image_size == c.camera.image_size);
  CHECK(cv::norm(cv::Mat(loaded.camera_matrix), cv::Mat(c.camera.camera_matrix)) < 1e-9);
  for (std::size_t i = 0; i < 5; ++i) CHECK(loaded.distortion[i] == doctest::Approx(c.camera.distortion[i]));
  // OpenCV reads the file as it reads its own samples' files.
  cv::FileStorage fs(dir.file("camera.yaml"), cv::FileStorage::READ);
  CHECK(static_cast<int>(fs["image_width"]) == 640);
  CHECK(static_cast<int>(fs["nr_of_frames"]) == 6);

  std::vector<BoardDetection> right;
  for (const Eigen::Isometry3d& v : scenes::board_views(board, 6)) {
    right.push_back(projected(board, truth, scenes::left_T_right().inverse() * v, "r", rng));
  }
  StereoOptions with_uncertainty;
  with_uncertainty.left_intrinsics = with_uncertainty.right_intrinsics = &c.uncertainty;
  const StereoCalibration s = calibrate_stereo(detections, right, truth, truth, with_uncertainty);
  save_stereo(dir.file("stereo.yaml"), s);
  const StereoCalibration s2 = load_stereo(dir.file("stereo.yaml"));
  CHECK(s2.baseline_m == doctest::Approx(s.baseline_m).epsilon(1e-12));
  CHECK(cv::norm(cv::Mat(s2.projection_right), cv::Mat(s.projection_right)) < 1e-9);
  CHECK(s2.rms_px == doctest::Approx(s.rms_px));
  // The calibration's covariance (both intrinsics and right_T_left) is read back, and OpenCV reads it too.
  REQUIRE(s.pose_uncertainty.has_value());
  REQUIRE(s2.pose_uncertainty.has_value());
  const cv::Mat& joint = s.pose_uncertainty->calibration_covariance;
  CHECK(cv::norm(s2.pose_uncertainty->calibration_covariance - joint) <= 1e-12 * cv::norm(joint));
  CHECK(cv::norm(cv::Mat(s2.pose_uncertainty->covariance), cv::Mat(s.pose_uncertainty->covariance)) <=
        1e-12 * cv::norm(cv::Mat(s.pose_uncertainty->covariance)));
  CHECK(s2.pose_uncertainty->corner_sigma_px == doctest::Approx(s.pose_uncertainty->corner_sigma_px));
  cv::Mat opencv_joint;
  cv::FileStorage(dir.file("stereo.yaml"), cv::FileStorage::READ)["calibration_covariance"] >> opencv_joint;
  CHECK(opencv_joint.size() == cv::Size(24, 24));
  {
    std::ifstream in(dir.file("stereo.yaml"));
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    text.replace(text.find("left fx"), 7, "left fy");
    std::ofstream(dir.file("stereo_order.yaml")) << text;
  }
  CHECK(contains(error_of([&] { (void)load_stereo(dir.file("stereo_order.yaml")); }),
                 "key 'calibration_covariance_order' is 'left fy"));

  HandEyeCalibration h;
  h.gripper_T_camera = scenes::gripper_T_camera();
  h.base_T_target = scenes::base_T_target();
  h.start_method = "park";
  h.rms_before_px = 0.5;
  h.rms_after_px = 0.1;
  save_hand_eye(dir.file("hand_eye.yaml"), h);
  const HandEyeCalibration h2 = load_hand_eye(dir.file("hand_eye.yaml"));
  CHECK(h2.gripper_T_camera.isApprox(h.gripper_T_camera, 1e-12));
  CHECK(h2.base_T_target.isApprox(h.base_T_target, 1e-12));
  CHECK(h2.start_method == "park");

  std::ofstream(dir.file("partial.yaml")) << "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n";
  CHECK(error_of([&] { (void)load_camera(dir.file("partial.yaml")); }) ==
        dir.file("partial.yaml") + ": key 'camera_matrix' missing or not a 3x3 matrix");
  CHECK(error_of([&] { (void)load_camera(dir.file("none.yaml")); }) == dir.file("none.yaml") + ": no such file");
  // Read through the input layer: a directory, an empty file and Latin-1 text are refused by name.
  CHECK(error_of([&] { (void)load_stereo(dir.path.string()); }) == dir.path.string() + ": is a directory, not a file");
  std::ofstream(dir.file("empty.yaml")) << "\n";
  CHECK(error_of([&] { (void)load_camera(dir.file("empty.yaml")); }) == dir.file("empty.yaml") + ": empty file");
  std::ofstream(dir.file("latin1.yaml")) << "%YAML:1.0\n# caf\xe9\n";
  CHECK(contains(error_of([&] { (void)load_camera(dir.file("latin1.yaml")); }), "not UTF-8"));
  // A byte-order mark and CRLF line ends, as Windows editors write, are read.
  {
    std::ofstream crlf(dir.file("crlf.yaml"), std::ios::binary);
    std::string text = "\xef\xbb\xbf";
    std::ifstream in(dir.file("camera.yaml"), std::ios::binary);
    for (std::string line; std::getline(in, line);) text += line + "\r\n";
    crlf << text;
  }
  CHECK(load_camera(dir.file("crlf.yaml")).camera_matrix == load_camera(dir.file("camera.yaml")).camera_matrix);
  CHECK(contains(error_of([&] { (void)load_hand_eye(dir.file("camera.yaml")); }), "key 'gripper_T_camera' missing"));
  // A key given twice (OpenCV's parser took the first, silently) and a second document (refused in
  // OpenCV's words, naming its source line) are named by the YAML limits.
  std::ofstream(dir.file("twice.yaml")) << "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\nimage_width: 800\n";
  CHECK(error_of([&] { (void)load_camera(dir.file("twice.yaml")); }) ==
        dir.file("twice.yaml") + ":5:1: 'image_width' given twice in this mapping (first at 3:1)");
  std::ofstream(dir.file("two.yaml")) << "%YAML:1.0\n---\nimage_width: 640\n---\nimage_width: 800\n";
  CHECK(contains(error_of([&] { (void)load_camera(dir.file("two.yaml")); }), dir.file("two.yaml") + ":4:"));
  CHECK(contains(error_of([&] { (void)load_camera(dir.file("two.yaml")); }), "a second YAML document"));
}

TEST_CASE("a camera in ROS camera_info YAML: the keys ROS reads, read back exactly") {
  TempDir dir;
  const CameraModel truth = model_of(scenes::test_camera());
  save_camera_ros(dir.file("camera_info.yaml"), truth, "wrist_camera");
  std::ifstream in(dir.file("camera_info.yaml"));
  std::ostringstream text;
  text << in.rdbuf();
  const cv::Matx33d& k = truth.camera_matrix;
  const auto n = [](double v) { return kincal::model::shortest_number_text(v); };
  CHECK(contains(text.str(),
                 "image_width: 640\nimage_height: 480\ncamera_name: wrist_camera\ncamera_matrix:\n"
                 "  rows: 3\n  cols: 3\n  data: [" +
                     n(k(0, 0)) + ", 0, " + n(k(0, 2)) + ", 0, " + n(k(1, 1)) + ", " + n(k(1, 2)) +
                     ", 0, 0, 1]\ndistortion_model: plumb_bob\ndistortion_coefficients:\n  rows: 1\n"));
  CHECK(contains(text.str(),
                 "rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n"
                 "projection_matrix:\n  rows: 3\n  cols: 4\n  data: [" +
                     n(k(0, 0)) + ", 0, " + n(k(0, 2)) + ", 0, 0, " + n(k(1, 1)) + ", " + n(k(1, 2)) +
                     ", 0, 0, 0, 1, 0]\n"));
  const CameraModel loaded = load_camera(dir.file("camera_info.yaml"));
  CHECK(loaded.image_size == truth.image_size);
  CHECK(cv::norm(cv::Mat(loaded.camera_matrix), cv::Mat(truth.camera_matrix)) == 0.0);
  for (std::size_t i = 0; i < 5; ++i) CHECK(loaded.distortion[i] == truth.distortion[i]);

  std::ofstream(dir.file("equidistant.yaml"))
      << "image_width: 640\nimage_height: 480\ncamera_matrix: {rows: 3, cols: 3, data: [1, 0, 0, 0, 1, 0, 0, 0, 1]}\n"
         "distortion_model: equidistant\ndistortion_coefficients: {rows: 1, cols: 4, data: [0, 0, 0, 0]}\n";
  CHECK(error_of([&] { (void)load_camera(dir.file("equidistant.yaml")); }) ==
        dir.file("equidistant.yaml") +
            ": distortion_model 'equidistant': kincal's camera is plumb_bob (k1 k2 p1 p2 k3); files of plumb_bob "
            "and of rational_polynomial (its k4 k5 k6 0) are read");
}

TEST_CASE("camera files as other tools write them: a distortion column, 4 to 14 terms, ROS's models, JSON") {
  TempDir dir;
  CameraModel truth = model_of(scenes::test_camera());
  truth.distortion = {-0.21, 0.08, 0.0012, -0.0007, -0.013};
  const cv::Mat row = truth.distortion_mat(), zeros = cv::Mat::zeros(1, 9, CV_64F);
  // OpenCV's own writer, as its calibration sample writes a camera (the distortion as given).
  const auto opencv_file = [&](const std::string& name, const cv::Mat& d, const std::string& model = "") {
    cv::FileStorage fs(dir.file(name), cv::FileStorage::WRITE);
    fs << "image_width" << 640 << "image_height" << 480 << "camera_matrix" << cv::Mat(truth.camera_matrix)
       << "distortion_coefficients" << d;
    if (!model.empty()) fs << "distortion_model" << model;
    fs.release();
    return dir.file(name);
  };
  const auto same_camera = [&](const std::string& path, double k3) {
    CAPTURE(path);
    const CameraModel loaded = load_camera(path);
    CHECK(loaded.image_size == truth.image_size);
    CHECK(loaded.camera_matrix == truth.camera_matrix);
    for (std::size_t i = 0; i < 4; ++i) CHECK(loaded.distortion[i] == truth.distortion[i]);
    CHECK(loaded.distortion[4] == k3);
  };
  const double k3 = truth.distortion[4];
  // A column of five (OpenCV's calibration sample); rows and columns of 8, 12 and 14 with the
  // rational, thin-prism and tilt terms 0; four (k1 k2 p1 p2): k3 is 0.
  same_camera(opencv_file("column.yaml", row.t()), k3);
  cv::Mat eight, twelve, fourteen;
  cv::hconcat(row, zeros.colRange(0, 3), eight);
  cv::hconcat(row, zeros.colRange(0, 7), twelve);
  cv::hconcat(row, zeros, fourteen);
  same_camera(opencv_file("eight.yaml", eight, "rational_polynomial"), k3);
  same_camera(opencv_file("twelve.yaml", twelve.t()), k3);
  same_camera(opencv_file("fourteen.yaml", fourteen), k3);
  same_camera(opencv_file("four.yaml", row.colRange(0, 4).clone()), 0.0);
  same_camera(opencv_file("four_column.yaml", cv::Mat(row.colRange(0, 4).t())), 0.0);
  // A lens with any term beyond k3 is another model: refused naming the term.
  eight.at<double>(5) = 0.02;
  CHECK(contains(error_of([&] { (void)load_camera(opencv_file("k4.yaml", eight)); }),
                 ": key 'distortion_coefficients': k4 = 0.02, not 0: kincal's camera is plumb_bob"));
  fourteen.at<double>(13) = -0.001;
  CHECK(contains(error_of([&] { (void)load_camera(opencv_file("tilt.yaml", fourteen.t())); }),
                 "'distortion_coefficients': ty = -0.001, not 0"));
  // Other counts and shapes, and a fisheye by name, are refused.
  for (const cv::Mat& d : {cv::Mat(cv::Mat::zeros(1, 6, CV_64F)), cv::Mat(cv::Mat::zeros(2, 5, CV_64F)),
                           cv::Mat(cv::Mat::zeros(1, 3, CV_64F))})
    CHECK(error_of([&] { (void)load_camera(opencv_file("shape.yaml", d)); }) ==
          dir.file("shape.yaml") +
              ": key 'distortion_coefficients' missing or not 4, 5, 8, 12 or 14 coefficients (1xN or Nx1)");
  CHECK(contains(
      error_of([&] { (void)load_camera(opencv_file("fisheye.yaml", row.colRange(0, 4).clone(), "equidistant")); }),
      ": distortion_model 'equidistant': kincal's camera is plumb_bob"));
  // OpenCV's JSON is read (through the YAML reader, JSON being YAML); its XML is refused by name.
  {
    cv::FileStorage fs(dir.file("camera.json"), cv::FileStorage::WRITE);
    fs << "image_width" << 640 << "image_height" << 480 << "camera_matrix" << cv::Mat(truth.camera_matrix)
       << "distortion_coefficients" << row.t();
  }
  same_camera(dir.file("camera.json"), k3);
  {
    cv::FileStorage fs(dir.file("camera.xml"), cv::FileStorage::WRITE);
    fs << "image_width" << 640 << "camera_matrix" << cv::Mat(truth.camera_matrix);
  }
  CHECK(error_of([&] { (void)load_camera(dir.file("camera.xml")); }) ==
        dir.file("camera.xml") +
            ": an OpenCV XML file; kincal reads camera files in YAML, OpenCV's or ROS's (cv::FileStorage writes "
            "YAML to a file named .yml or .yaml)");
  // Kalibr's camera chain of one camera, as kalibr_calibrate_cameras writes it (its README's
  // example); of two cameras, or a fisheye, refused by name.
  const std::string cam0 =
      "cam0:\n  cam_overlaps: []\n  camera_model: pinhole\n  distortion_coeffs: [-0.2879529995338575, "
      "0.0781311194952221, 0.00021265916642721963, -0.0001221450347654466]\n  distortion_model: radtan\n  "
      "intrinsics: [458.9432286546919, 457.5637533402653, 367.0272509347057, 249.3128033381081]\n  resolution: "
      "[752, 480]\n  rostopic: /cam0/image_raw\n";
  std::ofstream(dir.file("camchain.yaml")) << cam0;
  const CameraModel kalibr = load_camera(dir.file("camchain.yaml"));
  CHECK(kalibr.image_size == cv::Size(752, 480));
  CHECK(kalibr.camera_matrix ==
        cv::Matx33d(458.9432286546919, 0, 367.0272509347057, 0, 457.5637533402653, 249.3128033381081, 0, 0, 1));
  CHECK(kalibr.distortion == std::array<double, 5>{-0.2879529995338575, 0.0781311194952221, 0.00021265916642721963,
                                                   -0.0001221450347654466, 0.0});
  std::ofstream(dir.file("camchain2.yaml")) << cam0 << "cam1:\n  camera_model: pinhole\n";
  CHECK(error_of([&] { (void)load_camera(dir.file("camchain2.yaml")); }) ==
        dir.file("camchain2.yaml") +
            ": a Kalibr camera chain of 2 cameras; give one camera's file (OpenCV's or ROS's YAML, or a chain of cam0 "
            "alone)");
  std::string fisheye = cam0;
  fisheye.replace(fisheye.find("radtan"), 6, "equidistant");
  std::ofstream(dir.file("camchain_fisheye.yaml")) << fisheye;
  CHECK(contains(error_of([&] { (void)load_camera(dir.file("camchain_fisheye.yaml")); }),
                 "cam0: distortion_model 'equidistant': kincal's distortion is plumb_bob (Kalibr's radtan)"));
  // OpenCV's keys without OpenCV's "%YAML:1.0" line, as people copy them into READMEs.
  {
    std::ifstream in(dir.file("column.yaml"));
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(dir.file("no_header.yaml")) << text.substr(text.find("image_width"));
  }
  same_camera(dir.file("no_header.yaml"), k3);

  // ROS camera_info: rational_polynomial of 8 (camera_calibration writes it) or of 5 (drivers
  // write it), no distortion_model (ROS's parser reads plumb_bob); a non-zero k5 is refused.
  const auto ros_file = [&](const std::string& name, const std::string& model, const std::string& data, int n) {
    const cv::Matx33d& k = truth.camera_matrix;
    std::ofstream(dir.file(name)) << "image_width: 640\nimage_height: 480\ncamera_name: c\ncamera_matrix:\n  rows: 3\n"
                                     "  cols: 3\n  data: ["
                                  << kincal::model::shortest_number_text(k(0, 0)) << ", 0, "
                                  << kincal::model::shortest_number_text(k(0, 2)) << ", 0, "
                                  << kincal::model::shortest_number_text(k(1, 1)) << ", "
                                  << kincal::model::shortest_number_text(k(1, 2)) << ", 0, 0, 1]\n"
                                  << model << "distortion_coefficients:\n  rows: 1\n  cols: " << n << "\n  data: ["
                                  << data << "]\n";
    return dir.file(name);
  };
  const std::string five = "-0.21, 0.08, 0.0012, -0.0007, -0.013";
  same_camera(ros_file("rational8.yaml", "distortion_model: rational_polynomial\n", five + ", 0, 0, 0", 8), k3);
  same_camera(ros_file("rational5.yaml", "distortion_model: rational_polynomial\n", five, 5), k3);
  same_camera(ros_file("no_model.yaml", "", five, 5), k3);
  CHECK(contains(error_of([&] {
                   (void)load_camera(
                       ros_file("k5.yaml", "distortion_model: rational_polynomial\n", five + ", 0, 0.5, 0", 8));
                 }),
                 "'distortion_coefficients': k5 = 0.5, not 0"));
  CHECK(contains(error_of([&] { (void)load_camera(ros_file("seven.yaml", "", five + ", 0, 0", 7)); }),
                 "not 4, 5, 8, 12 or 14 coefficients"));
  // A shape whose product overflows an int is refused before any product is taken (UBSan watches).
  std::ofstream(dir.file("huge.yaml")) << "image_width: 640\nimage_height: 480\ncamera_matrix: {rows: 3, cols: 3, "
                                          "data: [1, 0, 0, 0, 1, 0, 0, 0, 1]}\ndistortion_coefficients: {rows: "
                                          "2000000000, cols: 2000000000, data: [0, 0, 0, 0, 0]}\n";
  CHECK(contains(error_of([&] { (void)load_camera(dir.file("huge.yaml")); }), "not 4, 5, 8, 12 or 14 coefficients"));
}

TEST_CASE("camera files carry the intrinsics' covariance and projection sigma; files without them still read") {
  TempDir dir;
  const Board board = parse_board(scenes::chessboard_text());
  cv::RNG rng(12);
  const std::vector<BoardDetection> detections = projected_views(board, 10, rng);
  const IntrinsicCalibration c = calibrate_intrinsics(detections);
  // The corner noise is 0.1 px; sigma from the residuals finds it.
  CHECK(c.uncertainty.corner_sigma_px == doctest::Approx(0.1).epsilon(0.1));
  for (int i = 0; i < 9; ++i)
    CHECK(c.std_dev[static_cast<std::size_t>(i)] == std::sqrt(c.uncertainty.covariance(i, i)));
  const auto same_covariance = [&](const std::optional<IntrinsicsCovariance>& loaded) {
    REQUIRE(loaded.has_value());
    CHECK(loaded->corner_sigma_px == doctest::Approx(c.uncertainty.corner_sigma_px).epsilon(1e-12));
    for (int i = 0; i < 9; ++i)
      for (int j = 0; j < 9; ++j)
        CHECK(loaded->covariance(i, j) == doctest::Approx(c.uncertainty.covariance(i, j)).epsilon(1e-12));
  };

  // OpenCV YAML: OpenCV reads its keys and the extra ones; kincal reads both.
  save_camera(dir.file("camera.yaml"), c, board.text());
  cv::FileStorage fs(dir.file("camera.yaml"), cv::FileStorage::READ);
  cv::Mat k, grid, grid_x, grid_y;
  fs["camera_matrix"] >> k;
  fs["projection_sigma_grid_px"] >> grid;
  fs["projection_sigma_grid_x_px"] >> grid_x;
  fs["projection_sigma_grid_y_px"] >> grid_y;
  CHECK(cv::norm(k, cv::Mat(c.camera.camera_matrix)) < 1e-9);
  CHECK(static_cast<std::string>(fs["intrinsics_covariance_order"]) == "fx fy cx cy k1 k2 p1 p2 k3");
  REQUIRE(grid.rows == 12);
  REQUIRE(grid.cols == 16);
  CHECK(grid_x.cols == 16);
  CHECK(grid_y.cols == 12);
  CHECK(grid_x.at<double>(0) == doctest::Approx(19.5));
  CHECK(grid_y.at<double>(11) == doctest::Approx(459.5));
  // The grid is the projection covariance's worst axis at those pixels, and grows off the board.
  const cv::Matx22d centre =
      projection_covariance(c.camera, c.uncertainty, {grid_x.at<double>(8), grid_y.at<double>(6)});
  CHECK(grid.at<double>(6, 8) >= std::sqrt(std::max(centre(0, 0), centre(1, 1))));
  CHECK(grid.at<double>(6, 8) <= std::sqrt(centre(0, 0) + centre(1, 1)));
  CHECK(grid.at<double>(0, 0) > 2 * grid.at<double>(6, 8));
  same_covariance(load_camera_uncertainty(dir.file("camera.yaml")));
  CHECK(load_camera(dir.file("camera.yaml")).camera_matrix == c.camera.camera_matrix);

  // ROS camera_info: the same keys; ROS's own keys unchanged; read back by kincal.
  save_camera_ros(dir.file("camera_info.yaml"), c.camera, "wrist_camera", c.views, c.uncertainty);
  std::ifstream in(dir.file("camera_info.yaml"));
  std::ostringstream text;
  text << in.rdbuf();
  CHECK(contains(text.str(), "distortion_model: plumb_bob\n"));
  CHECK(contains(text.str(), "\nprojection_sigma_grid_px:\n  rows: 12\n  cols: 16\n  data: ["));
  same_covariance(load_camera_uncertainty(dir.file("camera_info.yaml")));
  CHECK(cv::norm(cv::Mat(load_camera(dir.file("camera_info.yaml")).camera_matrix), cv::Mat(c.camera.camera_matrix)) <
        1e-9);

  // Files without the keys: the camera reads, the uncertainty is absent.
  save_camera_ros(dir.file("plain_info.yaml"), c.camera, "wrist_camera");
  CHECK_FALSE(load_camera_uncertainty(dir.file("plain_info.yaml")).has_value());
  std::ofstream(dir.file("opencv_sample.yaml"))
      << "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\ncamera_matrix: !!opencv-matrix\n   rows: 3\n"
         "   cols: 3\n   dt: d\n   data: [ 600., 0., 320., 0., 600., 240., 0., 0., 1. ]\n"
         "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   data: [ 0., 0., 0., 0., 0. "
         "]\n";
  CHECK(load_camera(dir.file("opencv_sample.yaml")).camera_matrix(0, 0) == 600);
  CHECK_FALSE(load_camera_uncertainty(dir.file("opencv_sample.yaml")).has_value());
  // A covariance in another order, without its sigma or not symmetric is refused by name.
  const auto with = [&](const std::string& name, const std::string& from, const std::string& to) {
    std::string t = text.str();
    t.replace(t.find(from), from.size(), to);
    std::ofstream(dir.file(name)) << t;
    return error_of([&] { (void)load_camera_uncertainty(dir.file(name)); });
  };
  CHECK(contains(with("order.yaml", "fx fy cx cy", "fy fx cx cy"), "key 'intrinsics_covariance_order' is 'fy fx"));
  CHECK(contains(with("sigma.yaml", "corner_sigma_px:", "corner_noise_px:"), "key 'corner_sigma_px' missing"));
  const auto n = [](double v) { return kincal::model::shortest_number_text(v); };
  const cv::Matx<double, 9, 9>& cov = c.uncertainty.covariance;
  CHECK(contains(with("asymmetric.yaml", "data: [" + n(cov(0, 0)) + ", " + n(cov(0, 1)) + ",",
                      "data: [" + n(cov(0, 0)) + ", " + n(2 * cov(0, 1) + 1) + ","),
                 "key 'intrinsics_covariance' is not a symmetric covariance"));
}

TEST_CASE("a host calibration converts to the platform's camera block and back") {
  const CameraModel truth = model_of(scenes::test_camera());
  const shared::CameraIntrinsics p = to_platform(truth);
  CHECK(p.fx_px == 610.0f);
  CHECK(p.cx_px == 324.5f);
  CHECK(p.k1 == static_cast<float>(truth.distortion[0]));
  CHECK(p.p2 == static_cast<float>(truth.distortion[3]));
  CHECK(p.width_px == 640);
  CHECK(p.height_px == 480);
  // Through the block's byte image, as it travels to the platform.
  std::array<std::uint8_t, shared::kIntrinsicsBytes> bytes{};
  REQUIRE(shared::encode_block(p, bytes) == shared::kIntrinsicsBytes);
  shared::CameraIntrinsics decoded;
  REQUIRE(shared::decode_block(bytes, decoded) == shared::DecodeStatus::kOk);
  const CameraModel back = from_platform(decoded);
  CHECK(back.image_size == truth.image_size);
  CHECK(back.camera_matrix(1, 2) == doctest::Approx(truth.camera_matrix(1, 2)));
  CHECK(back.distortion[1] == doctest::Approx(truth.distortion[1]).epsilon(1e-6));

  CameraModel wide = truth;
  wide.image_size.width = 70000;
  CHECK(error_of([&] { (void)to_platform(wide); }) == "camera image width 70000 px is outside 1..65535");
  CameraModel broken = truth;
  broken.distortion[4] = std::nan("");
  CHECK(contains(error_of([&] { (void)to_platform(broken); }), "camera parameter k3 = nan"));
}

TEST_CASE(
    "robot poses as controllers and other tools give them: x,y,z + quaternion without joints, rx,ry,rz, 4x4 and 3x4 "
    "rows") {
  const Eigen::Isometry3d expected = [] {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    t.translation() = Eigen::Vector3d(0.4, -0.1, 0.6);
    return t;
  }();
  const Eigen::Quaterniond q(expected.rotation());
  const Eigen::Vector3d rotvec = 0.5 * Eigen::Vector3d(1, 2, 3).normalized();
  const Eigen::Vector3d zyx = expected.rotation().eulerAngles(2, 1, 0);  // yaw, pitch, roll
  const auto same = [&](const std::vector<RobotPose>& p) {
    REQUIRE(p.size() == 1);
    CHECK((p[0].pose.matrix() - expected.matrix()).norm() < 1e-6);
  };
  std::ostringstream csv, rv, rpy, rows16, rows4;
  csv.precision(17);
  rv.precision(17);
  rpy.precision(17);
  rows16.precision(17);
  rows4.precision(17);
  csv << "# from the controller\ntime,x,y,z,qw,qx,qy,qz\n7," << 0.4 << ",-0.1,0.6," << q.w() << ',' << q.x() << ','
      << q.y() << ',' << q.z() << "\n";
  rv << "x;y;z;rx;ry;rz\n0.4;-0.1;0.6;" << rotvec.x() << ';' << rotvec.y() << ';' << rotvec.z() << "\n";
  rpy << "x,y,z,rx,ry,rz\n0.4,-0.1,0.6," << zyx[2] << ',' << zyx[1] << ',' << zyx[0] << "\n";
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      rows16 << expected.matrix()(r, c) << (c < 3 || r < 3 ? " " : "\n");
      rows4 << expected.matrix()(r, c) << (c < 3 ? ", " : "\n");
    }
  }
  std::istringstream in_csv(csv.str()), in_rv(rv.str()), in_rpy(rpy.str()), in16(rows16.str()), in4(rows4.str());
  same(parse_robot_poses(in_csv, "q.csv", RotationColumns::kUnnamed));
  same(parse_robot_poses(in_rv, "rv.csv", RotationColumns::kRotationVector));
  same(parse_robot_poses(in_rpy, "rpy.csv", RotationColumns::kRpy));
  same(parse_robot_poses(in16, "rows16.txt", RotationColumns::kUnnamed));
  same(parse_robot_poses(in4, "rows4.txt", RotationColumns::kUnnamed));

  std::istringstream unnamed(rv.str());
  CHECK(contains(error_of([&] { (void)parse_robot_poses(unnamed, "rv.csv", RotationColumns::kUnnamed); }),
                 "rv.csv:1: rx,ry,rz can mean a rotation vector or roll-pitch-yaw angles"));
  std::istringstream millimetres("x,y,z,qw,qx,qy,qz\n400,-100,600,1,0,0,0\n");
  CHECK(contains(error_of([&] { (void)parse_robot_poses(millimetres, "mm.csv", RotationColumns::kUnnamed); }),
                 "mm.csv:2: the translation is"));
  std::istringstream unfinished("1 0 0 0\n0 1 0 0\n");
  CHECK(contains(error_of([&] { (void)parse_robot_poses(unfinished, "m.txt", RotationColumns::kUnnamed); }),
                 "m.txt:1: an unfinished 4x4 matrix (8 numbers)"));
  std::istringstream skewed("1 0.1 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n");
  CHECK(contains(error_of([&] { (void)parse_robot_poses(skewed, "s.txt", RotationColumns::kUnnamed); }),
                 "s.txt:1: the rotation is not orthonormal"));
  // The hostile-input audit: rotation vectors in degrees (OpenCV's solve then failed in its own
  // words), two rotations or a column twice (the first was taken), a rotation meaning named for a
  // file without rx,ry,rz (ignored).
  const auto refused = [&](const std::string& text, RotationColumns rotation) {
    std::istringstream in(text);
    return error_of([&] { (void)parse_robot_poses(in, "p.csv", rotation); });
  };
  CHECK(contains(refused("x,y,z,rx,ry,rz\n0.4,0,0.6,0,0,3\n0.4,0,0.6,90,0,0\n", RotationColumns::kRotationVector),
                 "p.csv:3: the rotation vector's angle is 90 rad, more than a turn: degrees given as radians?"));
  CHECK(contains(refused("x,y,z,rx,ry,rz\n0.4,0,0.6,1e300,0,0\n", RotationColumns::kRpy),
                 "p.csv:2: an angle is 1e+300 rad"));
  CHECK(contains(refused("x,y,z,rx,ry,rz\n0.4,0,0.6,0,0,400\n", RotationColumns::kRpyDeg),
                 "p.csv:2: an angle is 400 deg, more than a turn: not degrees?"));
  CHECK(contains(refused("x,y,z,qw,qx,qy,qz,rx,ry,rz\n0.4,0,0.6,1,0,0,0,0,0,0\n", RotationColumns::kRotationVector),
                 "p.csv:1: the header has both qw,qx,qy,qz and rx,ry,rz"));
  CHECK(contains(refused("x,y,z,qw,qx,qy,qz,z\n0.4,0,0.6,1,0,0,0,9\n", RotationColumns::kUnnamed),
                 "p.csv:1: the header names column z twice"));
  CHECK(contains(refused("x,y,z,qw,qx,qy,qz\n0.4,0,0.6,1,0,0,0\n", RotationColumns::kRpy),
                 "p.csv:1: the rotation is qw,qx,qy,qz, yet a meaning of rx,ry,rz"));
  CHECK(contains(refused(rows16.str(), RotationColumns::kRotationVector), "p.csv:1: the poses are 4x4 matrices, yet"));
  std::istringstream twice_ignored("t,t,x,y,z,qw,qx,qy,qz\n1,2,0.4,0,0.6,1,0,0,0\n");  // columns not read may repeat
  CHECK(parse_robot_poses(twice_ignored, "t.csv", RotationColumns::kUnnamed).size() == 1);

  // The same poses as other tools write them: ROS's x,y,z,w quaternion order with upper-case
  // names in a whitespace-separated table, KITTI's 3x4 rows (12 numbers a line).
  std::ostringstream ros, kitti;
  ros.precision(17);
  kitti.precision(17);
  ros << "T X Y Z QX QY QZ QW\n1.5\t0.4  -0.1 0.6 " << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << "\n";
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) kitti << expected.matrix()(r, c) << (r < 2 || c < 3 ? " " : "\n");
  std::istringstream in_ros(ros.str()), in_kitti(kitti.str());
  same(parse_robot_poses(in_ros, "ros.txt", RotationColumns::kUnnamed));
  same(parse_robot_poses(in_kitti, "kitti.txt", RotationColumns::kUnnamed));
  // A trajectory's rows without a header (TUM's t x y z qx qy qz qw) could be read many ways:
  // refused, asking for the columns' names; a header without x,y,z says what it does name.
  CHECK(contains(refused("# timestamp tx ty tz qx qy qz qw\n1 0.4 0 0.6 0 0 0 1\n", RotationColumns::kUnnamed),
                 "p.csv:2: 8 numbers and no header: a trajectory row"));
  CHECK(contains(refused("timestamp tx ty tz qx qy qz qw\n1 0.4 0 0.6 0 0 0 1\n", RotationColumns::kUnnamed),
                 "p.csv:1: the header has no x,y,z columns (it names timestamp,tx,ty,tz,qx,qy,qz,qw)"));
  CHECK(contains(refused("1 0 0 0 0 1 0 0 0 0 1 0\n0 0 0 1\n", RotationColumns::kUnnamed),
                 "p.csv:2: an unfinished 4x4 matrix (4 numbers)"));
}

TEST_CASE("a 17x28 board in a rendered 4K view: the primary detector, a window sized to its squares") {
  // The same scene at VGA and at 4K (6 times the focal length and image): the corner error in
  // pixels per square (the square's size in pixels) should not grow with the resolution.
  const Board board = parse_board("chessboard:17x28:0.008");
  const sim::PlanarTarget target = scenes::target_of(board);
  Eigen::Isometry3d camera_T_board = Eigen::Isometry3d::Identity();
  camera_T_board.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 0.5, 0).normalized()).toRotationMatrix();
  camera_T_board.translation() = Eigen::Vector3d(-0.07, -0.11, 0.55);
  double error_per_square[2] = {0, 0};
  for (const int scale : {1, 6}) {
    const sim::CameraSpec spec = scenes::scaled(scenes::test_camera(), scale);
    const BoardDetection d = detect_board(board, scenes::render(spec, camera_T_board, target, 5), "4k");
    CAPTURE(scale);
    REQUIRE_MESSAGE(d.found, d.reason);
    std::vector<cv::Point2f> truth;
    cv::Mat r, rvec;
    const Eigen::Matrix3d rotation = camera_T_board.rotation();
    cv::eigen2cv(rotation, r);
    cv::Rodrigues(r, rvec);
    const cv::Vec3d t(camera_T_board.translation().x(), camera_T_board.translation().y(),
                      camera_T_board.translation().z());
    cv::projectPoints(d.board_m, rvec, t, cv::Mat(model_of(spec).camera_matrix), model_of(spec).distortion_mat(),
                      truth);
    double sum = 0;
    for (std::size_t i = 0; i < truth.size(); ++i) sum += std::pow(cv::norm(truth[i] - d.image_px[i]), 2);
    const double square_px = cv::norm(truth[1] - truth[0]);
    error_per_square[scale == 1 ? 0 : 1] = std::sqrt(sum / static_cast<double>(truth.size())) / square_px;
    MESSAGE(d.detector << ": corner RMS " << std::sqrt(sum / static_cast<double>(truth.size())) << " px, square "
                       << square_px << " px");
    if (scale == 6) {
      CHECK(contains(d.detector, "findChessboardCornersSB"));
      CHECK(d.refine_half_window_px > 10);
    }
  }
  CHECK(error_per_square[1] <= 1.2 * error_per_square[0]);
}

// Issue #43: gates that must not refuse valid real data. Over every real set here -- OpenCV's
// sample views (Debian's opencv-doc, 13 left and 13 right views of a 9x6 chessboard, 640x480) and
// the variants tests/host/camera/real_corpus.hpp makes of them (crops through the board's outer
// squares, the board on another photograph's texture, rescales, a common crop that leaves one
// view's board partly outside) -- kincal's camera calibration is run as a user would, every
// refusal of valid data counted, and its held-out accuracy set beside OpenCV's recipe in the same
// run. (The shared AprilGrid set is benchmarked by its own bench.)
//
// OpenCV's recipe (modules/calib3d/misc/python/test/test_calibration.py): findChessboardCorners
// with its default flags, cornerSubPix (5, 5) with (EPS + COUNT, 30, 0.1), calibrateCamera with
// default flags.
// Held out: the views split in two halves (even and odd positions in the set); each half's
// camera predicts the other half's corners, through a pose fitted to them (solvePnP); each
// pipeline on its own corners (detection and calibration, as camera_real_bench), over the views
// both found. kincal calibrates with its gates on (calibrate_intrinsics with default options: the
// outlier gate included).
//
// FIGUREs:
//   camera_corpus_false_refusals   valid data refused: sets kincal's calibrate (either half) or
//       stereo refuses, plus views of the true 9x6 board kincal calls another board (the
//       per-view variants and the sets' views)
//   camera_corpus_worst_heldout_over_opencv   the largest, over the sets, of kincal's held-out RMS
//       over the recipe's
//   camera_corpus_views_missed   views the recipe uses that kincal does not (not found, or left out
//       by a gate), over the sets
//   camera_corpus_sets, camera_corpus_view_variants   how many sets and per-view variants were run
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "host/camera/board.hpp"
#include "host/camera/intrinsics.hpp"
#include "host/camera/stereo.hpp"
#include "tests/host/camera/real_corpus.hpp"

using namespace kincal::camera;
namespace corpus = kincal::camera::testing;

namespace {

void figure(const char* name, double value, const char* unit) { std::printf("FIGURE %s %.6g %s\n", name, value, unit); }

const cv::Size kPattern(9, 6);

// The recipe's corners of a view; empty when it does not find the board.
std::vector<cv::Point2f> recipe_corners(const cv::Mat& grey) {
  std::vector<cv::Point2f> corners;
  if (!cv::findChessboardCorners(grey, kPattern, corners)) return {};
  cv::cornerSubPix(grey, corners, cv::Size(5, 5), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.1));
  return corners;
}

std::vector<cv::Point3f> board_grid() {
  std::vector<cv::Point3f> grid;
  for (int j = 0; j < kPattern.height; ++j)
    for (int i = 0; i < kPattern.width; ++i)
      grid.emplace_back(static_cast<float>(i * corpus::kSampleSquare_m),
                        static_cast<float>(j * corpus::kSampleSquare_m), 0.0f);
  return grid;
}

// Sum of squared distances (px^2) between corners and their projection at the pose solvePnP fits.
double prediction_ssr(const cv::Mat& k, const cv::Mat& d, const std::vector<cv::Point3f>& board_m,
                      const std::vector<cv::Point2f>& image_px) {
  cv::Mat r, t;
  cv::solvePnP(board_m, image_px, k, d, r, t);
  std::vector<cv::Point2f> predicted;
  cv::projectPoints(board_m, r, t, k, d, predicted);
  double sum = 0;
  for (std::size_t i = 0; i < predicted.size(); ++i) {
    const cv::Point2f e = predicted[i] - image_px[i];
    sum += static_cast<double>(e.dot(e));
  }
  return sum;
}

struct SetResult {
  bool refused = false;
  std::string refusal;
  double kincal_px = 0, recipe_px = 0;
  int wrong_board_views = 0, missed_views = 0, views_compared = 0;
};

SetResult run_set(const corpus::RealSet& set) {
  SetResult out;
  const Board board = parse_board(corpus::kSampleBoard);
  std::vector<cv::Mat> images;
  std::vector<std::string> names;
  for (const corpus::RealView& v : set.views) {
    images.push_back(v.image);
    names.push_back(set.name + "/" + v.name);
  }
  const std::vector<BoardDetection> kincal = detect_boards(board, images, names);
  std::vector<std::vector<cv::Point2f>> recipe;
  for (const cv::Mat& image : images) recipe.push_back(recipe_corners(image));
  for (const BoardDetection& d : kincal) out.wrong_board_views += d.larger_board || !d.fitting_board.empty() ? 1 : 0;
  const cv::Size size = images.front().size();
  const std::vector<cv::Point3f> grid = board_grid();
  double kincal_ssr = 0, recipe_ssr = 0;
  std::size_t corners = 0;
  for (int half = 0; half < 2; ++half) {
    std::vector<BoardDetection> train;
    std::vector<std::vector<cv::Point3f>> recipe_board;
    std::vector<std::vector<cv::Point2f>> recipe_image;
    for (std::size_t k = 0; k < kincal.size(); ++k) {
      if (static_cast<int>(k % 2) != half) continue;
      train.push_back(kincal[k]);
      if (recipe[k].empty()) continue;
      recipe_board.push_back(grid);
      recipe_image.push_back(recipe[k]);
    }
    IntrinsicCalibration c;
    try {
      c = calibrate_intrinsics(train);
    } catch (const CalibrationError& e) {
      out.refused = true;
      out.refusal = e.what();
      return out;
    }
    for (std::size_t k = 0, t = 0; k < kincal.size(); ++k) {
      if (static_cast<int>(k % 2) != half) continue;
      if (!recipe[k].empty() && !c.views[t].used) ++out.missed_views;
      ++t;
    }
    cv::Mat recipe_k, recipe_d;
    std::vector<cv::Mat> r, tv;
    cv::calibrateCamera(recipe_board, recipe_image, size, recipe_k, recipe_d, r, tv);
    const cv::Mat kincal_k(c.camera.camera_matrix), kincal_d = c.camera.distortion_mat();
    for (std::size_t k = 0; k < kincal.size(); ++k) {
      if (static_cast<int>(k % 2) == half || !kincal[k].found || recipe[k].empty()) continue;
      kincal_ssr += prediction_ssr(kincal_k, kincal_d, kincal[k].board_m, kincal[k].image_px);
      recipe_ssr += prediction_ssr(recipe_k, recipe_d, grid, recipe[k]);
      corners += recipe[k].size();
      ++out.views_compared;
    }
  }
  out.kincal_px = std::sqrt(kincal_ssr / static_cast<double>(std::max<std::size_t>(corners, 1)));
  out.recipe_px = std::sqrt(recipe_ssr / static_cast<double>(std::max<std::size_t>(corners, 1)));
  return out;
}

}  // namespace

int main() {
  int false_refusals = 0, missed = 0;
  double worst = 0;
  const std::vector<corpus::RealSet> sets = corpus::calibration_sets();
  for (const corpus::RealSet& set : sets) {
    const SetResult r = run_set(set);
    false_refusals += (r.refused ? 1 : 0) + r.wrong_board_views;
    missed += r.missed_views;
    if (r.refused) {
      std::printf("%s: REFUSED: %s\n", set.name.c_str(), r.refusal.c_str());
      continue;
    }
    const double ratio = r.kincal_px / r.recipe_px;
    worst = std::max(worst, ratio);
    std::printf(
        "%s: %zu views, %d compared held out: kincal %.4f px, OpenCV's recipe %.4f px, ratio %.4f; %d views "
        "called another board, %d the recipe uses left out by kincal\n",
        set.name.c_str(), set.views.size(), r.views_compared, r.kincal_px, r.recipe_px, ratio, r.wrong_board_views,
        r.missed_views);
  }
  // Stereo: the pairs of the sets made the same way on both sides (not the crops: each side's
  // crop is its own, and two image sizes are two cameras).
  const Board board = parse_board(corpus::kSampleBoard);
  for (std::size_t s = 0; s < sets.size() / 2; ++s) {  // calibration_sets(): the left sets, then the right ones
    const corpus::RealSet &left = sets[s], &right = sets[s + sets.size() / 2];
    if (left.name.find("cropped") != std::string::npos) continue;
    std::vector<cv::Mat> li, ri;
    std::vector<std::string> ln, rn;
    for (const corpus::RealView& v : left.views) {
      li.push_back(v.image);
      ln.push_back(left.name + "/" + v.name);
    }
    for (const corpus::RealView& v : right.views) {
      ri.push_back(v.image);
      rn.push_back(right.name + "/" + v.name);
    }
    const std::vector<BoardDetection> ld = detect_boards(board, li, ln), rd = detect_boards(board, ri, rn);
    try {
      const StereoCalibration st =
          calibrate_stereo(ld, rd, calibrate_intrinsics(ld).camera, calibrate_intrinsics(rd).camera);
      const auto used =
          std::count_if(st.pairs.begin(), st.pairs.end(), [](const StereoPairReport& p) { return p.used; });
      std::printf("stereo %s / %s: %td pairs used, baseline %.4f m\n", left.name.c_str(), right.name.c_str(), used,
                  st.baseline_m);
    } catch (const CalibrationError& e) {
      ++false_refusals;
      std::printf("stereo %s / %s: REFUSED: %s\n", left.name.c_str(), right.name.c_str(), e.what());
    }
  }
  // The per-view variants: each alone, the true board given.
  const std::vector<corpus::RealView> variants = corpus::view_variants();
  std::vector<cv::Mat> images;
  std::vector<std::string> names;
  for (const corpus::RealView& v : variants) {
    images.push_back(v.image);
    names.push_back(v.name);
  }
  int variant_wrong = 0, variant_missed = 0;
  for (const BoardDetection& d : detect_boards(board, images, names)) {
    if (d.larger_board || !d.fitting_board.empty()) {
      ++variant_wrong;
      std::printf("%s: called another board: %s\n", d.view.c_str(), d.reason.c_str());
    } else if (!d.found) {
      ++variant_missed;
      std::printf("%s: not found: %s\n", d.view.c_str(), d.reason.c_str());
    }
  }
  false_refusals += variant_wrong;
  std::printf("per-view variants: %zu, %d called another board, %d not found\n", variants.size(), variant_wrong,
              variant_missed);
  figure("camera_corpus_false_refusals", false_refusals, "count");
  figure("camera_corpus_worst_heldout_over_opencv", worst, "ratio");
  figure("camera_corpus_views_missed", missed, "count");
  figure("camera_corpus_sets", static_cast<double>(sets.size()), "count");
  figure("camera_corpus_view_variants", static_cast<double>(variants.size()), "count");
  return 0;
}

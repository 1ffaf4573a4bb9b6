// Issue #22: does the projection uncertainty kincal writes into a camera file (host/camera/
// uncertainty.hpp) say how wrong the camera is, over the whole image?
//
// The true camera: the camera tests' (tests/host/camera/camera_scenes.hpp: 640x480, fx 610,
// k1 -0.21, k2 0.09, small tangential terms) and its 9x6 board of 30 mm squares, 0.5..0.75 m
// away, tilted 15..35 degrees; the board covers a fifth to a third of the image in each view.
// Trial t uses 10 + t % 11 views (board_views: the board wanders over the image) with corner
// noise of a known sigma, Gaussian and independent in x and y, and calibrates with
// calibrate_intrinsics (k1 k2 p1 p2 k3 free: the true lens is in the model's family).
// Then, on every 16th pixel of the whole image (40 x 30, including where no corner ever was),
// the pixel's true ray (the true camera unprojects it) is projected by the calibrated camera,
// and the error is judged by the predicted 2 x 2 covariance at that pixel: inside the 95 %
// ellipse when e^T cov^-1 e <= 5.991 (chi-square, 2 dof).
//
// FIGUREs:
//   camera_projection_uncertainty_coverage_95              fraction inside, 200 trials, projected
//       corners with sigma 0.2 px (target 0.90..0.98)
//   camera_projection_uncertainty_coverage_95_board_area   the same over the pixels within the
//       corners' convex hull in at least one view, and _off_board beyond all of them
//   camera_projection_uncertainty_mean_chi2_over_2         mean of e^T cov^-1 e / 2 (1 when the
//       covariance is right, larger when it is too small)
//   camera_corner_sigma_estimate_over_true                 the residuals' sigma over the noise's
//   camera_projection_uncertainty_not_inverted_fraction    grid pixels where the calibrated model
//       folds (does not invert; no covariance, left out of the fractions above)
//   camera_projection_uncertainty_coverage_95_rendered     the same test on 20 trials of rendered
//       and detected views (host/sim/render.hpp, 2x supersampling, blur 0.7 px, read and shot
//       noise): the corner noise is then the detector's, neither Gaussian nor known
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "host/camera/board.hpp"
#include "host/camera/intrinsics.hpp"
#include "host/camera/uncertainty.hpp"
#include "tests/host/camera/camera_scenes.hpp"

using namespace kincal;
using namespace kincal::camera;

namespace {

constexpr double kChi2_95 = 5.991464547107979;  // chi-square quantile, 2 dof, 0.95
constexpr int kStep_px = 16;

void figure(const char* name, double value, const char* unit) { std::printf("FIGURE %s %.6g %s\n", name, value, unit); }

struct Tally {
  long inside = 0, judged = 0, not_inverted = 0;
  double chi2 = 0;
  void add(double d2) {
    ++judged;
    inside += d2 <= kChi2_95 ? 1 : 0;
    chi2 += d2;
  }
  double fraction() const { return judged ? static_cast<double>(inside) / static_cast<double>(judged) : 0.0; }
};

struct Coverage {
  Tally all, board_area, off_board;
};

// Judges one calibration against the truth on the pixel grid; `board_area` marks the grid pixels
// (row-major) that lie inside some view's corner hull.
void judge(const CameraModel& truth, const IntrinsicCalibration& c, const std::vector<bool>& board_area,
           Coverage& out) {
  std::vector<cv::Point2d> pixels;
  for (int y = 0; y < truth.image_size.height; y += kStep_px)
    for (int x = 0; x < truth.image_size.width; x += kStep_px) pixels.emplace_back(x, y);
  const std::vector<cv::Point2d> estimated = reproject(truth, c.camera, pixels);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const cv::Matx22d cov = projection_covariance(c.camera, c.uncertainty, pixels[i]);
    Tally& area = board_area[i] ? out.board_area : out.off_board;
    if (!std::isfinite(cov(0, 0))) {
      ++out.all.not_inverted;
      ++area.not_inverted;
      continue;
    }
    const cv::Vec2d e(estimated[i].x - pixels[i].x, estimated[i].y - pixels[i].y);
    const double d2 = (e.t() * cov.inv() * e)(0);
    out.all.add(d2);
    area.add(d2);
  }
}

// The grid pixels inside the convex hull of some view's corners.
std::vector<bool> board_area_of(const std::vector<BoardDetection>& views, cv::Size image) {
  std::vector<bool> inside;
  std::vector<std::vector<cv::Point2f>> hulls;
  for (const BoardDetection& v : views) {
    if (!v.found) continue;
    hulls.emplace_back();
    cv::convexHull(v.image_px, hulls.back());
  }
  for (int y = 0; y < image.height; y += kStep_px) {
    for (int x = 0; x < image.width; x += kStep_px) {
      bool in = false;
      const cv::Point2f p(static_cast<float>(x), static_cast<float>(y));
      for (const auto& h : hulls) in = in || cv::pointPolygonTest(h, p, false) >= 0;
      inside.push_back(in);
    }
  }
  return inside;
}

void print(const char* what, const Tally& t) {
  std::printf("%s: %ld of %ld pixels inside the 95 %% ellipse (%.4f), mean chi2/2 %.3f, %ld not inverted\n", what,
              t.inside, t.judged, t.fraction(), t.judged ? t.chi2 / 2 / static_cast<double>(t.judged) : 0.0,
              t.not_inverted);
}

}  // namespace

int main() {
  const Board board = parse_board(scenes::chessboard_text());
  const sim::CameraSpec spec = scenes::test_camera();
  const CameraModel truth = scenes::model_of(spec);

  // Projected corners with known Gaussian noise.
  constexpr int kTrials = 200;
  constexpr double kSigma_px = 0.2;
  Coverage projected;
  double sigma_ratio_sum = 0;
  for (int t = 0; t < kTrials; ++t) {
    cv::RNG rng(static_cast<std::uint64_t>(1000 + t));
    std::vector<BoardDetection> views;
    for (const Eigen::Isometry3d& pose : scenes::board_views(board, 10 + t % 11)) {
      views.push_back(scenes::projected(board, truth, pose, "view" + std::to_string(views.size()), rng, kSigma_px));
    }
    const IntrinsicCalibration c = calibrate_intrinsics(views);
    sigma_ratio_sum += c.uncertainty.corner_sigma_px / kSigma_px;
    judge(truth, c, board_area_of(views, truth.image_size), projected);
  }
  print("projected corners, all pixels", projected.all);
  print("projected corners, board area", projected.board_area);
  print("projected corners, off the board", projected.off_board);
  figure("camera_projection_uncertainty_coverage_95", projected.all.fraction(), "fraction");
  figure("camera_projection_uncertainty_coverage_95_board_area", projected.board_area.fraction(), "fraction");
  figure("camera_projection_uncertainty_coverage_95_off_board", projected.off_board.fraction(), "fraction");
  figure("camera_projection_uncertainty_mean_chi2_over_2",
         projected.all.chi2 / 2 / static_cast<double>(projected.all.judged), "ratio");
  figure("camera_corner_sigma_estimate_over_true", sigma_ratio_sum / kTrials, "ratio");
  figure("camera_projection_uncertainty_not_inverted_fraction",
         static_cast<double>(projected.all.not_inverted) /
             static_cast<double>(projected.all.not_inverted + projected.all.judged),
         "fraction");

  // Rendered and detected views: the detector's own corner noise.
  constexpr int kRenderedTrials = 20;
  const sim::PlanarTarget target = scenes::target_of(board);
  Coverage rendered;
  for (int t = 0; t < kRenderedTrials; ++t) {
    std::vector<BoardDetection> views;
    for (const Eigen::Isometry3d& pose : scenes::board_views(board, 10 + t % 11)) {
      const cv::Mat image =
          scenes::render(spec, pose, target, static_cast<std::uint64_t>(5000 + 100 * t) + views.size());
      views.push_back(detect_board(board, image, "view" + std::to_string(views.size())));
    }
    const IntrinsicCalibration c = calibrate_intrinsics(views);
    std::printf("rendered trial %d: %d views, corner sigma %.4f px\n", t, c.views_used, c.uncertainty.corner_sigma_px);
    judge(truth, c, board_area_of(views, truth.image_size), rendered);
  }
  print("rendered views, all pixels", rendered.all);
  print("rendered views, board area", rendered.board_area);
  print("rendered views, off the board", rendered.off_board);
  figure("camera_projection_uncertainty_coverage_95_rendered", rendered.all.fraction(), "fraction");
  return 0;
}

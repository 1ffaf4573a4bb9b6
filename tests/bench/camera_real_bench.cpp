// Issue #22: kincal's camera calibration beside OpenCV's documented recipe, in one run, on real
// photographs nobody here made: OpenCV's sample views (Debian's opencv-doc, left01..14.jpg and
// right01..14.jpg, 13 views each, 640x480, a 9x6 chessboard; there is no 10).
//
// OpenCV's recipe (modules/calib3d/misc/python/test/test_calibration.py, published RMS 0.1963 px):
// findChessboardCorners with its default flags, cornerSubPix (5, 5) with (EPS + COUNT, 30, 0.1),
// calibrateCamera with no flags; for the pairs, stereoCalibrate on its corners with its two
// cameras fixed (CALIB_FIX_INTRINSIC), as kincal's `camera stereo` does with its own.
//
// FIGUREs:
//   camera_real_rms_px, camera_real_opencv_rms_px     reprojection RMS over the 13 left views
//   camera_real_heldout_rms_px, ..._opencv_heldout_rms_px, camera_real_heldout_rms_over_opencv
//       leave-one-view-out: each view's own corners predicted by the camera calibrated without
//       it (its pose by solvePnP from its corners with the held-out intrinsics); RMS over all
//       held-out corners, kincal over the recipe
//   camera_real_lens_model_difference_px, camera_real_lens_model_difference_max_px
//       the two left cameras: every 8th pixel of the image unprojected by the recipe's model
//       and projected by kincal's; RMS and largest distance
//   camera_real_lens_model_difference_aligned_px, ..._aligned_max_px   the same as mrcal compares
//       two calibrations (mrcal.projection_diff with its defaults): each solve fixes its own camera
//       frame only up to a rotation the views' poses absorb, so the rotation that best carries the
//       recipe's rays onto kincal's pixels within min(W,H)/6 of the image centre (points at
//       infinity: a rotation only) is fitted first, then the difference is taken over the image
//   camera_real_lens_model_difference_in_hull_px, ..._outside_hull_px   the same RMS over the
//       pixels inside the convex hull of all the views' corners (where the board was) and outside
//   camera_real_lens_model_difference_over_sigma   the mean of (distance / sigma)^2 over the image,
//       sigma kincal's own predicted projection sigma per axis (host/camera/uncertainty.hpp) at
//       that pixel: about 2 if the models differed by one model's own error, less when both
//       estimates share the images
//   camera_real_projection_error_expected_px   kincal's own predicted RMS distance (px) of its
//       projection from the true camera's over the image (sqrt of the mean trace of the projection
//       covariance): the scale below which no two calibrations from these 13 views can be told apart
//   camera_real_k3_effect_px, camera_real_k3_effect_in_hull_px   kincal's camera against kincal's
//       with k3 held at 0 (CALIB_FIX_K3) on the same corners: RMS over the image and inside the hull
//   camera_real_intrinsics_std_over_opencv   kincal's standard deviations of the 9 intrinsics over
//       OpenCV's stdDeviationsIntrinsics on the same corners (the same for all 9 to 1e-6)
//   camera_real_intrinsics_std_same_sigma_deviation   the largest |ratio - 1| once both use one
//       sigma (the ratio is OpenCV's N - n against kincal's 2N - n degrees of freedom)
//   camera_real_stereo_baseline_difference_pct, camera_real_stereo_rotation_difference_deg
//       kincal's right_T_left against stereoCalibrate's on the same 13 pairs
// The board's square is taken as 25 mm for both (the sample does not say; only ratios matter).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "host/camera/board.hpp"
#include "host/camera/intrinsics.hpp"
#include "host/camera/stereo.hpp"
#include "host/camera/uncertainty.hpp"

using namespace kincal::camera;

namespace {

constexpr double kSquare_m = 0.025;
const std::vector<int> kViews = {1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13, 14};

std::string sample(const char* side, int i) {
  return std::string(KINCAL_OPENCV_SAMPLES) + "/" + side + (i < 10 ? "0" : "") + std::to_string(i) + ".jpg";
}

void figure(const char* name, double value, const char* unit) { std::printf("FIGURE %s %.6g %s\n", name, value, unit); }

struct Views {
  std::vector<std::vector<cv::Point3f>> board_m;
  std::vector<std::vector<cv::Point2f>> image_px;
};

Views recipe_views(const char* side) {
  std::vector<cv::Point3f> grid;
  for (int j = 0; j < 6; ++j)
    for (int i = 0; i < 9; ++i)
      grid.emplace_back(static_cast<float>(i * kSquare_m), static_cast<float>(j * kSquare_m), 0.0f);
  Views v;
  for (int i : kViews) {
    const cv::Mat grey = cv::imread(sample(side, i), cv::IMREAD_GRAYSCALE);
    std::vector<cv::Point2f> corners;
    if (!cv::findChessboardCorners(grey, cv::Size(9, 6), corners)) {
      std::fprintf(stderr, "%s: the recipe does not find the board\n", sample(side, i).c_str());
      std::exit(1);
    }
    cv::cornerSubPix(grey, corners, cv::Size(5, 5), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.1));
    v.board_m.push_back(grid);
    v.image_px.push_back(corners);
  }
  return v;
}

std::vector<BoardDetection> kincal_views(const char* side) {
  const Board board = parse_board("chessboard:9x6:" + std::to_string(kSquare_m));
  std::vector<BoardDetection> out;
  for (int i : kViews) {
    const std::string path = sample(side, i);
    out.push_back(detect_board(board, cv::imread(path, cv::IMREAD_GRAYSCALE), path));
  }
  return out;
}

Views views_of(const std::vector<BoardDetection>& detections) {
  Views v;
  for (const BoardDetection& d : detections) {
    v.board_m.push_back(d.board_m);
    v.image_px.push_back(d.image_px);
  }
  return v;
}

// calibrateCamera with no flags; its RMS (px) into *rms_px when given.
CameraModel recipe_camera(const Views& v, double* rms_px = nullptr) {
  cv::Mat k, d;
  std::vector<cv::Mat> r, t;
  const double rms = cv::calibrateCamera(v.board_m, v.image_px, cv::Size(640, 480), k, d, r, t);
  if (rms_px) *rms_px = rms;
  CameraModel c;
  c.image_size = cv::Size(640, 480);
  c.camera_matrix = cv::Matx33d(k);
  for (int i = 0; i < 5; ++i) c.distortion[static_cast<std::size_t>(i)] = d.at<double>(i);
  return c;
}

// Sum of squared distances (px^2) between a view's corners and their projection by `camera`
// at the pose solvePnP finds from those corners.
double squared_prediction_error(const CameraModel& camera, const std::vector<cv::Point3f>& board_m,
                                const std::vector<cv::Point2f>& image_px) {
  cv::Mat r, t;
  cv::solvePnP(board_m, image_px, cv::Mat(camera.camera_matrix), camera.distortion_mat(), r, t);
  std::vector<cv::Point2f> predicted;
  cv::projectPoints(board_m, r, t, cv::Mat(camera.camera_matrix), camera.distortion_mat(), predicted);
  double sum = 0;
  for (std::size_t i = 0; i < predicted.size(); ++i) {
    const cv::Point2f e = predicted[i] - image_px[i];
    sum += static_cast<double>(e.dot(e));
  }
  return sum;
}

// Leave-one-view-out RMS (px); `calibrate` maps a list of views to a camera.
template <typename Calibrate>
double held_out_rms_px(const Views& all, Calibrate calibrate) {
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < all.board_m.size(); ++k) {
    const CameraModel camera = calibrate(k);
    sum += squared_prediction_error(camera, all.board_m[k], all.image_px[k]);
    n += all.image_px[k].size();
  }
  return std::sqrt(sum / static_cast<double>(n));
}

// mrcal's implied rotation (implied_Rt10__from_unprojections at infinity): the rotation vector r
// minimising sum |project_to(R(r) ray_from(p)) - p|^2 over `focus_px`, by Gauss-Newton on
// cv::projectPoints' Jacobian.
cv::Vec3d implied_rotation(const CameraModel& from, const CameraModel& to, const std::vector<cv::Point2d>& focus_px) {
  const std::vector<cv::Point3d> rays = rays_of(from, focus_px);
  cv::Vec3d r(0, 0, 0);
  for (int iteration = 0; iteration < 20; ++iteration) {
    std::vector<cv::Point2d> projected;
    cv::Mat jacobian;
    cv::projectPoints(rays, r, cv::Vec3d(0, 0, 0), cv::Mat(to.camera_matrix), to.distortion_mat(), projected, jacobian);
    cv::Matx33d normal = cv::Matx33d::zeros();
    cv::Vec3d gradient(0, 0, 0);
    for (std::size_t i = 0; i < projected.size(); ++i) {
      const cv::Point2d e = projected[i] - focus_px[i];
      for (int axis = 0; axis < 2; ++axis) {
        const int row = static_cast<int>(2 * i) + axis;
        const cv::Vec3d j(jacobian.at<double>(row, 0), jacobian.at<double>(row, 1), jacobian.at<double>(row, 2));
        normal += j * j.t();
        gradient += j * (axis == 0 ? e.x : e.y);
      }
    }
    const cv::Vec3d step = -(normal.inv(cv::DECOMP_CHOLESKY) * gradient);
    r += step;
    if (cv::norm(step) < 1e-12) break;
  }
  return r;
}

}  // namespace

int main() {
  const std::vector<BoardDetection> left = kincal_views("left"), right = kincal_views("right");
  const IntrinsicCalibration kincal_left = calibrate_intrinsics(left), kincal_right = calibrate_intrinsics(right);
  const Views recipe_left = recipe_views("left"), recipe_right = recipe_views("right");
  double recipe_rms_px = 0;
  const CameraModel recipe_left_camera = recipe_camera(recipe_left, &recipe_rms_px);
  figure("camera_real_rms_px", kincal_left.rms_px, "px");
  figure("camera_real_opencv_rms_px", recipe_rms_px, "px");
  std::printf("kincal uses %d of %zu views\n", kincal_left.views_used, left.size());

  // The intrinsics' standard deviations beside OpenCV's stdDeviationsIntrinsics on kincal's
  // corners: OpenCV's sigma^2 divides by N - n, kincal's by 2N - n (host/camera/uncertainty.hpp).
  {
    const Views own = views_of(left);
    cv::Mat k, d, opencv_std, std_extrinsics, per_view;
    std::vector<cv::Mat> r, t;
    cv::calibrateCamera(own.board_m, own.image_px, cv::Size(640, 480), k, d, r, t, opencv_std, std_extrinsics,
                        per_view);
    const double n = kincal_left.uncertainty.parameters, corners = kincal_left.uncertainty.corners;
    const double same_sigma = std::sqrt((2 * corners - n) / (corners - n));
    double low = 1e9, high = 0, deviation = 0;
    for (int i = 0; i < 9; ++i) {
      const double ratio = kincal_left.std_dev[static_cast<std::size_t>(i)] / opencv_std.at<double>(i);
      low = std::min(low, ratio);
      high = std::max(high, ratio);
      deviation = std::max(deviation, std::abs(ratio * same_sigma - 1));
    }
    std::printf("kincal's standard deviations over OpenCV's: %.6f..%.6f; sqrt((N - n) / (2N - n)) = %.6f\n", low, high,
                1 / same_sigma);
    figure("camera_real_intrinsics_std_over_opencv", 0.5 * (low + high), "ratio");
    figure("camera_real_intrinsics_std_same_sigma_deviation", deviation, "ratio");
  }

  const double kincal_held_px = held_out_rms_px(views_of(left), [&](std::size_t k) {
    std::vector<BoardDetection> others = left;
    others.erase(others.begin() + static_cast<std::ptrdiff_t>(k));
    return calibrate_intrinsics(others).camera;
  });
  const double recipe_held_px = held_out_rms_px(recipe_left, [&](std::size_t k) {
    Views others = recipe_left;
    others.board_m.erase(others.board_m.begin() + static_cast<std::ptrdiff_t>(k));
    others.image_px.erase(others.image_px.begin() + static_cast<std::ptrdiff_t>(k));
    return recipe_camera(others);
  });
  figure("camera_real_heldout_rms_px", kincal_held_px, "px");
  figure("camera_real_opencv_heldout_rms_px", recipe_held_px, "px");
  figure("camera_real_heldout_rms_over_opencv", kincal_held_px / recipe_held_px, "ratio");

  // The lens models over the whole image: rays of the recipe's model, projected by kincal's.
  std::vector<cv::Point2d> pixels;
  for (int y = 0; y < 480; y += 8)
    for (int x = 0; x < 640; x += 8) pixels.emplace_back(x, y);
  const std::vector<cv::Point2d> reprojected = reproject(recipe_left_camera, kincal_left.camera, pixels);
  double sum = 0, largest = 0;
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const double e = cv::norm(reprojected[i] - pixels[i]);
    sum += e * e;
    largest = std::max(largest, e);
  }
  figure("camera_real_lens_model_difference_px", std::sqrt(sum / static_cast<double>(pixels.size())), "px");
  figure("camera_real_lens_model_difference_max_px", largest, "px");
  {
    const double radius = std::min(640, 480) / 6.0;
    std::vector<cv::Point2d> focus;
    for (const cv::Point2d& p : pixels)
      if (cv::norm(p - cv::Point2d(319.5, 239.5)) <= radius) focus.push_back(p);
    const cv::Vec3d r = implied_rotation(recipe_left_camera, kincal_left.camera, focus);
    std::vector<cv::Point2d> aligned;
    cv::projectPoints(rays_of(recipe_left_camera, pixels), r, cv::Vec3d(0, 0, 0),
                      cv::Mat(kincal_left.camera.camera_matrix), kincal_left.camera.distortion_mat(), aligned);
    double aligned_sum = 0, aligned_largest = 0;
    for (std::size_t i = 0; i < pixels.size(); ++i) {
      const double e = cv::norm(aligned[i] - pixels[i]);
      aligned_sum += e * e;
      aligned_largest = std::max(aligned_largest, e);
    }
    std::printf("implied rotation between the two cameras: %.4f deg (%zu focus pixels)\n", cv::norm(r) * 180 / CV_PI,
                focus.size());
    figure("camera_real_lens_model_difference_aligned_px", std::sqrt(aligned_sum / static_cast<double>(pixels.size())),
           "px");
    figure("camera_real_lens_model_difference_aligned_max_px", aligned_largest, "px");
  }

  // Where the board was: the convex hull of every used corner. How far apart the models are
  // inside and outside it, against kincal's own projection uncertainty, and what k3 does.
  {
    std::vector<cv::Point2f> corners, hull;
    for (const BoardDetection& d : left) corners.insert(corners.end(), d.image_px.begin(), d.image_px.end());
    cv::convexHull(corners, hull);
    const auto inside = [&](const cv::Point2d& p) {
      return cv::pointPolygonTest(hull, cv::Point2f(static_cast<float>(p.x), static_cast<float>(p.y)), false) >= 0;
    };
    IntrinsicOptions no_k3;
    no_k3.flags = cv::CALIB_FIX_K3;
    const std::vector<cv::Point2d> without_k3 =
        reproject(kincal_left.camera, calibrate_intrinsics(left, no_k3).camera, pixels);
    double in_sum = 0, out_sum = 0, z_sum = 0, trace_sum = 0, k3_sum = 0, k3_in_sum = 0;
    int in_count = 0, z_count = 0;
    for (std::size_t i = 0; i < pixels.size(); ++i) {
      const double e2 = std::pow(cv::norm(reprojected[i] - pixels[i]), 2),
                   k3 = std::pow(cv::norm(without_k3[i] - pixels[i]), 2);
      const bool in = inside(pixels[i]);
      (in ? in_sum : out_sum) += e2;
      in_count += in ? 1 : 0;
      k3_sum += k3;
      k3_in_sum += in ? k3 : 0;
      const cv::Matx22d c = projection_covariance(kincal_left.camera, kincal_left.uncertainty, pixels[i]);
      if (const double sigma2 = 0.5 * (c(0, 0) + c(1, 1)); std::isfinite(sigma2)) {
        z_sum += e2 / sigma2;
        trace_sum += 2 * sigma2;
        ++z_count;
      }
    }
    const double n = static_cast<double>(pixels.size());
    std::printf("%d of %zu pixels inside the corners' hull\n", in_count, pixels.size());
    figure("camera_real_lens_model_difference_in_hull_px", std::sqrt(in_sum / in_count), "px");
    figure("camera_real_lens_model_difference_outside_hull_px", std::sqrt(out_sum / (n - in_count)), "px");
    figure("camera_real_lens_model_difference_over_sigma", z_sum / z_count, "ratio");
    figure("camera_real_projection_error_expected_px", std::sqrt(trace_sum / z_count), "px");
    figure("camera_real_k3_effect_px", std::sqrt(k3_sum / n), "px");
    figure("camera_real_k3_effect_in_hull_px", std::sqrt(k3_in_sum / in_count), "px");
  }

  // The 13 pairs.
  const StereoCalibration s = calibrate_stereo(left, right, kincal_left.camera, kincal_right.camera);
  const CameraModel recipe_right_camera = recipe_camera(recipe_right);
  cv::Mat k1(recipe_left_camera.camera_matrix), d1 = recipe_left_camera.distortion_mat();
  cv::Mat k2(recipe_right_camera.camera_matrix), d2 = recipe_right_camera.distortion_mat();
  cv::Mat rotation, translation, essential, fundamental;
  const double recipe_stereo_rms_px =
      cv::stereoCalibrate(recipe_left.board_m, recipe_left.image_px, recipe_right.image_px, k1, d1, k2, d2,
                          cv::Size(640, 480), rotation, translation, essential, fundamental, cv::CALIB_FIX_INTRINSIC);
  const double recipe_baseline_m = cv::norm(translation);
  cv::Vec3d difference;
  cv::Rodrigues(s.right_R_left * cv::Matx33d(rotation).t(), difference);
  std::printf("stereo: kincal baseline %.6f m RMS %.4f px; stereoCalibrate baseline %.6f m RMS %.4f px\n", s.baseline_m,
              s.rms_px, recipe_baseline_m, recipe_stereo_rms_px);
  figure("camera_real_stereo_baseline_difference_pct", 100 * std::abs(s.baseline_m / recipe_baseline_m - 1), "%");
  figure("camera_real_stereo_rotation_difference_deg", cv::norm(difference) * 180 / CV_PI, "deg");
  return 0;
}

#include "host/camera/intrinsics.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <sstream>

#include <opencv2/calib3d.hpp>

#include "host/camera/number_text.hpp"

namespace kincal::camera {

namespace {

std::string size_text(cv::Size s) { return std::to_string(s.width) + "x" + std::to_string(s.height); }

constexpr int kGridCols = 8, kGridRows = 6;

// The RMS distance (px) between two detections' image corners when they saw the same board
// corners in the same order, or a negative number when they did not.
double same_corners_rms_px(const BoardDetection& a, const BoardDetection& b) {
  if (a.board_m != b.board_m || a.image_px.empty()) return -1.0;
  double sum = 0.0;
  for (std::size_t i = 0; i < a.image_px.size(); ++i) {
    const cv::Point2f d = a.image_px[i] - b.image_px[i];
    sum += static_cast<double>(d.dot(d));
  }
  return std::sqrt(sum / static_cast<double>(a.image_px.size()));
}

// Where a view puts the board, from the homography of the board's plane to its corners: the
// board centre's image position (per image width and height), the log of its scale (px per m)
// and its tilt (the homography's perspective row times the board's extent). What the views of a
// calibration should spread over; nullopt when no homography fits.
std::optional<std::array<double, 5>> view_place(const BoardDetection& d) {
  std::vector<cv::Point2f> plane;
  cv::Point2f board_mean(0, 0), image_mean(0, 0);
  for (const cv::Point3f& p : d.board_m) plane.emplace_back(p.x, p.y);
  for (std::size_t i = 0; i < plane.size(); ++i) {
    board_mean += plane[i];
    image_mean += d.image_px[i];
  }
  const float n = static_cast<float>(plane.size());
  board_mean /= n;
  image_mean /= n;
  double board_spread = 0.0, image_spread = 0.0;
  for (std::size_t i = 0; i < plane.size(); ++i) {
    board_spread += static_cast<double>((plane[i] - board_mean).dot(plane[i] - board_mean));
    image_spread += static_cast<double>((d.image_px[i] - image_mean).dot(d.image_px[i] - image_mean));
  }
  const cv::Mat h = plane.size() >= 4 && d.image_size.area() > 0 ? cv::findHomography(plane, d.image_px) : cv::Mat();
  if (h.empty() || board_spread <= 0.0 || image_spread <= 0.0 || std::abs(h.at<double>(2, 2)) < 1e-12)
    return std::nullopt;
  const double extent = std::sqrt(board_spread / static_cast<double>(n));
  return std::array<double, 5>{
      static_cast<double>(image_mean.x) / d.image_size.width, static_cast<double>(image_mean.y) / d.image_size.height,
      0.5 * std::log(image_spread / board_spread), h.at<double>(2, 0) / h.at<double>(2, 2) * extent,
      h.at<double>(2, 1) / h.at<double>(2, 2) * extent};
}

// At most `count` of `views` (indices into detections), the most spread over view_place's
// dimensions (each scaled by its standard deviation over the views): farthest-point sampling
// from the view farthest from the mean, in the order chosen. Views without a place come last.
std::vector<std::size_t> spread_views(const std::vector<BoardDetection>& detections,
                                      const std::vector<std::size_t>& views, std::size_t count) {
  std::vector<std::size_t> placed, unplaced;
  std::vector<std::array<double, 5>> place;
  for (std::size_t v : views) {
    const std::optional<std::array<double, 5>> p = view_place(detections[v]);
    (p ? placed : unplaced).push_back(v);
    if (p) place.push_back(*p);
  }
  std::array<double, 5> mean{}, scale{};
  for (const auto& p : place)
    for (std::size_t k = 0; k < 5; ++k) mean[k] += p[k] / static_cast<double>(place.size());
  for (const auto& p : place)
    for (std::size_t k = 0; k < 5; ++k) scale[k] += (p[k] - mean[k]) * (p[k] - mean[k]);
  for (double& s : scale)
    s = std::max(std::sqrt(s / static_cast<double>(std::max<std::size_t>(place.size(), 1))), 1e-9);
  const auto distance = [&](const std::array<double, 5>& a, const std::array<double, 5>& b) {
    double sum = 0.0;
    for (std::size_t k = 0; k < 5; ++k) sum += (a[k] - b[k]) * (a[k] - b[k]) / (scale[k] * scale[k]);
    return sum;
  };
  std::vector<double> nearest(place.size());
  for (std::size_t i = 0; i < place.size(); ++i) nearest[i] = distance(place[i], mean);
  std::vector<std::size_t> chosen;
  std::vector<bool> taken(place.size(), false);
  while (chosen.size() < count && chosen.size() < place.size()) {
    std::size_t best = 0;
    double far = -1.0;
    for (std::size_t i = 0; i < place.size(); ++i)
      if (!taken[i] && nearest[i] > far) far = nearest[best = i];
    taken[best] = true;
    chosen.push_back(placed[best]);
    for (std::size_t i = 0; i < place.size(); ++i) nearest[i] = std::min(nearest[i], distance(place[i], place[best]));
  }
  for (std::size_t v : unplaced)
    if (chosen.size() < count) chosen.push_back(v);
  return chosen;
}

// A view's corners predicted by `camera`: the sum of squared distances (px^2) between them and
// their projection at the pose cv::solvePnP fits to them.
double prediction_ssr(const cv::Mat& camera_matrix, const cv::Mat& distortion, const BoardDetection& d) {
  cv::Mat r, t;
  cv::solvePnP(d.board_m, d.image_px, camera_matrix, distortion, r, t);
  std::vector<cv::Point2f> predicted;
  cv::projectPoints(d.board_m, r, t, camera_matrix, distortion, predicted);
  double sum = 0.0;
  for (std::size_t i = 0; i < predicted.size(); ++i) {
    const cv::Point2f e = predicted[i] - d.image_px[i];
    sum += static_cast<double>(e.dot(e));
  }
  return sum;
}

// Leave-views-out (see the header): the views of `judged` in `folds` folds (the k-th in fold
// k % folds), each fold's views predicted by the camera calibrated on the other folds' views and
// `also`; per judged view, its held-out squared error per corner (px^2), in the order of `judged`.
std::vector<double> held_out_errors(const std::vector<BoardDetection>& detections,
                                    const std::vector<std::size_t>& judged, const std::vector<std::size_t>& also,
                                    std::size_t folds, int flags, cv::Size image_size) {
  std::vector<double> out(judged.size(), 0.0);
  for (std::size_t fold = 0; fold < folds; ++fold) {
    std::vector<std::vector<cv::Point3f>> object_points;
    std::vector<std::vector<cv::Point2f>> image_points;
    const auto train = [&](std::size_t v) {
      object_points.push_back(detections[v].board_m);
      image_points.push_back(detections[v].image_px);
    };
    for (std::size_t k = 0; k < judged.size(); ++k)
      if (k % folds != fold) train(judged[k]);
    for (std::size_t v : also) train(v);
    cv::Mat camera_matrix, distortion;
    std::vector<cv::Mat> rvecs, tvecs;
    cv::calibrateCamera(object_points, image_points, image_size, camera_matrix, distortion, rvecs, tvecs, flags);
    for (std::size_t k = 0; k < judged.size(); ++k) {
      if (k % folds != fold) continue;
      const BoardDetection& d = detections[judged[k]];
      out[k] = prediction_ssr(camera_matrix, distortion, d) / static_cast<double>(d.image_px.size());
    }
  }
  return out;
}

double rms_of(const std::vector<double>& squared) {
  double sum = 0.0;
  for (double e : squared) sum += e;
  return std::sqrt(sum / static_cast<double>(std::max<std::size_t>(squared.size(), 1)));
}

}  // namespace

cv::Mat CameraModel::distortion_mat() const {
  cv::Mat d(1, 5, CV_64F);
  for (int i = 0; i < 5; ++i) d.at<double>(0, i) = distortion[static_cast<std::size_t>(i)];
  return d;
}

namespace {

// The board text most detections give in `field` (fitting_board or seen_board), with how many give
// it and how many different texts they give; nullopt when none gives one.
struct BoardVote {
  std::string board;
  int views = 0, sizes = 0;
};
std::optional<BoardVote> most_given(const std::vector<BoardDetection>& detections, std::string BoardDetection::*field) {
  std::map<std::string, int> votes;
  for (const BoardDetection& d : detections)
    if (!(d.*field).empty()) ++votes[d.*field];
  const auto most =
      std::max_element(votes.begin(), votes.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
  if (most == votes.end()) return std::nullopt;
  return BoardVote{most->first, most->second, static_cast<int>(votes.size())};
}

}  // namespace

void refuse_wrong_board(const std::vector<BoardDetection>& detections) {
  const auto wrong = [](const BoardDetection& d) { return d.larger_board || !d.fitting_board.empty(); };
  const auto count = std::count_if(detections.begin(), detections.end(), wrong);
  const auto showing =
      count + std::count_if(detections.begin(), detections.end(), [](const BoardDetection& d) { return d.found; });
  // Enough views must show it (see the header): else those that do are left out as not found.
  if (count == 0 || (count < showing && (count < kMinWrongBoardViews || count * kWrongBoardShare < showing))) return;
  // The view to name: the first measuring the size most views measured, else the first wrong one.
  const std::optional<BoardVote> most = most_given(detections, &BoardDetection::fitting_board);
  const auto named = std::find_if(detections.begin(), detections.end(), [&](const BoardDetection& d) {
    return most ? d.fitting_board == most->board : wrong(d);
  });
  throw CalibrationError(named->view + ": " + named->reason + " (" + std::to_string(count) + " of " +
                         std::to_string(detections.size()) + " views show another board" +
                         (most && most->sizes > 1 ? ", " + std::to_string(most->views) + " of them this size" : "") +
                         ")");
}

std::string seen_board_hint(const std::vector<BoardDetection>& detections) {
  const std::optional<BoardVote> most = most_given(detections, &BoardDetection::seen_board);
  if (!most) return "";
  return "\n  " + std::to_string(most->views) + " of " + std::to_string(detections.size()) + " views show a board " +
         most->board + ": give --board " + most->board + "?";
}

void refuse_other_image_sizes(const std::vector<BoardDetection>& detections, cv::Size expected,
                              const std::string& whose) {
  std::string others;
  int count = 0;
  for (const BoardDetection& d : detections) {
    if (d.image_size.area() == 0 || d.image_size == expected) continue;
    if (++count <= 5) others += "\n  " + d.view + ": " + size_text(d.image_size);
  }
  if (count == 0) return;
  throw CalibrationError(std::to_string(count) + " images are not " + size_text(expected) + " like " + whose +
                         " (another camera or another resolution):" + others + (count > 5 ? "\n  ..." : ""));
}

IntrinsicCalibration calibrate_intrinsics(const std::vector<BoardDetection>& detections,
                                          const IntrinsicOptions& options) {
  refuse_wrong_board(detections);
  const auto first_found =
      std::find_if(detections.begin(), detections.end(), [](const BoardDetection& d) { return d.found; });
  if (first_found != detections.end()) refuse_other_image_sizes(detections, first_found->image_size, first_found->view);
  IntrinsicCalibration result;
  std::vector<std::size_t> used;  // indices into detections and result.views
  for (const BoardDetection& d : detections) {
    ViewReport v;
    v.view = d.view;
    v.detector = d.detector;
    v.corners = static_cast<int>(d.image_px.size());
    if (!d.found) {
      v.rejection = d.reason;
    } else if (d.board_m.size() != d.image_px.size()) {
      v.rejection = "detection without board coordinates";
    } else if (const auto twin = std::find_if(used.begin(), used.end(),
                                              [&](std::size_t u) {
                                                const double rms = same_corners_rms_px(d, detections[u]);
                                                return rms >= 0.0 && rms < kDuplicateViewRms_px;
                                              });
               twin != used.end()) {
      v.rejection = "a near-duplicate of " + detections[*twin].view + " (the same corners within " +
                    fixed(same_corners_rms_px(d, detections[*twin]), 3) + " px RMS, less than " +
                    fixed(kDuplicateViewRms_px, 1) + " px)";
    } else {
      v.used = true;
      used.push_back(result.views.size());
    }
    result.views.push_back(std::move(v));
  }
  if (used.size() > static_cast<std::size_t>(options.max_views)) {
    // The solve's cost grows with the cube of the views (a video gives thousands): the most spread.
    const std::size_t found = used.size();
    std::vector<std::size_t> spread = spread_views(detections, used, static_cast<std::size_t>(options.max_views));
    std::sort(spread.begin(), spread.end());
    for (std::size_t u : used)
      if (!std::binary_search(spread.begin(), spread.end(), u)) {
        result.views[u].used = false;
        result.views[u].rejection = "not needed: " + std::to_string(found) + " views passed, and the " +
                                    std::to_string(options.max_views) +
                                    " most spread over the image, distances and tilts are solved on";
      }
    used = spread;
  }
  const auto refuse_if_too_few = [&] {
    result.views_used = static_cast<int>(used.size());
    if (result.views_used >= options.min_views) return;
    std::string message = "intrinsic calibration: " + std::to_string(result.views_used) + " usable views of " +
                          std::to_string(detections.size()) + ", at least " + std::to_string(options.min_views) +
                          " needed";
    for (const ViewReport& v : result.views) {
      if (!v.used) message += "\n  " + v.view + ": " + v.rejection;
    }
    throw CalibrationError(message + seen_board_hint(detections));
  };
  refuse_if_too_few();
  const cv::Size image_size = detections[used.front()].image_size;

  cv::Mat camera_matrix, distortion, per_view;
  std::vector<cv::Mat> rvecs, tvecs;
  const auto solve = [&] {
    std::vector<std::vector<cv::Point3f>> object_points;
    std::vector<std::vector<cv::Point2f>> image_points;
    for (std::size_t u : used) {
      object_points.push_back(detections[u].board_m);
      image_points.push_back(detections[u].image_px);
    }
    cv::Mat std_intrinsics, std_extrinsics;
    result.rms_px = cv::calibrateCamera(object_points, image_points, image_size, camera_matrix, distortion, rvecs,
                                        tvecs, std_intrinsics, std_extrinsics, per_view, options.flags);
  };
  solve();
  // The outlier gate (see the header): candidates by their RMS, each left out only when the
  // other views' held-out error says so; then one more solve.
  std::vector<double> sorted(per_view.begin<double>(), per_view.end<double>());
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  const double median_px = sorted[sorted.size() / 2];
  const double limit_px = std::max(options.outlier_over_median * median_px, options.outlier_floor_px);
  std::vector<std::size_t> candidates, others;  // indices into `used`
  for (std::size_t k = 0; k < used.size(); ++k)
    (per_view.at<double>(static_cast<int>(k)) > limit_px ? candidates : others).push_back(k);
  std::vector<std::size_t> judged, all_candidates, kept, outliers;  // indices into detections
  for (std::size_t k : others) judged.push_back(used[k]);
  for (std::size_t k : candidates) all_candidates.push_back(used[k]);
  kept = judged;
  // The views judged: those below the limit, in options.outlier_folds folds of at least two views,
  // each fold's complement (without any candidate) enough to calibrate on.
  const std::size_t folds = static_cast<std::size_t>(std::max(2, options.outlier_folds));
  const std::size_t largest_fold = (judged.size() + folds - 1) / folds;
  const bool can_judge = judged.size() >= 2 * folds &&
                         judged.size() - largest_fold >= static_cast<std::size_t>(std::max(3, options.min_views));
  std::vector<double> with_all;
  if (can_judge && !candidates.empty())
    with_all = held_out_errors(detections, judged, all_candidates, folds, options.flags, image_size);
  for (std::size_t k : candidates) {
    const double rms_px = per_view.at<double>(static_cast<int>(k));
    ViewReport& v = result.views[used[k]];
    v.rms_px = rms_px;
    const std::string above = "RMS " + fixed(rms_px, 3) + " px, more than " + fixed(limit_px, 3) + " px (" +
                              fixed(options.outlier_over_median, 0) + " times the median view's " +
                              fixed(median_px, 3) + " px, at least " + fixed(options.outlier_floor_px, 2) + " px)";
    if (!can_judge) {
      kept.push_back(used[k]);
      v.outlier_test = "kept: " + above + ", but too few other views (" + std::to_string(others.size()) +
                       ") to show by cross-validation that leaving it out helps";
      continue;
    }
    std::vector<std::size_t> rest;
    for (std::size_t c : all_candidates)
      if (c != used[k]) rest.push_back(c);
    const std::vector<double> without = held_out_errors(detections, judged, rest, folds, options.flags, image_size);
    // Paired over the judged views: the mean change of their held-out squared error and its
    // standard error; left out only when it drops by two standard errors (a tie keeps the view).
    double mean = 0.0, variance = 0.0;
    const double n = static_cast<double>(without.size());
    for (std::size_t i = 0; i < without.size(); ++i) mean += (without[i] - with_all[i]) / n;
    for (std::size_t i = 0; i < without.size(); ++i) variance += std::pow(without[i] - with_all[i] - mean, 2) / (n - 1);
    const bool lowers = mean < 0 && mean <= -2.0 * std::sqrt(variance / n);
    const std::string numbers = "the other views' held-out RMS (" + std::to_string(folds) +
                                "-fold leave-views-out) is " + fixed(rms_of(with_all), 3) + " px with it, " +
                                fixed(rms_of(without), 3) + " px without";
    if (lowers) {
      outliers.push_back(used[k]);
      v.used = false;
      v.rejection = "an outlier: " + above + " and " + numbers + ": a bad detection or a moved board";
    } else {
      kept.push_back(used[k]);
      v.outlier_test = "kept: " + above + ", but " + numbers +
                       " (leaving it out does not lower it by two standard errors): its residuals cost the others "
                       "nothing (often a close or steep view, where the lens model fits least)";
    }
  }
  std::sort(kept.begin(), kept.end());
  if (!outliers.empty()) {
    if (static_cast<double>(outliers.size()) > options.max_outlier_fraction * static_cast<double>(used.size())) {
      std::string message = "intrinsic calibration: " + std::to_string(outliers.size()) + " of " +
                            std::to_string(used.size()) + " views are outliers (more than " +
                            fixed(100 * options.max_outlier_fraction, 0) +
                            " %): the views do not fit one camera (another camera, a zoomed or refocused lens, or a "
                            "bent board)";
      for (std::size_t o : outliers) message += "\n  " + result.views[o].view + ": " + result.views[o].rejection;
      throw CalibrationError(message);
    }
    used = kept;
    refuse_if_too_few();
    solve();
  }
  result.camera.image_size = image_size;
  result.camera.camera_matrix = cv::Matx33d(camera_matrix);
  for (int i = 0; i < 5; ++i) result.camera.distortion[static_cast<std::size_t>(i)] = distortion.at<double>(i);

  double max_tilt_rad = 0;
  std::vector<bool> cells(kGridCols * kGridRows, false);
  for (std::size_t k = 0; k < used.size(); ++k) {
    ViewReport& v = result.views[used[k]];
    v.rms_px = per_view.at<double>(static_cast<int>(k));
    v.camera_r_board = cv::Vec3d(rvecs[k]);
    v.camera_t_board_m = cv::Vec3d(tvecs[k]);
    // Tilt: the angle between the board's normal and the camera's optical axis.
    cv::Matx33d r;
    cv::Rodrigues(v.camera_r_board, r);
    max_tilt_rad = std::max(max_tilt_rad, std::acos(std::min(1.0, std::abs(r(2, 2)))));
    for (const cv::Point2f& p : detections[used[k]].image_px) {
      const int cx =
          std::clamp(static_cast<int>(p.x * kGridCols / static_cast<float>(image_size.width)), 0, kGridCols - 1);
      const int cy =
          std::clamp(static_cast<int>(p.y * kGridRows / static_cast<float>(image_size.height)), 0, kGridRows - 1);
      cells[static_cast<std::size_t>(cy * kGridCols + cx)] = true;
    }
  }
  result.coverage =
      static_cast<double>(std::count(cells.begin(), cells.end(), true)) / static_cast<double>(cells.size());
  std::vector<SolvedView> solved;
  for (std::size_t k = 0; k < used.size(); ++k) {
    const ViewReport& v = result.views[used[k]];
    solved.push_back(
        {&detections[used[k]].board_m, &detections[used[k]].image_px, v.camera_r_board, v.camera_t_board_m});
  }
  result.uncertainty = intrinsics_covariance(result.camera, solved, options.flags);
  for (int i = 0; i < 9; ++i)
    result.std_dev[static_cast<std::size_t>(i)] = std::sqrt(result.uncertainty.covariance(i, i));

  if (result.views_used < options.recommended_views) {
    result.warnings.push_back("only " + std::to_string(result.views_used) + " views used; " +
                              std::to_string(options.recommended_views) + " or more give reliable distortion");
  }
  if (result.coverage < options.min_coverage) {
    result.warnings.push_back("the corners cover " + fixed(100 * result.coverage, 0) + " % of the image (cells of " +
                              std::to_string(kGridCols) + "x" + std::to_string(kGridRows) + "), less than " +
                              fixed(100 * options.min_coverage, 0) +
                              " %: distortion near the edges is extrapolated; add views with the board near the "
                              "image corners");
  }
  if (max_tilt_rad < options.min_tilt_rad) {
    result.warnings.push_back("the board is never tilted more than " + fixed(max_tilt_rad * 180 / CV_PI, 1) +
                              " degrees (at least " + fixed(options.min_tilt_rad * 180 / CV_PI, 0) +
                              " wanted): focal length and distance are confounded; add tilted views");
  }
  return result;
}

std::string describe(const IntrinsicCalibration& c) {
  static constexpr std::array<const char*, 9> kNames = {"fx_px", "fy_px", "cx_px", "cy_px", "k1",
                                                        "k2",    "p1",    "p2",    "k3"};
  const cv::Matx33d& k = c.camera.camera_matrix;
  const std::array<double, 9> values = {k(0, 0),
                                        k(1, 1),
                                        k(0, 2),
                                        k(1, 2),
                                        c.camera.distortion[0],
                                        c.camera.distortion[1],
                                        c.camera.distortion[2],
                                        c.camera.distortion[3],
                                        c.camera.distortion[4]};
  std::ostringstream out;
  out << "image: " << size_text(c.camera.image_size) << "\n";
  out << "views used: " << c.views_used << " of " << c.views.size() << "\n";
  out << "reprojection RMS: " << fixed(c.rms_px, 4) << " px\n";
  for (std::size_t i = 0; i < kNames.size(); ++i) {
    out << kNames[i] << ": " << general(values[i]) << " +- " << general(c.std_dev[i]) << "\n";
  }
  out << "corner sigma (from the residuals): " << fixed(c.uncertainty.corner_sigma_px, 4) << " px\n";
  const ProjectionSigmaGrid grid = projection_sigma_grid(c.camera, c.uncertainty, 16, 12);
  std::vector<double> sigmas;
  cv::Point largest_at;
  double largest_px = 0;
  for (int r = 0; r < grid.sigma_px.rows; ++r) {
    for (int col = 0; col < grid.sigma_px.cols; ++col) {
      const double s = grid.sigma_px.at<double>(r, col);
      if (!std::isfinite(s)) continue;
      sigmas.push_back(s);
      if (s > largest_px) {
        largest_px = s;
        largest_at = {col, r};
      }
    }
  }
  if (!sigmas.empty()) {
    std::nth_element(sigmas.begin(), sigmas.begin() + static_cast<std::ptrdiff_t>(sigmas.size() / 2), sigmas.end());
    out << "projection sigma over the image (worst axis, 16x12 grid): median " << fixed(sigmas[sigmas.size() / 2], 3)
        << " px, largest " << fixed(largest_px, 3) << " px at ("
        << fixed(grid.x_px[static_cast<std::size_t>(largest_at.x)], 0) << ", "
        << fixed(grid.y_px[static_cast<std::size_t>(largest_at.y)], 0) << ")\n";
  }
  out << "coverage: " << fixed(100 * c.coverage, 0) << " %\n";
  for (const ViewReport& v : c.views) {
    out << "view " << v.view << ": ";
    if (v.used) {
      out << v.corners << " corners, RMS " << fixed(v.rms_px, 4) << " px (" << v.detector << ")"
          << (v.outlier_test.empty() ? "" : "; " + v.outlier_test) << "\n";
    } else {
      out << "rejected: " << v.rejection << "\n";
    }
  }
  for (const std::string& w : c.warnings) out << "warning: " << w << "\n";
  return out.str();
}

}  // namespace kincal::camera

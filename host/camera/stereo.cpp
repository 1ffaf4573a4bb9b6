#include "host/camera/stereo.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include <opencv2/calib3d.hpp>

#include "host/camera/number_text.hpp"

namespace kincal::camera {

namespace {

// right_T_left from one pair's own board poses (cv::solvePnP in each camera).
struct PairPose {
  cv::Matx33d right_R_left;
  cv::Vec3d right_t_left_m;
  double board_distance_m = 0;  // the board's origin from the left camera
};

std::optional<PairPose> pair_pose(const std::vector<cv::Point3f>& board_m, const std::vector<cv::Point2f>& left_px,
                                  const std::vector<cv::Point2f>& right_px, const CameraModel& left,
                                  const CameraModel& right) {
  cv::Vec3d rl, tl, rr, tr;
  if (!cv::solvePnP(board_m, left_px, cv::Mat(left.camera_matrix), left.distortion_mat(), rl, tl) ||
      !cv::solvePnP(board_m, right_px, cv::Mat(right.camera_matrix), right.distortion_mat(), rr, tr))
    return std::nullopt;
  cv::Matx33d left_R_board, right_R_board;
  cv::Rodrigues(rl, left_R_board);
  cv::Rodrigues(rr, right_R_board);
  const cv::Matx33d r = right_R_board * left_R_board.t();
  return PairPose{r, tr - r * tl, cv::norm(tl)};
}

double angle_between_rad(const cv::Matx33d& a, const cv::Matx33d& b) {
  cv::Vec3d v;
  cv::Rodrigues(a * b.t(), v);
  return cv::norm(v);
}

// RMS distance (px) of each corner from its match's epipolar line (see StereoPairReport).
double epipolar_rms_px(const CameraModel& left, const CameraModel& right, const cv::Matx33d& fundamental,
                       const std::vector<cv::Point2f>& left_px, const std::vector<cv::Point2f>& right_px) {
  const auto undistorted = [](const CameraModel& camera, const std::vector<cv::Point2f>& px) {
    CameraModel pinhole = camera;
    pinhole.distortion = {};
    return reproject(camera, pinhole, std::vector<cv::Point2d>(px.begin(), px.end()));
  };
  const std::vector<cv::Point2d> l = undistorted(left, left_px), r = undistorted(right, right_px);
  std::vector<cv::Vec3d> in_right, in_left;  // lines a x + b y + c = 0 with a^2 + b^2 = 1
  cv::computeCorrespondEpilines(l, 1, fundamental, in_right);
  cv::computeCorrespondEpilines(r, 2, fundamental, in_left);
  double sum2 = 0;
  for (std::size_t i = 0; i < l.size(); ++i) {
    const double dr = in_right[i].dot(cv::Vec3d(r[i].x, r[i].y, 1)), dl = in_left[i].dot(cv::Vec3d(l[i].x, l[i].y, 1));
    sum2 += dr * dr + dl * dl;
  }
  return std::sqrt(sum2 / (2.0 * static_cast<double>(l.size())));
}

// How many pairs of the pair-consistency gate's largest agreeing group its message names.
constexpr std::size_t kNamedGroupPairs = 4;

double median_of(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// The pair-consistency gate (see the header). Each used pair's own pose (index as `used`) is
// returned, its distance from the consensus written into result.pairs.
std::vector<std::optional<PairPose>> refuse_disagreeing_pairs(StereoCalibration& result,
                                                              const std::vector<std::size_t>& used,
                                                              const std::vector<std::vector<cv::Point3f>>& board_m,
                                                              const std::vector<std::vector<cv::Point2f>>& left_px,
                                                              const std::vector<std::vector<cv::Point2f>>& right_px,
                                                              const StereoOptions& options) {
  std::vector<std::optional<PairPose>> own(used.size());
  std::vector<PairPose> poses;
  std::vector<std::size_t> posed;  // indices into used
  for (std::size_t k = 0; k < used.size(); ++k) {
    own[k] = pair_pose(board_m[k], left_px[k], right_px[k], result.left, result.right);
    if (own[k]) {
      poses.push_back(*own[k]);
      posed.push_back(k);
      result.pairs[used[k]].posed = true;
      result.pairs[used[k]].consensus_distance = std::numeric_limits<double>::quiet_NaN();
    }
  }
  if (poses.size() < 3) return own;
  // How far pose a is from pose b, in units of the gate's limits (above 1: disagrees).
  const auto distance = [&](const PairPose& a, const PairPose& b) {
    return std::max(angle_between_rad(a.right_R_left, b.right_R_left) / options.max_pair_rotation_rad,
                    cv::norm(a.right_t_left_m - b.right_t_left_m) /
                        (options.max_pair_translation_fraction * cv::norm(b.right_t_left_m)));
  };
  // The consensus: the pose most others agree with (within distance 1), the smallest median
  // distance among equals.
  std::size_t consensus_index = 0;
  std::ptrdiff_t most_agreeing = 0;
  double best_median = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < poses.size(); ++i) {
    std::vector<double> d;
    for (const PairPose& other : poses) d.push_back(distance(other, poses[i]));
    const std::ptrdiff_t agreeing = std::count_if(d.begin(), d.end(), [](double x) { return x <= 1; });
    const double m = median_of(d);
    if (agreeing > most_agreeing || (agreeing == most_agreeing && m < best_median)) {
      most_agreeing = agreeing;
      best_median = m;
      consensus_index = i;
    }
  }
  const PairPose& consensus = poses[consensus_index];
  // No baseline to measure the pairs' translations against (the same images left and right, or
  // one camera twice): the baseline check after the solve refuses it, saying so.
  if (cv::norm(consensus.right_t_left_m) < kMinBaselineOverBoardDistance * consensus.board_distance_m) return own;
  std::vector<std::size_t> bad, group;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const double d = distance(poses[i], consensus);
    result.pairs[used[posed[i]]].consensus_distance = d;
    (d > 1 ? bad : group).push_back(i);
  }
  if (bad.empty()) return own;
  const auto pair_name = [&](std::size_t i) {
    const StereoPairReport& p = result.pairs[used[posed[i]]];
    return p.left_view + " / " + p.right_view;
  };
  const PairPose& first = poses[bad.front()];
  std::string message = "stereo calibration: pair " + pair_name(bad.front()) +
                        " disagrees with the others: its right_T_left (from its own board poses) differs from " +
                        (2 * group.size() > poses.size() ? "the consensus (pair " + pair_name(consensus_index) + ")"
                                                         : "that of pair " + pair_name(consensus_index)) +
                        " by " + fixed(angle_between_rad(first.right_R_left, consensus.right_R_left) * 180 / CV_PI, 2) +
                        " degrees and " + fixed(cv::norm(first.right_t_left_m - consensus.right_t_left_m), 4) +
                        " m (at most " + fixed(options.max_pair_rotation_rad * 180 / CV_PI, 1) + " degrees and " +
                        fixed(100 * options.max_pair_translation_fraction, 0) + " % of the baseline " +
                        fixed(cv::norm(consensus.right_t_left_m), 4) + " m); " + std::to_string(bad.size()) + " of " +
                        std::to_string(poses.size()) + " pairs disagree";
  // Without a majority the consensus is only the largest group: say which pairs it holds, so a
  // list shifted part-way shows where the pairs still agree.
  if (group.size() == 1) {
    message += ", no two pairs agree";
  } else if (2 * group.size() <= poses.size()) {
    message += ", no majority agrees: the largest group that does is " + std::to_string(group.size()) + " pairs (";
    for (std::size_t k = 0; k < group.size() && k < kNamedGroupPairs; ++k)
      message += (k > 0 ? ", " : "") + pair_name(group[k]);
    message += group.size() > kNamedGroupPairs ? ", ...)" : ")";
  }
  throw CalibrationError(message + ": the left and right lists are shifted or mismatched, or the cameras moved");
}

}  // namespace

StereoCalibration calibrate_stereo(const std::vector<BoardDetection>& left, const std::vector<BoardDetection>& right,
                                   const CameraModel& left_camera, const CameraModel& right_camera,
                                   const StereoOptions& options) {
  if (left.size() != right.size()) {
    throw CalibrationError("stereo calibration: " + std::to_string(left.size()) + " left views but " +
                           std::to_string(right.size()) + " right views");
  }
  if (left_camera.image_size != right_camera.image_size) {
    throw CalibrationError("stereo calibration: the cameras' image sizes differ");
  }
  refuse_wrong_board(left);
  refuse_wrong_board(right);
  refuse_other_image_sizes(left, left_camera.image_size, "the left camera's calibration");
  refuse_other_image_sizes(right, right_camera.image_size, "the right camera's calibration");
  StereoCalibration result;
  result.left = left_camera;
  result.right = right_camera;
  std::vector<std::vector<cv::Point3f>> object_points;
  std::vector<std::vector<cv::Point2f>> left_points, right_points;
  std::vector<std::size_t> used;
  for (std::size_t i = 0; i < left.size(); ++i) {
    const BoardDetection& l = left[i];
    const BoardDetection& r = right[i];
    StereoPairReport p{l.view, r.view, false, {}, 0, 0};
    if (!l.found || !r.found) {
      p.rejection = !l.found ? l.view + ": " + l.reason : r.view + ": " + r.reason;
    } else {
      std::map<int, std::size_t> right_index;
      for (std::size_t k = 0; k < r.ids.size(); ++k) right_index[r.ids[k]] = k;
      std::vector<cv::Point3f> obj;
      std::vector<cv::Point2f> lp, rp;
      for (std::size_t k = 0; k < l.ids.size(); ++k) {
        const auto it = right_index.find(l.ids[k]);
        if (it == right_index.end()) continue;
        obj.push_back(l.board_m[k]);
        lp.push_back(l.image_px[k]);
        rp.push_back(r.image_px[it->second]);
      }
      p.common_corners = static_cast<int>(obj.size());
      if (p.common_corners < options.min_common_corners) {
        p.rejection = "too few corners seen by both cameras (" + std::to_string(p.common_corners) + ", at least " +
                      std::to_string(options.min_common_corners) + ")";
      } else {
        p.used = true;
        object_points.push_back(std::move(obj));
        left_points.push_back(std::move(lp));
        right_points.push_back(std::move(rp));
        used.push_back(result.pairs.size());
      }
    }
    result.pairs.push_back(std::move(p));
  }
  if (static_cast<int>(used.size()) < options.min_pairs) {
    std::string message = "stereo calibration: " + std::to_string(used.size()) + " usable pairs of " +
                          std::to_string(left.size()) + ", at least " + std::to_string(options.min_pairs) + " needed";
    for (const StereoPairReport& p : result.pairs) {
      if (!p.used) message += "\n  " + p.left_view + " / " + p.right_view + ": " + p.rejection;
    }
    std::vector<BoardDetection> both = left;
    both.insert(both.end(), right.begin(), right.end());
    throw CalibrationError(message + seen_board_hint(both));
  }

  const std::vector<std::optional<PairPose>> own_poses =
      refuse_disagreeing_pairs(result, used, object_points, left_points, right_points, options);

  cv::Mat k1(left_camera.camera_matrix), k2(right_camera.camera_matrix);
  cv::Mat d1 = left_camera.distortion_mat(), d2 = right_camera.distortion_mat();
  cv::Mat r, t, e, f, per_view;
  const int flags = options.refine_intrinsics ? cv::CALIB_USE_INTRINSIC_GUESS : cv::CALIB_FIX_INTRINSIC;
  result.rms_px = cv::stereoCalibrate(object_points, left_points, right_points, k1, d1, k2, d2, left_camera.image_size,
                                      r, t, e, f, per_view, flags,
                                      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-10));
  result.left.camera_matrix = cv::Matx33d(k1);
  result.right.camera_matrix = cv::Matx33d(k2);
  for (int i = 0; i < 5; ++i) {
    result.left.distortion[static_cast<std::size_t>(i)] = d1.at<double>(i);
    result.right.distortion[static_cast<std::size_t>(i)] = d2.at<double>(i);
  }
  result.right_R_left = cv::Matx33d(r);
  result.right_t_left_m = cv::Vec3d(t);
  result.baseline_m = cv::norm(result.right_t_left_m);
  std::vector<double> distances_m;
  for (std::size_t k = 0; k < object_points.size(); ++k) {
    cv::Mat rvec, tvec;
    if (cv::solvePnP(object_points[k], left_points[k], k1, d1, rvec, tvec)) distances_m.push_back(cv::norm(tvec));
  }
  if (!distances_m.empty()) {
    std::nth_element(distances_m.begin(), distances_m.begin() + static_cast<std::ptrdiff_t>(distances_m.size() / 2),
                     distances_m.end());
    const double distance_m = distances_m[distances_m.size() / 2];
    if (result.baseline_m < kMinBaselineOverBoardDistance * distance_m)
      throw CalibrationError("stereo calibration: baseline " + fixed(result.baseline_m, 6) + " m is " +
                             fixed(100 * result.baseline_m / distance_m, 3) + " % of the board's median distance " +
                             fixed(distance_m, 3) + " m (at least " + fixed(100 * kMinBaselineOverBoardDistance, 1) +
                             " %): the same images left and right, or one camera twice");
  }
  result.essential = cv::Matx33d(e);
  result.fundamental = cv::Matx33d(f);
  for (std::size_t k = 0; k < used.size(); ++k) {
    StereoPairReport& p = result.pairs[used[k]];
    // OpenCV gives the RMS of each camera per view; the pair's RMS is over both images.
    p.left_rms_px = per_view.at<double>(static_cast<int>(k), 0);
    p.right_rms_px = per_view.at<double>(static_cast<int>(k), 1);
    p.rms_px = std::sqrt(0.5 * (p.left_rms_px * p.left_rms_px + p.right_rms_px * p.right_rms_px));
    p.epipolar_rms_px = epipolar_rms_px(result.left, result.right, result.fundamental, left_points[k], right_points[k]);
    if (own_poses[k]) {
      p.pose_rotation_rad = angle_between_rad(own_poses[k]->right_R_left, result.right_R_left);
      p.pose_translation_m = cv::norm(own_poses[k]->right_t_left_m - result.right_t_left_m);
    }
  }
  std::vector<double> pair_rms;
  for (std::size_t u : used) pair_rms.push_back(result.pairs[u].rms_px);
  const double limit_px = std::max(options.outlier_over_median * median_of(pair_rms), options.outlier_floor_px);
  result.pair_rms_limit_px = limit_px;
  for (std::size_t u : used) {
    const StereoPairReport& p = result.pairs[u];
    if (p.rms_px > limit_px)
      throw CalibrationError("stereo calibration: pair " + p.left_view + " / " + p.right_view + " has RMS " +
                             fixed(p.rms_px, 3) + " px, more than " + fixed(limit_px, 3) + " px (" +
                             fixed(options.outlier_over_median, 0) + " times the median pair's, at least " +
                             fixed(options.outlier_floor_px, 2) +
                             " px): its corners do not fit the stereo geometry (a mismatched pair, or the board "
                             "moved between the two exposures)");
  }
  if (options.left_intrinsics != nullptr && options.right_intrinsics != nullptr && !options.refine_intrinsics) {
    std::vector<StereoView> views;
    for (std::size_t k = 0; k < object_points.size(); ++k)
      views.push_back({&object_points[k], &left_points[k], &right_points[k]});
    result.pose_uncertainty =
        stereo_pose_covariance(result.left, result.right, result.right_R_left, result.right_t_left_m, views,
                               options.left_intrinsics, options.right_intrinsics);
  }
  cv::Mat r1, r2, p1, p2, q;
  cv::stereoRectify(k1, d1, k2, d2, left_camera.image_size, r, t, r1, r2, p1, p2, q, cv::CALIB_ZERO_DISPARITY, 0);
  result.rectify_left = cv::Matx33d(r1);
  result.rectify_right = cv::Matx33d(r2);
  result.projection_left = cv::Matx34d(p1);
  result.projection_right = cv::Matx34d(p2);
  result.disparity_to_depth = cv::Matx44d(q);
  return result;
}

std::string describe(const StereoCalibration& c) {
  std::ostringstream out;
  out << "pairs used: "
      << std::count_if(c.pairs.begin(), c.pairs.end(), [](const StereoPairReport& p) { return p.used; }) << " of "
      << c.pairs.size() << "\n";
  out << "reprojection RMS: " << fixed(c.rms_px, 4) << " px\n";
  out << "baseline: " << fixed(c.baseline_m, 6) << " m\n";
  out << "right_t_left: " << fixed(c.right_t_left_m[0], 6) << " " << fixed(c.right_t_left_m[1], 6) << " "
      << fixed(c.right_t_left_m[2], 6) << " m\n";
  // The right camera's centre in the left camera's frame: left of it (x < 0, mostly along x) is
  // a valid rig, but more often the two lists given the wrong way round.
  const cv::Vec3d right_centre = -(c.right_R_left.t() * c.right_t_left_m);
  if (right_centre[0] < 0 && std::abs(right_centre[0]) > std::max(std::abs(right_centre[1]), std::abs(right_centre[2])))
    out << "note: the right camera's centre is " << fixed(-right_centre[0], 4)
        << " m to the left of the left camera's (x right in its image): if so mounted, fine; otherwise the left "
           "and right images are swapped\n";
  cv::Vec3d rotation;
  cv::Rodrigues(c.right_R_left, rotation);
  out << "right_R_left: " << fixed(cv::norm(rotation) * 180 / CV_PI, 4) << " degrees\n";
  if (c.pose_uncertainty) {
    const cv::Matx66d& v = c.pose_uncertainty->covariance;
    const cv::Vec3d along = c.right_t_left_m / c.baseline_m;
    double baseline_variance = 0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) baseline_variance += along[i] * v(3 + i, 3 + j) * along[j];
    out << "baseline sigma (with the intrinsics' uncertainty): " << fixed(1e3 * std::sqrt(baseline_variance), 4)
        << " mm\n";
    out << "right_R_left sigma about x y z: " << fixed(std::sqrt(v(0, 0)) * 180 / CV_PI, 4) << " "
        << fixed(std::sqrt(v(1, 1)) * 180 / CV_PI, 4) << " " << fixed(std::sqrt(v(2, 2)) * 180 / CV_PI, 4)
        << " degrees\n";
  }
  for (const StereoPairReport& p : c.pairs) {
    out << "pair " << p.left_view << " / " << p.right_view << ": ";
    if (p.used) {
      out << p.common_corners << " corners, RMS " << fixed(p.rms_px, 4) << " px\n";
    } else {
      out << "rejected: " << p.rejection << "\n";
    }
  }
  return out.str();
}

}  // namespace kincal::camera

#include "host/cli/camera_report.hpp"

#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <utility>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "host/report/report.hpp"
#include "host/report/svg_plot.hpp"

namespace kincal::cli {

namespace {

constexpr int kGridCols = 16, kGridRows = 12;
constexpr double kDeg = 180 / CV_PI;

// describe()'s lines but those starting with `listed` (the items the page's table or plots show).
std::vector<std::string> facts_of(const std::string& description, const std::string& listed) {
  std::vector<std::string> facts;
  std::istringstream text(description);
  for (std::string line; std::getline(text, line);) {
    if (line.rfind(listed, 0) != 0) facts.push_back(line);
  }
  return facts;
}

std::string file_name(const std::string& path) { return std::filesystem::path(path).filename().string(); }

report::CameraReport image_report(const camera::CameraModel& camera, std::string title) {
  report::CameraReport r;
  r.title = std::move(title);
  r.date = report::utc_date_now();
  r.width_px = camera.image_size.width;
  r.height_px = camera.image_size.height;
  return r;
}

// A view's corners and their residuals (detected - projected) with the board at (r, t).
report::CameraReportView residual_view(std::string name, const camera::CameraModel& camera,
                                       const camera::BoardDetection& d, const cv::Vec3d& camera_r_board,
                                       const cv::Vec3d& camera_t_board_m, double rms_px) {
  std::vector<cv::Point2d> projected;
  cv::projectPoints(std::vector<cv::Point3d>(d.board_m.begin(), d.board_m.end()), camera_r_board, camera_t_board_m,
                    cv::Mat(camera.camera_matrix), camera.distortion_mat(), projected);
  report::CameraReportView out{std::move(name), {}, {}, {}, {}, rms_px};
  for (std::size_t i = 0; i < projected.size(); ++i) {
    const cv::Point2d detected = d.image_px[i];
    out.x_px.push_back(detected.x);
    out.y_px.push_back(detected.y);
    out.dx_px.push_back(detected.x - projected[i].x);
    out.dy_px.push_back(detected.y - projected[i].y);
  }
  return out;
}

// The distortion field and, with a covariance, the projection sigma on the report's grid.
void add_lens(report::CameraReport& r, const camera::CameraModel& camera,
              const std::optional<camera::IntrinsicsCovariance>& uncertainty) {
  std::vector<cv::Point2d> pixels;
  if (uncertainty) {
    const camera::ProjectionSigmaGrid grid = camera::projection_sigma_grid(camera, *uncertainty, kGridCols, kGridRows);
    r.sigma_x_px = grid.x_px;
    r.sigma_y_px = grid.y_px;
    r.sigma_px.assign(grid.sigma_px.begin<double>(), grid.sigma_px.end<double>());
  }
  // The field on the grid's cell centres (projection_sigma_grid's): the pinhole camera's pixel
  // -> its distorted pixel.
  for (int row = 0; row < kGridRows; ++row) {
    for (int col = 0; col < kGridCols; ++col) {
      pixels.emplace_back((col + 0.5) * camera.image_size.width / kGridCols - 0.5,
                          (row + 0.5) * camera.image_size.height / kGridRows - 0.5);
    }
  }
  camera::CameraModel pinhole = camera;
  pinhole.distortion = {};
  const std::vector<cv::Point2d> distorted = camera::reproject(pinhole, camera, pixels);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    r.field_x_px.push_back(pixels[i].x);
    r.field_y_px.push_back(pixels[i].y);
    r.field_dx_px.push_back(distorted[i].x - pixels[i].x);
    r.field_dy_px.push_back(distorted[i].y - pixels[i].y);
  }
}

std::string number_or_dash(bool given, double v, int decimals) { return given ? report::fixed_text(v, decimals) : "-"; }

}  // namespace

report::CameraReport camera_report(const camera::IntrinsicCalibration& c,
                                   const std::vector<camera::BoardDetection>& detections) {
  report::CameraReport r = image_report(c.camera, "Camera calibration");
  // The summary: describe()'s lines up to the per-view list, which the plots show.
  r.facts = facts_of(camera::describe(c), "view ");
  for (std::size_t k = 0; k < c.views.size() && k < detections.size(); ++k) {
    const camera::ViewReport& v = c.views[k];
    if (!v.used) continue;
    r.views.push_back(
        residual_view(file_name(v.view), c.camera, detections[k], v.camera_r_board, v.camera_t_board_m, v.rms_px));
  }
  add_lens(r, c.camera, c.uncertainty);
  return r;
}

report::CameraReport lens_report(const camera::CameraModel& camera,
                                 const std::optional<camera::IntrinsicsCovariance>& uncertainty,
                                 const std::string& source) {
  report::CameraReport r = image_report(camera, "Camera");
  r.facts.push_back("from " + source + " (its views and residuals are in its own calibrate report)");
  if (!uncertainty) r.facts.push_back("the file holds no intrinsics_covariance: no projection uncertainty");
  add_lens(r, camera, uncertainty);
  return r;
}

report::CameraPage stereo_report(const camera::StereoCalibration& s, const camera::StereoOptions& options,
                                 report::CameraReport left, report::CameraReport right) {
  report::CameraPage page{"Stereo calibration", report::utc_date_now(), facts_of(camera::describe(s), "pair "), {}, {}};
  report::TextTable pairs{"Pairs",
                          {"left / right", "status", "corners", "RMS left (px)", "RMS right (px)", "epipolar RMS (px)",
                           "own right_T_left vs calibrated: rotation (deg)", "translation (mm)",
                           "distance from the consensus (gate: at most 1)"},
                          {},
                          {}};
  for (const camera::StereoPairReport& p : s.pairs) {
    const std::string name = file_name(p.left_view) + " / " + file_name(p.right_view);
    if (!p.used) {
      pairs.rows.push_back(
          {name, "left out: " + p.rejection, std::to_string(p.common_corners), "-", "-", "-", "-", "-", "-"});
      continue;
    }
    pairs.rows.push_back({name, "used", std::to_string(p.common_corners), report::fixed_text(p.left_rms_px, 3),
                          report::fixed_text(p.right_rms_px, 3), report::fixed_text(p.epipolar_rms_px, 3),
                          number_or_dash(p.posed, p.pose_rotation_rad * kDeg, 3),
                          number_or_dash(p.posed, p.pose_translation_m * 1e3, 2),
                          number_or_dash(p.posed && std::isfinite(p.consensus_distance), p.consensus_distance, 2)});
  }
  pairs.note =
      "Epipolar RMS: each corner's distance from its match's epipolar line, both ways, undistorted. Own right_T_left: "
      "the pair's board poses in each camera (solvePnP) composed; its distance from the consensus pair's is in units "
      "of the gate's limits (" +
      report::fixed_text(options.max_pair_rotation_rad * kDeg, 1) + " degrees, " +
      report::fixed_text(100 * options.max_pair_translation_fraction, 0) +
      " % of the baseline; '-' when fewer than 3 pairs were posed). The gates refuse the calibration, naming the "
      "pair, when a pair's distance exceeds 1 or its RMS over both images exceeds " +
      report::fixed_text(s.pair_rms_limit_px, 3) + " px (" + report::fixed_text(options.outlier_over_median, 0) +
      " times the median pair's, at least " + report::fixed_text(options.outlier_floor_px, 2) +
      " px); no report is written then. Pairs left out had no board in one image or too few corners seen by both.";
  page.tables.push_back({"pairs", std::move(pairs)});
  left.title = "Left camera";
  right.title = "Right camera";
  page.cameras = {std::move(left), std::move(right)};
  return page;
}

report::CameraPage hand_eye_report(const camera::HandEyeCalibration& h, const std::vector<camera::HandEyeView>& views,
                                   const camera::CameraModel& camera) {
  report::CameraPage page{
      "Hand-eye calibration", report::utc_date_now(), facts_of(camera::describe(h), "view "), {}, {}};
  for (const std::string& w : h.warnings) page.facts.push_back("warning: " + w);
  report::TextTable poses{"Poses",
                          {"view", "status", "board pose RMS (px)", "refined RMS (px)", "AX = XB rotation (deg)",
                           "AX = XB translation (mm)", "AX = ZB loop rotation (deg)", "AX = ZB loop translation (mm)"},
                          {},
                          "Board pose RMS: the corners at the view's own board pose (solvePnP). Refined RMS: at the "
                          "board pose the refined hand-eye and base_T_target give. AX = XB: RMS over the pairs of "
                          "poses holding this one. AX = ZB loop: base_T_target^-1 base_T_gripper gripper_T_camera "
                          "camera_T_target, its angle and translation. Views left out are named with the reason."};
  report::CameraReport corners = image_report(camera, "Board corners at the refined hand-eye and board pose");
  for (std::size_t i = 0; i < h.views.size() && i < views.size(); ++i) {
    const camera::HandEyeViewReport& v = h.views[i];
    if (!v.used) {
      poses.rows.push_back({v.view, "left out: " + v.rejection, "-", "-", "-", "-", "-", "-"});
      continue;
    }
    poses.rows.push_back(
        {v.view, "used", report::fixed_text(v.board_rms_px, 3), report::fixed_text(v.refined_rms_px, 3),
         report::fixed_text(v.pair_rotation_rms_rad * kDeg, 4), report::fixed_text(v.pair_translation_rms_m * 1e3, 3),
         report::fixed_text(v.loop_rotation_rad * kDeg, 4), report::fixed_text(v.loop_translation_m * 1e3, 3)});
    cv::Matx33d rotation;
    cv::eigen2cv(Eigen::Matrix3d(v.refined_camera_T_target.rotation()), rotation);
    cv::Vec3d r;
    cv::Rodrigues(rotation, r);
    const Eigen::Vector3d t = v.refined_camera_T_target.translation();
    corners.views.push_back(residual_view(file_name(views[i].detection.view), camera, views[i].detection, r,
                                          cv::Vec3d(t.x(), t.y(), t.z()), v.refined_rms_px));
  }
  page.tables.push_back({"poses", std::move(poses)});
  page.cameras.push_back(std::move(corners));
  return page;
}

}  // namespace kincal::cli

#include "host/cli/camera_report.hpp"

#include <filesystem>
#include <sstream>
#include <string>

#include <opencv2/calib3d.hpp>

#include "host/camera/uncertainty.hpp"
#include "host/report/report.hpp"

namespace kincal::cli {

namespace {

constexpr int kGridCols = 16, kGridRows = 12;

}  // namespace

report::CameraReport camera_report(const camera::IntrinsicCalibration& c,
                                   const std::vector<camera::BoardDetection>& detections) {
  report::CameraReport r;
  r.date = report::utc_date_now();
  r.width_px = c.camera.image_size.width;
  r.height_px = c.camera.image_size.height;
  // The summary: describe()'s lines up to the per-view list, which the plots show.
  std::istringstream text(camera::describe(c));
  for (std::string line; std::getline(text, line);) {
    if (line.rfind("view ", 0) != 0) r.facts.push_back(line);
  }
  for (std::size_t k = 0; k < c.views.size() && k < detections.size(); ++k) {
    const camera::ViewReport& v = c.views[k];
    if (!v.used) continue;
    const camera::BoardDetection& d = detections[k];
    std::vector<cv::Point2d> projected;
    cv::projectPoints(std::vector<cv::Point3d>(d.board_m.begin(), d.board_m.end()), v.camera_r_board,
                      v.camera_t_board_m, cv::Mat(c.camera.camera_matrix), c.camera.distortion_mat(), projected);
    report::CameraReportView out{std::filesystem::path(v.view).filename().string(), {}, {}, {}, {}, v.rms_px};
    for (std::size_t i = 0; i < projected.size(); ++i) {
      const cv::Point2d detected = d.image_px[i];
      out.x_px.push_back(detected.x);
      out.y_px.push_back(detected.y);
      out.dx_px.push_back(detected.x - projected[i].x);
      out.dy_px.push_back(detected.y - projected[i].y);
    }
    r.views.push_back(std::move(out));
  }
  const camera::ProjectionSigmaGrid grid = camera::projection_sigma_grid(c.camera, c.uncertainty, kGridCols, kGridRows);
  r.sigma_x_px = grid.x_px;
  r.sigma_y_px = grid.y_px;
  r.sigma_px.assign(grid.sigma_px.begin<double>(), grid.sigma_px.end<double>());
  // The distortion field on the same grid: the pinhole camera's pixel -> its distorted pixel.
  camera::CameraModel pinhole = c.camera;
  pinhole.distortion = {};
  std::vector<cv::Point2d> pixels;
  for (double y : grid.y_px)
    for (double x : grid.x_px) pixels.emplace_back(x, y);
  const std::vector<cv::Point2d> distorted = camera::reproject(pinhole, c.camera, pixels);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    r.field_x_px.push_back(pixels[i].x);
    r.field_y_px.push_back(pixels[i].y);
    r.field_dx_px.push_back(distorted[i].x - pixels[i].x);
    r.field_dy_px.push_back(distorted[i].y - pixels[i].y);
  }
  return r;
}

}  // namespace kincal::cli

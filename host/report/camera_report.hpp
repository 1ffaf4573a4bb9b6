// The camera calibration report (issue #22): one self-contained HTML page (report.hpp's style,
// inline SVG) that shows a user where a camera calibration is weak and where more views of the
// board are needed, from plain numbers (host/cli/camera_report.cpp fills it from host/camera).
//
// Sections, each a <section class="..."> with its plots (<svg class="plot">):
//   summary      the facts given (model, RMS, corner sigma, views) as lines of text;
//   residuals    each corner's residual (detected - projected, px) drawn as a vector from the
//                corner, magnified by a stated factor, every view in its own colour (all views
//                overlaid: a view whose vectors line up is badly modelled or badly detected);
//   coverage     every used corner over the image frame: empty regions are extrapolated;
//   distortion   the lens's displacement (distorted - pinhole projection, px) on a grid, drawn
//                to a stated scale;
//   uncertainty  the worst-axis projection sigma (px) on a grid over the image, dots coloured
//                by range (legend), the largest named.
// A section whose data are not given is left out (no views: no residuals or coverage; no field:
// no distortion; no sigma grid: no uncertainty).
// Image coordinates are drawn with rows growing downward as in the image (the y axis shows
// the row counted from the top, negated).
//
// A camera page (stereo, hand-eye: CameraPage) holds its own summary and tables (report.hpp's
// TextTable), then each camera's sections under the camera's title.
//
// Errors: ReportError for a non-finite coordinate or residual, vectors of unequal lengths, a
// grid whose sigma count is not cols x rows, an image size of 0; write_camera_report also for an
// unwritable file (its path named). Cost: O(corners + grid points).
#pragma once

#include <string>
#include <vector>

#include "host/report/report.hpp"

namespace kincal::report {

struct CameraReportView {
  std::string name;
  std::vector<double> x_px, y_px;    // detected corners
  std::vector<double> dx_px, dy_px;  // residual: detected - projected by the calibrated camera
  double rms_px = 0.0;
};

struct CameraReport {
  std::string title = "Camera calibration";
  std::string date;
  int width_px = 0, height_px = 0;
  std::vector<std::string> facts;
  std::vector<CameraReportView> views;  // used views only
  // The distortion field: at (field_x_px[i], field_y_px[i]) the displacement (field_dx_px,
  // field_dy_px) from the pinhole projection to the distorted one.
  std::vector<double> field_x_px, field_y_px, field_dx_px, field_dy_px;
  // The projection sigma grid (row-major, sigma_y_px.size() rows of sigma_x_px.size(); NaN where
  // the model does not invert, shown as such).
  std::vector<double> sigma_x_px, sigma_y_px, sigma_px;
};

std::string render_camera_html(const CameraReport& report);
void write_camera_report(const CameraReport& report, const std::string& path);

struct CameraPageTable {
  std::string id;  // the section's id
  TextTable table;
};

struct CameraPage {
  std::string title;
  std::string date;
  std::vector<std::string> facts;
  std::vector<CameraPageTable> tables;
  std::vector<CameraReport> cameras;  // each under its title (its date unused)
};

std::string render_camera_page_html(const CameraPage& page);
void write_camera_page(const CameraPage& page, const std::string& path);

}  // namespace kincal::report

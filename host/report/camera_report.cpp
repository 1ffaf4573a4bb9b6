#include "host/report/camera_report.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "host/report/report.hpp"
#include "host/report/svg_plot.hpp"

namespace kincal::report {

namespace {

constexpr std::array<const char*, 8> kViewColours = {"#d95f02", "#7570b3", "#1b9e77", "#e7298a",
                                                     "#66a61e", "#e6ab02", "#a6761d", "#666666"};

void require_that(bool ok, const std::string& what) {
  if (!ok) throw ReportError("camera report: " + what);
}

// A plot of the image frame, rows downward (y drawn as -row).
PlotSpec image_plot(const CameraReport& r, const std::string& title) {
  PlotSpec p;
  p.title = title;
  p.x = {"column (px)", false, {}, -0.5, r.width_px - 0.5};
  p.y = {"row (px, negated: downward as in the image)", false, {}, -(r.height_px - 0.5), 0.5};
  p.width_px = 560;
  p.height_px = 420;
  p.equal_aspect = true;
  return p;
}

// One two-point polyline per vector, from (x, y) to (x + scale dx, y + scale dy); the first of
// each group carries the legend name.
void add_vectors(PlotSpec& p, const std::string& name, const char* colour, const std::vector<double>& x,
                 const std::vector<double>& y, const std::vector<double>& dx, const std::vector<double>& dy,
                 double scale) {
  require_that(x.size() == y.size() && x.size() == dx.size() && x.size() == dy.size(),
               name + ": positions and vectors differ in number");
  for (std::size_t i = 0; i < x.size(); ++i) {
    p.series.push_back(
        {i == 0 ? name : "", colour, {x[i], x[i] + scale * dx[i]}, {-y[i], -(y[i] + scale * dy[i])}, true});
  }
}

// The scale that draws the largest vector `length_px` long.
double scale_for(const std::vector<double>& dx, const std::vector<double>& dy, double length_px) {
  double largest = 0;
  for (std::size_t i = 0; i < dx.size(); ++i) largest = std::max(largest, std::hypot(dx[i], dy[i]));
  return largest > 0 ? length_px / largest : 1.0;
}

std::string camera_section(const char* cls, const std::string& title, const std::string& text, const std::string& svg) {
  return std::string("<section class=\"") + cls + "\"><h3>" + escape_html(title) + "</h3><p>" + escape_html(text) +
         "</p><div class=\"plots\">" + svg + "</div></section>";
}

std::string residual_section(const CameraReport& r) {
  std::vector<double> all_dx, all_dy;
  for (const CameraReportView& v : r.views) {
    all_dx.insert(all_dx.end(), v.dx_px.begin(), v.dx_px.end());
    all_dy.insert(all_dy.end(), v.dy_px.begin(), v.dy_px.end());
  }
  const double scale = scale_for(all_dx, all_dy, 0.04 * r.width_px);
  PlotSpec p = image_plot(r, "Residuals of every corner, all views");
  for (std::size_t k = 0; k < r.views.size(); ++k) {
    const CameraReportView& v = r.views[k];
    add_vectors(p, v.name + " (" + fixed_text(v.rms_px, 3) + " px)", kViewColours[k % kViewColours.size()], v.x_px,
                v.y_px, v.dx_px, v.dy_px, scale);
  }
  p.notes.push_back("vectors magnified " + fixed_text(scale, 0) + " times");
  return camera_section("residuals", "Residuals",
                        "Each corner's residual (detected minus projected) drawn from the corner. Vectors that line up "
                        "across a region or a view point to a lens the model does not follow or a bad detection.",
                        svg_plot(p));
}

std::string coverage_section(const CameraReport& r) {
  PlotSpec p = image_plot(r, "Corners used, over the image");
  PlotSeries dots{"corners", "#1b9e77", {}, {}, false};
  for (const CameraReportView& v : r.views) {
    for (std::size_t i = 0; i < v.x_px.size(); ++i) {
      dots.x.push_back(v.x_px[i]);
      dots.y.push_back(-v.y_px[i]);
    }
  }
  p.series.push_back(std::move(dots));
  return camera_section(
      "coverage", "Coverage",
      "Where the corners were. The lens model is extrapolated in empty regions: add views with the board "
      "there.",
      svg_plot(p));
}

std::string distortion_section(const CameraReport& r) {
  const double scale = scale_for(r.field_dx_px, r.field_dy_px, 0.06 * r.width_px);
  double largest = 0;
  for (std::size_t i = 0; i < r.field_dx_px.size(); ++i)
    largest = std::max(largest, std::hypot(r.field_dx_px[i], r.field_dy_px[i]));
  PlotSpec p = image_plot(r, "Distortion field");
  add_vectors(p, "displacement", "#7570b3", r.field_x_px, r.field_y_px, r.field_dx_px, r.field_dy_px, scale);
  p.notes.push_back("largest displacement " + fixed_text(largest, 1) + " px, drawn " + fixed_text(scale, 2) + " times");
  return camera_section("distortion", "Distortion",
                        "How far the lens moves each point from where a pinhole camera would see it.", svg_plot(p));
}

std::string uncertainty_section(const CameraReport& r) {
  require_that(r.sigma_px.size() == r.sigma_x_px.size() * r.sigma_y_px.size(), "the sigma grid is not cols x rows");
  constexpr std::array<double, 4> kBounds = {0.1, 0.25, 0.5, 1.0};
  constexpr std::array<const char*, 6> kColours = {"#1a9850", "#91cf60", "#fee08b", "#fc8d59", "#d73027", "#999999"};
  std::array<PlotSeries, 6> bins;
  for (std::size_t b = 0; b < bins.size(); ++b) {
    bins[b].colour = kColours[b];
    bins[b].name = b == 5   ? "model does not invert"
                   : b == 0 ? "below " + fixed_text(kBounds[0], 2) + " px"
                   : b == 4 ? fixed_text(kBounds[3], 2) + " px and more"
                            : fixed_text(kBounds[b - 1], 2) + " to " + fixed_text(kBounds[b], 2) + " px";
  }
  double largest = 0, largest_x = 0, largest_y = 0;
  for (std::size_t row = 0; row < r.sigma_y_px.size(); ++row) {
    for (std::size_t col = 0; col < r.sigma_x_px.size(); ++col) {
      const double s = r.sigma_px[row * r.sigma_x_px.size() + col];
      std::size_t b = 5;
      if (std::isfinite(s)) {
        b = static_cast<std::size_t>(std::upper_bound(kBounds.begin(), kBounds.end(), s) - kBounds.begin());
        if (s > largest) {
          largest = s;
          largest_x = r.sigma_x_px[col];
          largest_y = r.sigma_y_px[row];
        }
      }
      bins[b].x.push_back(r.sigma_x_px[col]);
      bins[b].y.push_back(-r.sigma_y_px[row]);
    }
  }
  PlotSpec p = image_plot(r, "Projection uncertainty (worst-axis sigma)");
  for (PlotSeries& b : bins) {
    if (!b.x.empty()) p.series.push_back(std::move(b));
  }
  p.notes.push_back("largest " + fixed_text(largest, 3) + " px at (" + fixed_text(largest_x, 0) + ", " +
                    fixed_text(largest_y, 0) + ")");
  return camera_section(
      "uncertainty", "Projection uncertainty",
      "How well the ray of each pixel is known: the intrinsics' covariance (view poses marginalised, corner "
      "noise from the residuals) propagated to the projection. Large values show where more views are "
      "needed.",
      svg_plot(p));
}

std::string summary_section(const std::vector<std::string>& facts) {
  if (facts.empty()) return {};
  std::string html = "<section class=\"summary\"><h3>Summary</h3><ul>";
  for (const std::string& f : facts) html += "<li>" + escape_html(f) + "</li>";
  return html + "</ul></section>";
}

// The camera's sections whose data are given (see the header).
std::string camera_sections(const CameraReport& r) {
  require_that(r.width_px > 0 && r.height_px > 0, "the image size is 0");
  std::string html = summary_section(r.facts);
  if (!r.views.empty()) html += residual_section(r) + coverage_section(r);
  if (!r.field_x_px.empty()) html += distortion_section(r);
  if (!r.sigma_px.empty()) html += uncertainty_section(r);
  return html;
}

}  // namespace

std::string render_camera_html(const CameraReport& r) { return html_page(r.title, r.date, camera_sections(r)); }

void write_camera_report(const CameraReport& report, const std::string& path) {
  write_page(render_camera_html(report), path);
}

std::string render_camera_page_html(const CameraPage& page) {
  std::string body = summary_section(page.facts);
  for (const CameraPageTable& t : page.tables) body += table_section(t.table, t.id);
  for (const CameraReport& camera : page.cameras) {
    body +=
        "<section class=\"camera\"><h2>" + escape_html(camera.title) + "</h2>" + camera_sections(camera) + "</section>";
  }
  return html_page(page.title, page.date, body);
}

void write_camera_page(const CameraPage& page, const std::string& path) {
  write_page(render_camera_page_html(page), path);
}

}  // namespace kincal::report

#include "host/report/report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <numbers>

#include <Eigen/Geometry>

#include "host/files/output_file.hpp"
#include "host/report/svg_plot.hpp"

namespace kincal::report {

namespace {

constexpr const char* kBefore = "#d95f02";
constexpr const char* kAfter = "#1b9e77";
constexpr const char* kPalette[] = {"#d95f02", "#7570b3", "#1b9e77", "#e7298a", "#66a61e", "#e6ab02"};
constexpr double kMm = 1e3;
constexpr double kUm = 1e6;
constexpr double kDeg = 180.0 / std::numbers::pi;

constexpr const char* kStyle = R"(
body{font-family:"DejaVu Sans",Helvetica,Arial,sans-serif;margin:24px auto;max-width:1200px;color:#222;
background:#fff;line-height:1.4}
h1{margin-bottom:0}h2{border-bottom:2px solid #1b9e77;padding-bottom:4px;margin-top:40px}
.date{color:#666;margin-top:4px}
table{border-collapse:collapse;margin:8px 0 16px}
th,td{border:1px solid #ccc;padding:3px 8px;font-size:13px}
th{background:#f0f4f3;text-align:left}td.n{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
tr.group th{background:#e0ebe8}td.off{color:#c00;font-weight:bold}td.fixed{color:#888;font-style:italic}
.plots{display:flex;flex-wrap:wrap;gap:8px}
svg.plot{background:#fff;border:1px solid #ddd}
svg.plot .frame{fill:none;stroke:#444}svg.plot .grid{stroke:#e4e4e4}
ul.legend{font-size:13px;color:#444;margin-top:0}span.off{color:#c00;font-weight:bold}
span.fixed{color:#888;font-style:italic}span.absorbs{font-size:11px;color:#555}
nav li{margin:2px 0}
)";

std::string format(const char* pattern, ...) __attribute__((format(printf, 1, 2)));
std::string format(const char* pattern, ...) {
  char text[128];
  va_list args;
  va_start(args, pattern);
  std::vsnprintf(text, sizeof text, pattern, args);
  va_end(args);
  return text;
}

// The unit of one table row of a quantity, the same in every cell of the row: mm for lengths;
// for angles mrad when every value of the row is below 0.1 rad (small angles read best so),
// else deg. Values with `value_decimals`, changes, sigmas and errors with one more.
struct RowUnit {
  const char* suffix;  // HTML
  double per_si;
  int value_decimals;
};

RowUnit row_unit(Quantity q, const std::vector<double>& values) {
  if (q == Quantity::length_m) return {" mm", kMm, 3};
  if (q == Quantity::ratio) return {"", 1.0, 6};
  if (q == Quantity::mass_kg) return {" kg", 1.0, 3};
  if (q == Quantity::compliance_rad_per_nm) return {" &micro;rad/(N&middot;m)", kUm, 3};
  if (q == Quantity::compliance_m_per_n) return {" &micro;m/N", kUm, 3};
  const bool small = std::all_of(values.begin(), values.end(), [](double v) { return std::abs(v) < 0.1; });
  return small ? RowUnit{" mrad", kMm, 3} : RowUnit{"&deg;", kDeg, 4};
}
std::string value_text(const RowUnit& u, double v) {
  return format("%.*f%s", u.value_decimals, v * u.per_si, u.suffix);
}
std::string delta_text(const RowUnit& u, double v) {
  return format("%.*f%s", u.value_decimals + 1, v * u.per_si, u.suffix);
}

// Lengths in plot notes and on plot axes: um below 1 mm, mm from there -- one rule for every
// plot, so that a reader never meets "5255.1 um". A note or axis of several lengths takes the
// unit of its largest.
struct LengthUnit {
  const char* name;
  double per_m;
};
LengthUnit length_unit(double largest_m) {
  return std::abs(largest_m) < 1e-3 ? LengthUnit{"\u00b5m", kUm} : LengthUnit{"mm", kMm};
}
std::string length_text(double m, const LengthUnit& u) {
  return format(u.per_m == kUm ? "%.1f %s" : "%.3f %s", m * u.per_m, u.name);
}
std::string length_text(double m) { return length_text(m, length_unit(m)); }
double largest_magnitude(const std::vector<double>& values) {
  double m = 0.0;
  for (const double v : values) m = std::max(m, std::abs(v));
  return m;
}

std::string cell(const std::string& html, const char* cls = "n") {
  return std::string("<td class=\"") + cls + "\">" + html + "</td>";
}

std::string heading(const std::string& text) { return "<th>" + escape_html(text) + "</th>"; }

class RunContext {
 public:
  RunContext(const Run& run, std::size_t index) : run_(run), index_(index) {}
  [[noreturn]] void fail(const std::string& what) const {
    throw ReportError("run " + std::to_string(index_ + 1) + " '" + run_.title + "': " + what);
  }
  std::string id(const std::string& part) const { return "run" + std::to_string(index_ + 1) + "-" + part; }
  const Run& run() const { return run_; }

 private:
  const Run& run_;
  std::size_t index_;
};

void validate(const RunContext& c) {
  const Run& run = c.run();
  if (run.measurements < 0) c.fail("the measurement count is negative");
  for (const ParameterRow& p : run.parameters)
    if (p.stddev && !(*p.stddev >= 0.0)) c.fail("parameter " + p.name + ": its sigma is negative or not a number");
  for (const Accuracy& a : run.accuracy)
    if (a.count < 0) c.fail("accuracy '" + a.label + "': the pose count is negative");
  const auto check_readings = [&](const std::string& what, std::size_t i, const std::vector<double>& q) {
    if (q.size() != run.joints.size())
      c.fail(what + " " + std::to_string(i + 1) + ": " + std::to_string(q.size()) + " joint readings, the run names " +
             std::to_string(run.joints.size()) + " joints");
  };
  for (std::size_t i = 0; i < run.validation.size(); ++i) check_readings("validation pose", i, run.validation[i].q);
  for (std::size_t i = 0; i < run.fit_residuals.size(); ++i) check_readings("fit residual", i, run.fit_residuals[i].q);
  for (std::size_t i = 0; i < run.sweeps.size(); ++i) {
    const SweepPlot& s = run.sweeps[i];
    const std::string where = "sweep " + std::to_string(i + 1) + ": ";
    if (s.joint < 0 || s.joint >= static_cast<int>(run.joints.size()))
      c.fail(where + "joint index " + std::to_string(s.joint) + ", the run names " + std::to_string(run.joints.size()) +
             " joints");
    if (s.points_m.size() < 3) c.fail(where + "fewer than 3 points");
    if (!(s.axis_direction.norm() > 0.0) || !s.axis_direction.allFinite() || !s.axis_point_m.allFinite())
      c.fail(where + "the axis is not a finite line with a direction");
  }
  for (const Comparison& t : run.comparisons)
    for (const ComparisonRow& row : t.rows)
      if (row.values.size() != t.columns.size())
        c.fail("comparison '" + t.title + "', row " + row.name + ": " + std::to_string(row.values.size()) +
               " values for " + std::to_string(t.columns.size()) + " columns");
  for (const TextTable& t : run.tables)
    for (std::size_t i = 0; i < t.rows.size(); ++i)
      if (t.rows[i].size() != t.columns.size())
        c.fail("table '" + t.title + "', row " + std::to_string(i + 1) + ": " + std::to_string(t.rows[i].size()) +
               " cells for " + std::to_string(t.columns.size()) + " columns");
}

std::string facts(const Run& run) {
  std::string html = "<table class=\"facts\">";
  const auto row = [&html](const char* name, const std::string& value) {
    if (!value.empty()) html += "<tr><th>" + std::string(name) + "</th><td>" + escape_html(value) + "</td></tr>";
  };
  row("robot", run.robot);
  row("method", run.method);
  row("data", run.data);
  if (run.measurements > 0) row("measurements", std::to_string(run.measurements));
  const bool truth = std::any_of(run.parameters.begin(), run.parameters.end(),
                                 [](const ParameterRow& p) { return p.truth.has_value(); });
  row("measurements are", !run.simulated   ? "not recorded in the data (simulated or measured)"
                          : *run.simulated ? (truth ? "simulated (true values known)" : "simulated")
                                           : "measured");
  return html + "</table>";
}

std::string model_table(const RunContext& c) {
  const Run& run = c.run();
  const bool truth = std::any_of(run.parameters.begin(), run.parameters.end(),
                                 [](const ParameterRow& p) { return p.truth.has_value(); });
  const bool identifiable = std::any_of(run.parameters.begin(), run.parameters.end(),
                                        [](const ParameterRow& p) { return p.identifiable_truth.has_value(); });
  const bool priors = std::any_of(run.parameters.begin(), run.parameters.end(), [](const ParameterRow& p) {
    return p.prior_sigma.has_value() || p.data_share.has_value();
  });
  std::string html = "<section class=\"model\" id=\"" + c.id("model") +
                     "\"><h3>Identified model</h3><table class=\"model\"><tr>" + heading("parameter") +
                     heading("nominal") + heading("identified") + heading("change") + heading("1-sigma");
  if (priors) html += heading("prior sigma") + heading("from data");
  if (truth) {
    html += heading("true");
    if (identifiable) html += heading("true, as the data identify it");
    html += heading(identifiable ? "error (identified \u2212 identifiable)" : "error (identified \u2212 true)");
  }
  html += "</tr>";
  const int columns = 5 + (priors ? 2 : 0) + (truth ? 2 : 0) + (truth && identifiable ? 1 : 0);
  std::string group;
  bool first = true, any_off = false, any_fixed = false, any_bound = false, any_absorbed = false,
       any_beyond_prior = false;
  for (const ParameterRow& p : run.parameters) {
    if (first || p.group != group)
      html +=
          "<tr class=\"group\"><th colspan=\"" + std::to_string(columns) + "\">" + escape_html(p.group) + "</th></tr>";
    first = false;
    group = p.group;
    std::vector<double> values = {p.nominal, p.identified};
    for (const std::optional<double>& v : {p.truth, p.identifiable_truth})
      if (v) values.push_back(*v);
    const RowUnit u = row_unit(p.quantity, values);
    const double change = p.identified - p.nominal;
    const bool beyond_prior = p.prior_sigma && std::abs(change) > 3.0 * *p.prior_sigma;
    any_beyond_prior = any_beyond_prior || beyond_prior;
    html += "<tr><td>" + escape_html(p.name) + "</td>" + cell(value_text(u, p.nominal)) +
            cell(value_text(u, p.identified)) + cell(delta_text(u, change), beyond_prior ? "n off" : "n") +
            (p.stddev     ? cell(delta_text(u, *p.stddev))
             : p.at_bound ? cell("at its bound", "fixed")
                          : cell("held fixed", "fixed"));
    any_fixed = any_fixed || (!p.stddev && !p.at_bound);
    any_bound = any_bound || p.at_bound;
    if (priors)
      html += cell(p.prior_sigma ? delta_text(u, *p.prior_sigma) : "none") +
              cell(p.data_share ? format("%.1f %%", 100.0 * *p.data_share) : "");
    if (truth) {
      html += cell(p.truth ? value_text(u, *p.truth) : "");
      if (identifiable) {
        std::string shown = p.identifiable_truth ? value_text(u, *p.identifiable_truth) : "";
        if (!p.absorbs.empty()) shown += "<br><span class=\"absorbs\">absorbs " + escape_html(p.absorbs) + "</span>";
        any_absorbed = any_absorbed || !p.absorbs.empty();
        html += cell(shown);
      }
      const std::optional<double> reference = p.identifiable_truth ? p.identifiable_truth : p.truth;
      if (reference) {
        const double error = p.identified - *reference;
        const bool off = p.stddev && std::abs(error) > 3.0 * *p.stddev;
        any_off = any_off || off;
        html += cell(delta_text(u, error), off ? "n off" : "n");
      } else {
        html += cell("");
      }
    }
    html += "</tr>";
  }
  html +=
      "</table><ul class=\"legend\"><li>lengths in mm; angles in degrees, or in mrad in a row whose values are "
      "all below 0.1 rad; the change, the 1-sigma and the error in the row's unit</li>";
  if (any_fixed)
    html +=
        "<li><span class=\"fixed\">held fixed</span>: not identified from these data (see Identifiability); "
        "kept at its starting value</li>";
  if (any_bound)
    html +=
        "<li><span class=\"fixed\">at its bound</span>: the solve ended on the parameter's physical bound (a "
        "compliance or a mass at 0, a model file's limit), which holds it; the other 1-sigmas are given it</li>";
  if (identifiable)
    html +=
        "<li>true, as the data identify it: the true model fitted in the identified parameters with the "
        "held-fixed ones at their starting values, the answer a solve from noise-free data at these poses "
        "would give; the error is measured from it" +
        std::string(any_absorbed ? ", and &ldquo;absorbs&rdquo; names the held-fixed parameters whose true "
                                   "errors it takes up"
                                 : "") +
        "</li>";
  if (priors)
    html +=
        "<li>prior sigma: the prior's 1-sigma on the deviation from the nominal; from data: the share of the "
        "parameter's posterior information that the measurements give, the rest is its prior's</li>";
  if (any_beyond_prior)
    html += "<li><span class=\"off\">bold red change</span>: more than 3 prior sigmas from the nominal</li>";
  if (any_off) html += "<li><span class=\"off\">bold red</span>: the error is more than 3 sigma</li>";
  return html + "</ul></section>";
}

std::string identifiability(const RunContext& c) {
  const Run& run = c.run();
  std::string html =
      "<section class=\"identifiability\" id=\"" + c.id("identifiability") + "\"><h3>Identifiability and notes</h3>";
  if (!run.held_fixed.empty()) {
    html += "<table class=\"held-fixed\"><tr>" + heading("held fixed") + heading("why") + "</tr>";
    for (const HeldFixed& h : run.held_fixed)
      html += "<tr><td>" + escape_html(h.parameter) + "</td><td>" + escape_html(h.reason) + "</td></tr>";
    html += "</table>";
  }
  if (!run.notes.empty()) {
    html += "<ul class=\"notes\">";
    for (const std::string& note : run.notes) {
      // The first line is the note; each further line an item under it.
      std::vector<std::string> lines;
      for (std::size_t start = 0; start <= note.size();) {
        const std::size_t end = std::min(note.find('\n', start), note.size());
        std::string line = note.substr(start, end - start);
        line.erase(0, std::min(line.find_first_not_of(' '), line.size()));
        if (!line.empty()) lines.push_back(line);
        start = end + 1;
      }
      if (lines.empty()) continue;
      html += "<li>" + escape_html(lines[0]);
      if (lines.size() > 1) {
        html += "<ul>";
        for (std::size_t i = 1; i < lines.size(); ++i) html += "<li>" + escape_html(lines[i]) + "</li>";
        html += "</ul>";
      }
      html += "</li>";
    }
    html += "</ul>";
  }
  return html + "</section>";
}

std::string accuracy(const RunContext& c) {
  const Run& run = c.run();
  const bool orientation =
      std::any_of(run.accuracy.begin(), run.accuracy.end(), [](const Accuracy& a) { return a.mean_rad.has_value(); });
  std::string html = "<section class=\"accuracy\" id=\"" + c.id("accuracy") + "\"><h3>Accuracy on " +
                     escape_html(run.accuracy_of) + "</h3><table class=\"accuracy\"><tr>" + heading("model") +
                     heading("poses") + heading("position mean") + heading("RMS") + heading("max");
  if (orientation) html += heading("orientation mean") + heading("RMS") + heading("max");
  html += "</tr>";
  PlotSpec plot;
  plot.title = "Position error on " + run.accuracy_of;
  plot.width_px = 560;
  plot.height_px = 90 + 30 * static_cast<int>(run.accuracy.size());
  plot.x = {"position error (mm)", true, {}, {}, {}};
  plot.series = {
      {"mean", kPalette[0], {}, {}, false}, {"RMS", kPalette[1], {}, {}, false}, {"max", kPalette[2], {}, {}, false}};
  for (std::size_t i = 0; i < run.accuracy.size(); ++i) {
    const Accuracy& a = run.accuracy[i];
    html += "<tr><td>" + escape_html(a.label) + "</td>" + cell(std::to_string(a.count)) +
            cell(format("%.4f mm", a.mean_m * kMm)) + cell(format("%.4f mm", a.rms_m * kMm)) +
            cell(format("%.4f mm", a.max_m * kMm));
    if (orientation) {
      for (const std::optional<double>& v : {a.mean_rad, a.rms_rad, a.max_rad})
        html += cell(v ? format("%.4f mrad", *v * kMm) : "");
    }
    html += "</tr>";
    plot.y.categories.push_back(a.label);
    const double values[] = {a.mean_m, a.rms_m, a.max_m};
    for (std::size_t k = 0; k < 3; ++k) {
      plot.series[k].x.push_back(values[k] * kMm);
      plot.series[k].y.push_back(static_cast<double>(i));
    }
  }
  return html + "</table><div class=\"plots\">" + svg_plot(plot) + "</div></section>";
}

// A joint's reading as its plots show it: deg (revolute) or mm (prismatic).
double reading(const JointInfo& joint, double q) { return q * (joint.prismatic ? kMm : kDeg); }

// A small plot of position error (mm) against joint j's reading, without its series.
PlotSpec joint_plot(const Run& run, std::size_t j, bool log_error) {
  const JointInfo& joint = run.joints[j];
  PlotSpec plot;
  plot.title = "Joint " + std::to_string(j + 1) + (joint.name.empty() ? "" : " (" + joint.name + ")");
  plot.width_px = 290;
  plot.height_px = 220;
  plot.x = {joint.prismatic ? "reading (mm)" : "reading (deg)", false, {}, {}, {}};
  plot.y = {"position error (mm)", log_error, {}, {}, {}};
  return plot;
}

std::string residuals(const RunContext& c) {
  const Run& run = c.run();
  std::string html = "<section class=\"residuals\" id=\"" + c.id("residuals") +
                     "\"><h3>Residuals</h3><p>Position error of the nominal model (before) and of the identified "
                     "model (after) on each validation pose.</p><div class=\"plots\">";
  PlotSpec per_pose;
  per_pose.title = "Position error per validation pose";
  per_pose.width_px = 760;
  per_pose.x = {"validation pose", false, {}, 0.5, static_cast<double>(run.validation.size()) + 0.5};
  per_pose.y = {"position error (mm)", true, {}, {}, {}};
  per_pose.series = {{"before", kBefore, {}, {}, false}, {"after", kAfter, {}, {}, false}};
  for (std::size_t i = 0; i < run.validation.size(); ++i) {
    for (PlotSeries& s : per_pose.series) s.x.push_back(static_cast<double>(i + 1));
    per_pose.series[0].y.push_back(run.validation[i].before_m * kMm);
    per_pose.series[1].y.push_back(run.validation[i].after_m * kMm);
  }
  html += svg_plot(per_pose) + "</div><h4>Against each joint's reading</h4><div class=\"plots\">";
  for (std::size_t j = 0; j < run.joints.size(); ++j) {
    PlotSpec plot = joint_plot(run, j, true);
    plot.series = {{"before", kBefore, {}, {}, false}, {"after", kAfter, {}, {}, false}};
    for (const ValidationPose& pose : run.validation) {
      for (PlotSeries& s : plot.series) s.x.push_back(reading(run.joints[j], pose.q[j]));
      plot.series[0].y.push_back(pose.before_m * kMm);
      plot.series[1].y.push_back(pose.after_m * kMm);
    }
    html += svg_plot(plot);
  }
  return html + "</div></section>";
}

std::string fit_residuals(const RunContext& c) {
  const Run& run = c.run();
  const bool any_rejected =
      std::any_of(run.fit_residuals.begin(), run.fit_residuals.end(), [](const FitResidual& r) { return r.rejected; });
  std::string html = "<section class=\"fit-residuals\" id=\"" + c.id("fit-residuals") +
                     "\"><h3>Residuals of the fit</h3><p>Position error of the identified model on each measurement "
                     "it was identified from, against each joint's reading" +
                     std::string(any_rejected ? "; the rows rejected as outliers (left out of the fit) marked" : "") +
                     ".</p><div class=\"plots\">";
  for (std::size_t j = 0; j < run.joints.size(); ++j) {
    PlotSpec plot = joint_plot(run, j, false);
    plot.series = {{"used", kAfter, {}, {}, false}};
    if (any_rejected) plot.series.push_back({"rejected", kBefore, {}, {}, false});
    for (const FitResidual& r : run.fit_residuals) {
      PlotSeries& s = plot.series[r.rejected ? 1 : 0];
      s.x.push_back(reading(run.joints[j], r.q[j]));
      s.y.push_back(r.residual_m * kMm);
    }
    html += svg_plot(plot);
  }
  return html + "</div></section>";
}

// Two unit vectors that make a right-handed frame with `axis`.
std::pair<Eigen::Vector3d, Eigen::Vector3d> plane_basis(const Eigen::Vector3d& axis) {
  Eigen::Index least = 0;
  axis.cwiseAbs().minCoeff(&least);
  const Eigen::Vector3d u = axis.cross(Eigen::Vector3d::Unit(least)).normalized();
  return {u, axis.cross(u)};
}

// 1, 2 or 5 times a power of ten, the largest not above `limit` (>= 1).
double round_factor(double limit) {
  if (!(limit > 1.0)) return 1.0;
  const double decade = std::pow(10.0, std::floor(std::log10(limit)));
  for (const double step : {5.0, 2.0, 1.0})
    if (step * decade <= limit) return step * decade;
  return decade;
}

// The sweep in 3-D: an orthographic view from 25 deg above the fit's plane (circle: from 30 deg
// beside the middle of the arc; line: across it), the axis upright on the page, equal scale in mm.
// Drawn: the fitted circle or line, the axis, the device frame's x, y, z directions from the
// circle's centre (the line's middle), and each measured point at its foot on the fit plus its
// offset from the fit magnified k times (a 1-2-5 factor, stated with the offsets' RMS and max),
// since offsets of micrometres vanish at the scale of the sweep.
std::string sweep_view_3d(const std::string& name, const SweepPlot& s, const Eigen::Vector3d& centre,
                          const Eigen::Vector3d& u, const Eigen::Vector3d& v, const Eigen::Vector3d& d) {
  constexpr double kElevation = 25.0 / kDeg, kAzimuth = 30.0 / kDeg;
  const Eigen::Vector3d towards_viewer =
      std::cos(kElevation) * (std::cos(kAzimuth) * u + std::sin(kAzimuth) * v) + std::sin(kElevation) * d;
  const Eigen::Vector3d right = d.cross(towards_viewer).normalized();
  const Eigen::Vector3d up = towards_viewer.cross(right);
  const auto add = [&](PlotSeries& series, const Eigen::Vector3d& p) {
    series.x.push_back(right.dot(p - centre) * kMm);
    series.y.push_back(up.dot(p - centre) * kMm);
  };
  // Each point's foot on the fit.
  std::vector<Eigen::Vector3d> feet;
  double lo = 0.0, hi = 0.0;
  for (const Eigen::Vector3d& p : s.points_m) {
    const Eigen::Vector3d r = p - centre;
    if (s.circle) {
      const Eigen::Vector3d in_plane = r - d * d.dot(r);
      feet.push_back(centre + (in_plane.norm() > 0.0 ? in_plane.normalized() : u) * s.radius_m);
    } else {
      const double t = d.dot(r);
      lo = std::min(lo, t);
      hi = std::max(hi, t);
      feet.push_back(centre + d * t);
    }
  }
  double squares = 0.0, largest = 0.0;
  for (std::size_t k = 0; k < feet.size(); ++k) {
    const double e = (s.points_m[k] - feet[k]).norm();
    squares += e * e;
    largest = std::max(largest, e);
  }
  const double extent = std::max(s.circle ? 2.0 * s.radius_m : hi - lo, 1e-6);
  const double magnify = largest > 0.0 ? round_factor(0.08 * extent / largest) : 1.0;

  PlotSpec view;
  view.title = name + ": 3-D view";
  view.width_px = 420;
  view.height_px = 360;
  view.equal_aspect = true;
  view.x = {"across the page (mm)", false, {}, {}, {}};
  view.y = {"up the page, along the axis (mm)", false, {}, {}, {}};
  PlotSeries fit{s.circle ? "circle" : "line", kAfter, {}, {}, true}, axis{"axis", "#444444", {}, {}, true},
      points{"points", kBefore, {}, {}, false};
  if (s.circle) {
    for (int k = 0; k <= 120; ++k) {
      const double angle = 2.0 * std::numbers::pi * k / 120.0;
      add(fit, centre + s.radius_m * (std::cos(angle) * u + std::sin(angle) * v));
    }
    add(axis, centre - 0.6 * extent * d);
    add(axis, centre + 0.6 * extent * d);
  } else {
    add(fit, centre + lo * d);
    add(fit, centre + hi * d);
    add(axis, centre + (lo - 0.15 * extent) * d);  // the joint's axis: the line's direction, drawn beyond it
    add(axis, centre + (hi + 0.15 * extent) * d);
  }
  view.series = {fit, axis};
  const char* device_names[] = {"device x", "device y", "device z"};
  for (int k = 0; k < 3; ++k) {
    PlotSeries direction{device_names[k], kPalette[3 + k], {}, {}, true};
    add(direction, centre);
    add(direction, centre + 0.3 * extent * Eigen::Vector3d::Unit(k));
    view.series.push_back(direction);
  }
  for (std::size_t k = 0; k < feet.size(); ++k) {
    const Eigen::Vector3d shown = feet[k] + magnify * (s.points_m[k] - feet[k]);
    PlotSeries offset{k == 0 ? format("offsets x%g", magnify) : "", kPalette[1], {}, {}, true};
    add(offset, feet[k]);
    add(offset, shown);
    view.series.push_back(offset);
    add(points, shown);
  }
  view.series.push_back(points);
  const double rms = std::sqrt(squares / static_cast<double>(feet.size()));
  view.notes = {
      s.circle ? "orthographic, 25 deg above the circle's plane, 30 deg beside mid-arc"
               : "orthographic, 25 deg above a plane through the line",
      format("points: offsets from the fit drawn x%g (RMS %s, max %s)", magnify,
             length_text(rms, length_unit(largest)).c_str(), length_text(largest, length_unit(largest)).c_str()),
      "device axes from the " + std::string(s.circle ? "circle's centre" : "line's middle") +
          format(", %.0f mm long", 0.3 * extent * kMm)};
  return svg_plot(view);
}

std::string sweep_plots(const RunContext& c, const SweepPlot& s) {
  const JointInfo& joint = c.run().joints[static_cast<std::size_t>(s.joint)];
  const std::string name = "Joint " + std::to_string(s.joint + 1) + (joint.name.empty() ? "" : " (" + joint.name + ")");
  const Eigen::Vector3d d = s.axis_direction.normalized();
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : s.points_m) mean += p;
  mean /= static_cast<double>(s.points_m.size());
  const Eigen::Vector3d centre = s.axis_point_m + d * d.dot(mean - s.axis_point_m);
  // In-plane x towards the middle of the arc, so that angles about the axis do not wrap.
  const Eigen::Vector3d towards_arc = (mean - centre) - d * d.dot(mean - centre);
  const auto [u, v] =
      s.circle && towards_arc.norm() > 0.0
          ? std::pair<Eigen::Vector3d, Eigen::Vector3d>(towards_arc.normalized(), d.cross(towards_arc.normalized()))
          : plane_basis(d);
  const std::vector<std::string> notes = {
      s.circle ? "radius " + length_text(s.radius_m, {"mm", kMm}) : std::string("line"), "RMS " + length_text(s.rms_m),
      std::to_string(s.points_m.size()) + " points" +
          (s.rejected > 0 ? ", " + std::to_string(s.rejected) + " rejected" : std::string())};
  PlotSpec fit;
  fit.width_px = 300;
  fit.height_px = 320;
  fit.notes = notes;
  if (s.circle) {
    fit.title = name + ": circle fit";
    fit.equal_aspect = true;
    fit.x = {"in-plane x (mm)", false, {}, {}, {}};
    fit.y = {"in-plane y (mm)", false, {}, {}, {}};
    PlotSeries circle{"fitted circle", kAfter, {}, {}, true}, points{"measured", kBefore, {}, {}, false};
    for (int k = 0; k <= 120; ++k) {
      const double angle = 2.0 * std::numbers::pi * k / 120.0;
      circle.x.push_back(s.radius_m * std::cos(angle) * kMm);
      circle.y.push_back(s.radius_m * std::sin(angle) * kMm);
    }
    PlotSpec residual;
    residual.title = name + ": residuals";
    residual.width_px = 300;
    residual.height_px = 320;
    residual.x = {"angle about the axis from mid-arc (deg)", false, {}, {}, {}};
    PlotSeries radial{"radial", kPalette[1], {}, {}, false}, axial{"along the axis", kPalette[3], {}, {}, false};
    for (const Eigen::Vector3d& p : s.points_m) {  // residuals in m, scaled to the axis's unit below
      const Eigen::Vector3d r = p - centre;
      const double x = u.dot(r), y = v.dot(r);
      points.x.push_back(x * kMm);
      points.y.push_back(y * kMm);
      radial.x.push_back(std::atan2(y, x) * kDeg);
      radial.y.push_back(std::hypot(x, y) - s.radius_m);
      axial.x.push_back(radial.x.back());
      axial.y.push_back(d.dot(r));
    }
    double radial_ss = 0.0, axial_ss = 0.0;
    for (std::size_t k = 0; k < radial.y.size(); ++k) {
      radial_ss += radial.y[k] * radial.y[k];
      axial_ss += axial.y[k] * axial.y[k];
    }
    const double n = static_cast<double>(radial.y.size());
    const LengthUnit unit = length_unit(std::max(largest_magnitude(radial.y), largest_magnitude(axial.y)));
    for (PlotSeries* series : {&radial, &axial})
      for (double& value : series->y) value *= unit.per_m;
    residual.y = {std::string("residual (") + unit.name + ")", false, {}, {}, {}};
    const double radial_rms = std::sqrt(radial_ss / n), axial_rms = std::sqrt(axial_ss / n);
    const LengthUnit rms_unit = length_unit(std::max(radial_rms, axial_rms));
    residual.notes = {
        "radial: distance from the axis - radius", "along the axis: distance from the circle's plane",
        "RMS radial " + length_text(radial_rms, rms_unit) + ", along the axis " + length_text(axial_rms, rms_unit)};
    fit.series = {circle, points};
    residual.series = {radial, axial};
    return sweep_view_3d(name, s, centre, u, v, d) + svg_plot(fit) + svg_plot(residual);
  }
  fit.title = name + ": line fit";
  fit.width_px = 420;
  fit.x = {"travel along the line (mm)", false, {}, {}, {}};
  PlotSeries line{"fitted line", kAfter, {}, {}, true}, across_u{"across, x", kBefore, {}, {}, false},
      across_v{"across, y", kPalette[1], {}, {}, false};
  for (const Eigen::Vector3d& p : s.points_m) {  // across in m, scaled to the axis's unit below
    const Eigen::Vector3d r = p - s.axis_point_m;
    const double travel = d.dot(r) * kMm;
    across_u.x.push_back(travel);
    across_u.y.push_back(u.dot(r));
    across_v.x.push_back(travel);
    across_v.y.push_back(v.dot(r));
  }
  const LengthUnit unit = length_unit(std::max(largest_magnitude(across_u.y), largest_magnitude(across_v.y)));
  for (PlotSeries* series : {&across_u, &across_v})
    for (double& value : series->y) value *= unit.per_m;
  fit.y = {std::string("off the line (") + unit.name + ")", false, {}, {}, {}};
  const auto [lo, hi] = std::minmax_element(across_u.x.begin(), across_u.x.end());
  line.x = {*lo, *hi};
  line.y = {0.0, 0.0};
  fit.series = {line, across_u, across_v};
  return sweep_view_3d(name, s, centre, u, v, d) + svg_plot(fit);
}

std::string sweeps(const RunContext& c) {
  std::string html = "<section class=\"sweeps\" id=\"" + c.id("sweeps") +
                     "\"><h3>Single-joint sweeps</h3><p>Each sweep in 3-D (the measured points, the fitted circle or "
                     "line and the joint's axis, in the device frame), then its points projected into the fit's "
                     "plane (circle: centred on the fitted centre; line: distance off the fitted line).</p>"
                     "<div class=\"plots\">";
  for (const SweepPlot& s : c.run().sweeps) html += sweep_plots(c, s);
  return html + "</div></section>";
}

std::string bus(const RunContext& c, const BusStatistics& b) {
  std::string html = "<section class=\"bus\" id=\"" + c.id("bus") + "\"><h3>CAN bus</h3><table class=\"bus\">";
  const auto row = [&html](const char* name, const std::string& value) {
    html += "<tr><th>" + std::string(name) + "</th>" + cell(value) + "</tr>";
  };
  if (!b.bus.empty()) html += "<tr><th>bus</th><td>" + escape_html(b.bus) + "</td></tr>";
  row("duration", format("%.3f s", b.seconds));
  row("frames", std::to_string(b.frames));
  row("payload bytes", std::to_string(b.bytes));
  row("errors", std::to_string(b.errors));
  row("load", format("%.2f %%", b.load * 100.0));
  if (b.seconds > 0.0) row("frame rate", format("%.1f frames/s", static_cast<double>(b.frames) / b.seconds));
  return html + "</table></section>";
}

std::string comparison(const RunContext& c, const Comparison& t, std::size_t index) {
  std::string html = "<section class=\"comparison\" id=\"" + c.id("comparison" + std::to_string(index + 1)) +
                     "\"><h3>" + escape_html(t.title) + "</h3><table class=\"comparison\"><tr>" + heading("parameter");
  for (const std::string& column : t.columns) html += heading(column);
  html += "</tr>";
  for (const ComparisonRow& row : t.rows) {
    html += "<tr><td>" + escape_html(row.name) + "</td>";
    std::vector<double> given;
    for (const std::optional<double>& v : row.values)
      if (v) given.push_back(*v);
    const RowUnit u = row_unit(row.quantity, given);
    for (const std::optional<double>& v : row.values) html += cell(v ? value_text(u, *v) : "&mdash;");
    html += "</tr>";
  }
  html += "</table>";
  if (!t.note.empty()) html += "<p class=\"note\">" + escape_html(t.note) + "</p>";
  return html + "</section>";
}

std::string text_table(const RunContext& c, const TextTable& t, std::size_t index) {
  return table_section(t, c.id("table" + std::to_string(index + 1)));
}

std::string run_section(const RunContext& c) {
  const Run& run = c.run();
  std::string html =
      "<section class=\"run\" id=\"" + c.id("section") + "\"><h2>" + escape_html(run.title) + "</h2>" + facts(run);
  if (!run.parameters.empty()) html += model_table(c);
  if (!run.held_fixed.empty() || !run.notes.empty()) html += identifiability(c);
  if (!run.accuracy.empty()) html += accuracy(c);
  if (!run.validation.empty()) html += residuals(c);
  if (!run.fit_residuals.empty()) html += fit_residuals(c);
  if (!run.sweeps.empty()) html += sweeps(c);
  if (run.bus) html += bus(c, *run.bus);
  for (std::size_t i = 0; i < run.comparisons.size(); ++i) html += comparison(c, run.comparisons[i], i);
  for (std::size_t i = 0; i < run.tables.size(); ++i) html += text_table(c, run.tables[i], i);
  return html + "</section>";
}

}  // namespace

std::string utc_date_now() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", &utc);
  return date;
}

std::string render_html(const Report& report) {
  std::vector<RunContext> runs;
  for (std::size_t i = 0; i < report.runs.size(); ++i) {
    runs.emplace_back(report.runs[i], i);
    validate(runs.back());
  }
  std::string html;
  if (runs.size() > 1) {
    html += "<nav><ul>";
    for (const RunContext& c : runs)
      html += "<li><a href=\"#" + c.id("section") + "\">" + escape_html(c.run().title) + "</a></li>";
    html += "</ul></nav>";
  }
  for (const RunContext& c : runs) {
    try {
      html += run_section(c);
    } catch (const ReportError& e) {  // a plot's complaint, said with the run it is in
      c.fail(e.what());
    }
  }
  return html_page(report.title, report.date, html);
}

std::string table_section(const TextTable& t, const std::string& id) {
  std::string html = "<section class=\"table\" id=\"" + escape_html(id) + "\"><h3>" + escape_html(t.title) +
                     "</h3><table class=\"text\"><tr>";
  for (const std::string& column : t.columns) html += heading(column);
  html += "</tr>";
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const std::vector<std::string>& row = t.rows[i];
    if (row.size() != t.columns.size()) {
      throw ReportError("table '" + t.title + "', row " + std::to_string(i + 1) + ": " + std::to_string(row.size()) +
                        " cells for " + std::to_string(t.columns.size()) + " columns");
    }
    html += "<tr>";
    for (const std::string& value : row) html += "<td>" + escape_html(value) + "</td>";
    html += "</tr>";
  }
  html += "</table>";
  if (!t.note.empty()) html += "<p class=\"note\">" + escape_html(t.note) + "</p>";
  return html + "</section>";
}

std::string html_page(const std::string& title, const std::string& date, const std::string& body_html) {
  std::string html = "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" + escape_html(title) +
                     "</title><style>" + kStyle + plot_style() + "</style></head><body><header><h1>" +
                     escape_html(title) + "</h1>";
  if (!date.empty()) html += "<p class=\"date\">" + escape_html(date) + "</p>";
  return html + "</header>" + body_html + "</body></html>\n";
}

void write_html(const Report& report, const std::string& path) { write_page(render_html(report), path); }

void write_page(const std::string& html, const std::string& path) {
  try {
    files::write_file_atomically(path, html);
  } catch (const files::OutputError& e) {
    throw ReportError(std::string(e.what()) + " (the report)");
  }
}

}  // namespace kincal::report

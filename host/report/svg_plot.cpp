#include "host/report/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "host/model/xml_text.hpp"
#include "host/report/report.hpp"

namespace kincal::report {

namespace {

std::string fixed(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", v);
  return text;
}

// A tick label: as few digits as the tick step needs.
std::string tick_text(double v, double step) {
  const int decimals = std::clamp(static_cast<int>(-std::floor(std::log10(step) + 1e-9)), 0, 9);
  char text[32];
  std::snprintf(text, sizeof text, "%.*f", decimals, std::abs(v) < step * 1e-6 ? 0.0 : v);
  return text;
}

// The axis as the plot draws it: t = value (linear, category) or log10(value) (log).
struct Scale {
  double lo = 0.0, hi = 1.0;
  bool log = false;
  double position(double v) const { return log ? std::log10(std::max(v, std::pow(10.0, lo))) : v; }
};

double nice_step(double range) {
  const double raw = range / 5.0;
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0})
    if (raw <= m * decade) return m * decade;
  return 10.0 * decade;
}

Scale make_scale(const PlotAxis& axis, const std::vector<const std::vector<double>*>& data) {
  Scale s;
  s.log = axis.log && axis.categories.empty();
  if (!axis.categories.empty()) {
    s.lo = -0.5;
    s.hi = static_cast<double>(axis.categories.size()) - 0.5;
    return s;
  }
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const std::vector<double>* values : data)
    for (const double v : *values)
      if (!s.log || v > 0.0) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
  if (axis.min) lo = *axis.min;
  if (axis.max) hi = *axis.max;
  if (s.log) {
    if (!(lo > 0.0)) lo = hi > 0.0 ? hi / 10.0 : 1.0;
    if (!(hi > 0.0)) hi = lo * 10.0;
    s.lo = std::floor(std::log10(lo));
    s.hi = std::max(std::ceil(std::log10(hi)), s.lo + 1.0);
    return s;
  }
  if (!std::isfinite(lo)) lo = hi = 0.0;
  if (hi - lo < 1e-12 * std::max(1.0, std::abs(lo))) {
    const double pad = std::max(1.0, std::abs(lo) * 0.1);
    lo -= pad;
    hi += pad;
  }
  const double margin = axis.min && axis.max ? 0.0 : 0.05 * (hi - lo);
  s.lo = axis.min ? lo : lo - margin;
  s.hi = axis.max ? hi : hi + margin;
  if (!(s.hi > s.lo)) throw ReportError("plot axis '" + axis.label + "': its max is not above its min");
  return s;
}

struct Tick {
  double t;
  std::string text;
};

std::vector<Tick> ticks(const PlotAxis& axis, const Scale& s) {
  std::vector<Tick> out;
  if (!axis.categories.empty()) {
    for (std::size_t i = 0; i < axis.categories.size(); ++i)
      out.push_back({static_cast<double>(i), axis.categories[i]});
  } else if (s.log) {
    for (double e = s.lo; e <= s.hi + 1e-9; e += 1.0) {
      char text[32];
      std::snprintf(text, sizeof text, "%g", std::pow(10.0, e));
      out.push_back({e, text});
    }
  } else {
    const double step = nice_step(s.hi - s.lo);
    for (double v = std::ceil(s.lo / step) * step; v <= s.hi + step * 1e-9; v += step)
      out.push_back({v, tick_text(v, step)});
  }
  return out;
}

}  // namespace

std::string escape_html(std::string_view text) { return model::escape_xml_text(text); }

std::string svg_plot(const PlotSpec& spec) {
  std::vector<const std::vector<double>*> xs, ys;
  for (const PlotSeries& series : spec.series) {
    if (series.x.size() != series.y.size())
      throw ReportError("plot '" + spec.title + "': series '" + series.name + "' has " +
                        std::to_string(series.x.size()) + " x values and " + std::to_string(series.y.size()) +
                        " y values");
    for (std::size_t i = 0; i < series.x.size(); ++i)
      if (!std::isfinite(series.x[i]) || !std::isfinite(series.y[i]))
        throw ReportError("plot '" + spec.title + "': series '" + series.name + "' point " + std::to_string(i + 1) +
                          " is not finite");
    xs.push_back(&series.x);
    ys.push_back(&series.y);
  }
  Scale sx = make_scale(spec.x, xs), sy = make_scale(spec.y, ys);

  std::size_t longest_category = 0;
  for (const std::string& c : spec.y.categories) longest_category = std::max(longest_category, c.size());
  const double left =
      std::clamp(16.0 + 6.2 * static_cast<double>(std::max<std::size_t>(longest_category, 6)), 58.0, 170.0);
  const bool legend = std::any_of(spec.series.begin(), spec.series.end(),
                                  [](const PlotSeries& series) { return !series.name.empty(); });
  const double top = legend ? 40.0 : 26.0, right = 12.0;
  const double bottom = 40.0 + 13.0 * static_cast<double>(spec.notes.size());
  const double width = spec.width_px - left - right, height = spec.height_px - top - bottom;
  if (spec.equal_aspect) {  // the same units per pixel on both axes: widen the tighter range
    const double per_px = std::max((sx.hi - sx.lo) / width, (sy.hi - sy.lo) / height);
    const double cx = (sx.lo + sx.hi) / 2, cy = (sy.lo + sy.hi) / 2;
    sx.lo = cx - per_px * width / 2;
    sx.hi = cx + per_px * width / 2;
    sy.lo = cy - per_px * height / 2;
    sy.hi = cy + per_px * height / 2;
  }
  const auto px = [&](double v) {
    return left + std::clamp((sx.position(v) - sx.lo) / (sx.hi - sx.lo), 0.0, 1.0) * width;
  };
  const auto py = [&](double v) {
    return top + height - std::clamp((sy.position(v) - sy.lo) / (sy.hi - sy.lo), 0.0, 1.0) * height;
  };

  std::string svg = "<svg class=\"plot\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" +
                    std::to_string(spec.width_px) + "\" height=\"" + std::to_string(spec.height_px) +
                    "\" viewBox=\"0 0 " + std::to_string(spec.width_px) + " " + std::to_string(spec.height_px) +
                    "\" role=\"img\" aria-label=\"" + escape_html(spec.title) + "\">";
  svg += "<text class=\"title\" x=\"" + fixed(left) + "\" y=\"16\">" + escape_html(spec.title) + "</text>";
  svg += "<rect class=\"frame\" x=\"" + fixed(left) + "\" y=\"" + fixed(top) + "\" width=\"" + fixed(width) +
         "\" height=\"" + fixed(height) + "\"/>";
  for (const Tick& t : ticks(spec.x, sx)) {
    const double x = left + (t.t - sx.lo) / (sx.hi - sx.lo) * width;
    svg += "<line class=\"grid\" x1=\"" + fixed(x) + "\" y1=\"" + fixed(top) + "\" x2=\"" + fixed(x) + "\" y2=\"" +
           fixed(top + height) + "\"/><text class=\"tick\" text-anchor=\"middle\" x=\"" + fixed(x) + "\" y=\"" +
           fixed(top + height + 13) + "\">" + escape_html(t.text) + "</text>";
  }
  for (const Tick& t : ticks(spec.y, sy)) {
    const double y = top + height - (t.t - sy.lo) / (sy.hi - sy.lo) * height;
    svg += "<line class=\"grid\" x1=\"" + fixed(left) + "\" y1=\"" + fixed(y) + "\" x2=\"" + fixed(left + width) +
           "\" y2=\"" + fixed(y) + "\"/><text class=\"tick\" text-anchor=\"end\" x=\"" + fixed(left - 4) + "\" y=\"" +
           fixed(y + 4) + "\">" + escape_html(t.text) + "</text>";
  }
  svg += "<text class=\"label\" text-anchor=\"middle\" x=\"" + fixed(left + width / 2) + "\" y=\"" +
         fixed(top + height + 30) + "\">" + escape_html(spec.x.label) + "</text>";
  svg += "<text class=\"label\" text-anchor=\"middle\" transform=\"translate(12 " + fixed(top + height / 2) +
         ") rotate(-90)\">" + escape_html(spec.y.label) + "</text>";

  for (const PlotSeries& series : spec.series) {
    const std::string colour = escape_html(series.colour);
    if (series.line) {
      svg += "<polyline class=\"mark\" fill=\"none\" stroke=\"" + colour + "\" points=\"";
      for (std::size_t i = 0; i < series.x.size(); ++i)
        svg += (i ? " " : "") + fixed(px(series.x[i])) + "," + fixed(py(series.y[i]));
      svg += "\"/>";
    } else {
      for (std::size_t i = 0; i < series.x.size(); ++i)
        svg += "<circle class=\"mark\" r=\"2.6\" fill=\"" + colour + "\" cx=\"" + fixed(px(series.x[i])) + "\" cy=\"" +
               fixed(py(series.y[i])) + "\"/>";
    }
  }

  double legend_x = left;  // the legend: one row under the title
  for (const PlotSeries& series : spec.series) {
    if (series.name.empty()) continue;
    svg += "<rect x=\"" + fixed(legend_x) + "\" y=\"24\" width=\"9\" height=\"9\" fill=\"" +
           escape_html(series.colour) + "\"/><text class=\"legend\" x=\"" + fixed(legend_x + 12) + "\" y=\"32\">" +
           escape_html(series.name) + "</text>";
    legend_x += 26.0 + 5.6 * static_cast<double>(series.name.size());
  }
  double note_y = top + height + 30;  // the notes: lines under the x label
  for (const std::string& note : spec.notes) {
    note_y += 13;
    svg +=
        "<text class=\"note\" x=\"" + fixed(left) + "\" y=\"" + fixed(note_y) + "\">" + escape_html(note) + "</text>";
  }
  svg += "</svg>";
  return svg;
}

}  // namespace kincal::report

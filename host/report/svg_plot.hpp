// Inline SVG plots for the HTML report (report.hpp), and the escaping every piece of text in it
// goes through. Internal to host/report.
//
// A plot is a title, a legend (the named series), a frame with ticks and labels on both axes
// (linear or log10; on a category axis the ticks are the category names) holding series of dots
// or polylines, and notes under it. Every data mark carries
// class="mark", and the <svg> element class="plot", so a test can count plots with data in the
// rendered page. Points outside the axis range are drawn at its edge (on a log axis a value
// <= 0 sits at the bottom). equal_aspect keeps one unit the same length on both axes (circles
// stay round; not with a category or log axis).
//
// Every piece of text lies inside the plot and clear of every other (the render check measures
// it in Chromium, tests/host/report/render_check.cpp). Text widths are estimated from the
// characters, on the wide side of DejaVu Sans (the report's first font; others are narrower):
// the left margin is as wide as the y tick labels need, the right one as half the last x tick
// label; a title, legend, axis label, category name or note too long for its room is wrapped
// onto further lines (words kept whole when they fit), and the plot grows taller for them and
// for categories of several lines, so width_px is kept and height_px is a minimum. Tick labels
// that would touch are thinned (every k-th kept). Font sizes are those of plot_style().
//
// Cost: O(points + text). Failure: svg_plot() throws ReportError for a non-finite coordinate,
// a series whose x and y differ in length, or a range whose max is not above its min.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace kincal::report {

// & < > " ' as entities: safe in element content and in quoted attributes (the XML escaping
// of host/model/xml_text.hpp, which the URDF writer shares).
std::string escape_html(std::string_view text);

struct PlotAxis {
  std::string label;
  bool log = false;
  std::vector<std::string> categories;  // non-empty: values are indices 0..n-1 into these
  std::optional<double> min, max;       // default: from the data, with a margin
};

struct PlotSeries {
  std::string name;  // in the legend ("" = not listed)
  std::string colour;
  std::vector<double> x, y;
  bool line = false;  // a polyline through the points instead of dots
};

struct PlotSpec {
  std::string title;
  PlotAxis x, y;
  int width_px = 360;
  int height_px = 260;  // at least; taller when its text needs it (see above)
  bool equal_aspect = false;
  std::vector<PlotSeries> series;
  std::vector<std::string> notes;  // lines printed under the plot (wrapped when too long)
};

std::string svg_plot(const PlotSpec& spec);

// The CSS of the plots' text (font sizes and weights), which svg_plot's layout assumes.
std::string plot_style();

// `v` with `decimals` digits after the point ("%.*f").
std::string fixed_text(double v, int decimals);

// The estimated width in px of `text` (UTF-8) at `font_px`, on the wide side (see above).
double text_width_px(std::string_view text, double font_px, bool bold = false);

}  // namespace kincal::report

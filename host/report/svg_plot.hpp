// Inline SVG plots for the HTML report (report.hpp), and the escaping every piece of text in it
// goes through. Internal to host/report.
//
// A plot is a title, a legend row (the named series), a frame with ticks and labels on both axes
// (linear or log10; on a category axis the ticks are the category names) holding series of dots
// or polylines, and notes under it. Every data mark carries
// class="mark", and the <svg> element class="plot", so a test can count plots with data in the
// rendered page. Points outside the axis range are drawn at its edge (on a log axis a value
// <= 0 sits at the bottom). equal_aspect keeps one unit the same length on both axes (circles
// stay round).
//
// Cost: O(points). Failure: svg_plot() throws ReportError for a non-finite coordinate, a series
// whose x and y differ in length, or a range whose max is not above its min.
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
  int height_px = 260;
  bool equal_aspect = false;
  std::vector<PlotSeries> series;
  std::vector<std::string> notes;  // short lines printed under the plot
};

std::string svg_plot(const PlotSpec& spec);

}  // namespace kincal::report

#include "host/report/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include "host/model/xml_text.hpp"
#include "host/report/report.hpp"

namespace kincal::report {

namespace {

// The plot's fonts (plot_style() writes them as CSS) and what the layout assumes of their
// glyph boxes: ascent and descent as fractions of the size, on the large side of DejaVu Sans
// (0.93, 0.24), and the pitch of wrapped lines.
struct Font {
  const char* css_class;
  double px;
  bool bold;
};
constexpr Font kTitle{"title", 12.0, true}, kLabel{"label", 11.0, false}, kTick{"tick", 10.0, false},
    kLegend{"legend", 10.0, false}, kNote{"note", 10.0, false};
constexpr double kAscent = 0.95, kDescent = 0.3, kPitch = 1.3;
constexpr double kPad = 6.0;          // between any text and the plot's edge
constexpr double kSwatch = 9.0;       // a legend entry's colour square
constexpr double kTickGap = 5.0;      // between a y tick label and the frame
constexpr double kMaxLeft = 0.45;     // of the width: the most the y tick labels may take
constexpr double kMinFrame = 60.0;    // px: the least height of the frame
constexpr double kCategoryGap = 6.0;  // px between the names of two categories

double line_pitch(const Font& f) { return kPitch * f.px; }
double width_of(std::string_view text, const Font& f) { return text_width_px(text, f.px, f.bold); }

// The next code point of UTF-8 `text` at `at` (advanced past it); a stray byte counts as one.
char32_t next_code_point(std::string_view text, std::size_t& at) {
  const auto byte = static_cast<unsigned char>(text[at++]);
  if (byte < 0x80) return byte;
  int more = byte >= 0xF0 ? 3 : byte >= 0xE0 ? 2 : byte >= 0xC0 ? 1 : 0;
  char32_t c = byte & (0x3Fu >> more);
  for (; more > 0 && at < text.size() && (static_cast<unsigned char>(text[at]) & 0xC0) == 0x80; --more)
    c = (c << 6) | (static_cast<unsigned char>(text[at++]) & 0x3Fu);
  return c;
}

// A character's advance in em, at least DejaVu Sans's (digits 0.64, most lower case 0.6-0.63,
// upper case up to 0.77, m 0.97, W 0.99).
double em_width(char32_t c) {
  if (c == ' ' || c == 0) return 0.35;
  if (c >= 0x80) return 1.0;  // µ, °, −, ×, σ: none wider than this
  const char ascii = static_cast<char>(c);
  if (std::strchr("il.,:;'|!`", ascii)) return 0.35;
  if (std::strchr("fjrt()[]{}-/\\\"", ascii)) return 0.5;
  if (std::strchr("mwMW%@", ascii)) return 1.0;
  if (ascii >= '0' && ascii <= '9') return 0.64;
  if (ascii >= 'A' && ascii <= 'Z') return 0.78;
  return 0.64;
}

// `text` in lines no wider than `max_px`: words whole where they fit, a longer word cut.
std::vector<std::string> wrap(const std::string& text, double max_px, const Font& f) {
  std::vector<std::string> lines;
  std::string line;
  const auto add_word = [&](const std::string& word) {
    const std::string joined = line.empty() ? word : line + " " + word;
    if (width_of(joined, f) <= max_px) {
      line = joined;
      return;
    }
    if (!line.empty()) lines.push_back(line);
    line.clear();
    std::size_t at = 0;
    while (at < word.size()) {  // the word alone, cut where it is too long for a line
      const std::size_t before = at;
      next_code_point(word, at);
      if (!line.empty() && width_of(line + word.substr(before, at - before), f) > max_px) {
        lines.push_back(line);
        line.clear();
      }
      line += word.substr(before, at - before);
    }
  };
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t space = std::min(text.find(' ', start), text.size());
    if (space > start) add_word(text.substr(start, space - start));
    start = space + 1;
  }
  if (!line.empty() || lines.empty()) lines.push_back(line);
  return lines;
}

double widest(const std::vector<std::string>& lines, const Font& f) {
  double w = 0.0;
  for (const std::string& line : lines) w = std::max(w, width_of(line, f));
  return w;
}

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

double text_width_px(std::string_view text, double font_px, bool bold) {
  double em = 0.0;
  for (std::size_t at = 0; at < text.size();) em += em_width(next_code_point(text, at));
  return em * font_px * (bold ? 1.12 : 1.0);
}

std::string fixed_text(double v, int decimals) {
  char text[48];
  std::snprintf(text, sizeof text, "%.*f", decimals, v);
  return text;
}

std::string plot_style() {
  std::string css = "svg.plot text{fill:#333}";
  for (const Font& f : {kTitle, kLabel, kTick, kLegend, kNote}) {
    char rule[96];
    std::snprintf(rule, sizeof rule, "svg.plot .%s{font-size:%gpx;font-weight:%s}", f.css_class, f.px,
                  f.bold ? "bold" : "normal");
    css += rule;
  }
  return css + "svg.plot .note{fill:#555}";
}

namespace {

// A text element (one line) at (x, y): y is its baseline.
std::string text_element(const Font& f, const char* anchor, double x, double y, const std::string& text,
                         const std::string& transform = "") {
  std::string svg = std::string("<text class=\"") + f.css_class + "\"";
  if (anchor) svg += std::string(" text-anchor=\"") + anchor + "\"";
  if (transform.empty()) {
    svg += " x=\"" + fixed(x) + "\" y=\"" + fixed(y) + "\"";
  } else {
    svg += " transform=\"" + transform + "\"";
  }
  return svg + ">" + escape_html(text) + "</text>";
}

// Every k-th of `all` (k >= 1), so that neighbours `spacing_px` apart are at least `needed_px`
// apart.
std::vector<Tick> thinned(const std::vector<Tick>& all, double spacing_px, double needed_px) {
  if (all.size() < 2 || spacing_px >= needed_px) return all;
  const auto k = static_cast<std::size_t>(std::ceil(needed_px / std::max(spacing_px, 1e-9)));
  std::vector<Tick> out;
  for (std::size_t i = 0; i < all.size(); i += k) out.push_back(all[i]);
  return out;
}

struct LegendEntry {
  std::string colour;
  std::vector<std::string> lines;
  double x = 0.0, y = 0.0;  // the swatch's top left
};

}  // namespace

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
  const Scale data_x = make_scale(spec.x, xs), data_y = make_scale(spec.y, ys);
  const double width_px = spec.width_px, room = width_px - 2.0 * kPad;

  // Above the frame: the title, then the legend in rows.
  double y_cursor = kPad;
  std::string header;
  for (const std::string& line : wrap(spec.title, room, kTitle)) {
    header += text_element(kTitle, nullptr, kPad, y_cursor + kAscent * kTitle.px, line);
    y_cursor += line_pitch(kTitle);
  }
  std::vector<LegendEntry> legend;
  double legend_x = kPad, row_height = 0.0;
  y_cursor += 2.0;
  for (const PlotSeries& series : spec.series) {
    if (series.name.empty()) continue;
    LegendEntry e{series.colour, wrap(series.name, room - kSwatch - 3.0, kLegend), 0.0, 0.0};
    const double entry_width = kSwatch + 3.0 + widest(e.lines, kLegend);
    if (legend_x > kPad && legend_x + entry_width > width_px - kPad) {
      legend_x = kPad;
      y_cursor += row_height;
      row_height = 0.0;
    }
    e.x = legend_x;
    e.y = y_cursor;
    legend_x += entry_width + 14.0;
    row_height = std::max(row_height, line_pitch(kLegend) * static_cast<double>(e.lines.size()));
    legend.push_back(std::move(e));
  }
  y_cursor += row_height;
  // The top y tick label reaches (kAscent - 0.35) em above the frame.
  const double top = y_cursor + (kAscent - 0.35) * kTick.px + 2.0;

  // Under the frame: x tick labels, the x label, the notes.
  const std::vector<std::string> x_label = wrap(spec.x.label, room, kLabel);
  std::vector<std::string> notes;
  for (const std::string& note : spec.notes)
    for (std::string& line : wrap(note, room, kNote)) notes.push_back(std::move(line));
  const double tick_top = (kDescent + 0.35) * kTick.px + 1.0;  // below the lowest y tick label
  const double label_top = tick_top + (kAscent + kDescent) * kTick.px + 2.0;
  const double notes_top =
      label_top + line_pitch(kLabel) * static_cast<double>(spec.x.label.empty() ? 0 : x_label.size());
  const double bottom = notes_top + line_pitch(kNote) * static_cast<double>(notes.size()) + kPad;

  // The frame's height: as asked, or what the categories' names need.
  const std::size_t categories = spec.y.categories.size();
  std::vector<std::vector<std::string>> category_lines(categories);
  std::size_t most_lines = 1;
  const double category_room = std::max(40.0, kMaxLeft * width_px - kPad - line_pitch(kLabel) - 2.0 - kTickGap);
  for (std::size_t i = 0; i < categories; ++i) {
    category_lines[i] = wrap(spec.y.categories[i], category_room, kTick);
    most_lines = std::max(most_lines, category_lines[i].size());
  }
  double frame_height = std::max(kMinFrame, static_cast<double>(spec.height_px) - top - bottom);
  if (categories > 0)
    frame_height = std::max(frame_height, static_cast<double>(categories) *
                                              (line_pitch(kTick) * static_cast<double>(most_lines) + kCategoryGap));
  const double height_px = std::ceil(top + frame_height + bottom);
  frame_height = height_px - top - bottom;
  const std::vector<std::string> y_label =
      spec.y.label.empty() ? std::vector<std::string>{} : wrap(spec.y.label, frame_height, kLabel);
  // The y label's lines stand left of this.
  const double left_column = kPad + line_pitch(kLabel) * static_cast<double>(y_label.size());

  // Left and right margins from the tick labels, which depend on the frame's width when the
  // aspect is kept: settled in a few passes.
  double left = left_column + 40.0, right = 12.0;
  Scale sx = data_x, sy = data_y;
  std::vector<Tick> x_ticks, y_ticks;
  std::vector<std::vector<std::string>> y_tick_lines;
  for (int pass = 0;; ++pass) {
    const double width = std::max(width_px - left - right, 1.0);
    sx = data_x;
    sy = data_y;
    if (spec.equal_aspect && !sx.log && !sy.log && spec.x.categories.empty() && categories == 0) {
      // The same units per pixel on both axes: widen the tighter range.
      const double per_px = std::max((sx.hi - sx.lo) / width, (sy.hi - sy.lo) / frame_height);
      const double cx = (sx.lo + sx.hi) / 2, cy = (sy.lo + sy.hi) / 2;
      sx.lo = cx - per_px * width / 2;
      sx.hi = cx + per_px * width / 2;
      sy.lo = cy - per_px * frame_height / 2;
      sy.hi = cy + per_px * frame_height / 2;
    }
    std::vector<Tick> all_x = ticks(spec.x, sx), all_y = ticks(spec.y, sy);
    double widest_x = 0.0;
    for (const Tick& t : all_x) widest_x = std::max(widest_x, width_of(t.text, kTick));
    const double x_spacing = all_x.size() > 1 ? (all_x[1].t - all_x[0].t) / (sx.hi - sx.lo) * width : width;
    x_ticks = thinned(all_x, x_spacing, widest_x + 8.0);
    const double y_spacing =
        all_y.size() > 1 ? (all_y[1].t - all_y[0].t) / (sy.hi - sy.lo) * frame_height : frame_height;
    y_ticks = categories > 0 ? all_y : thinned(all_y, y_spacing, line_pitch(kTick) + 2.0);
    y_tick_lines.clear();
    double widest_y = 0.0;
    for (const Tick& t : y_ticks) {
      const auto index = static_cast<std::size_t>(t.t);
      y_tick_lines.push_back(categories > 0 ? category_lines[index] : std::vector<std::string>{t.text});
      widest_y = std::max(widest_y, widest(y_tick_lines.back(), kTick));
    }
    double new_left = std::max(left_column + 2.0 + widest_y + kTickGap, 40.0);
    double new_right = 12.0;
    if (!x_ticks.empty()) {  // end labels centred on the frame's edges at worst
      new_left = std::max(new_left, kPad + width_of(x_ticks.front().text, kTick) / 2.0);
      new_right = std::max(new_right, kPad + width_of(x_ticks.back().text, kTick) / 2.0);
    }
    new_left = std::ceil(new_left);
    new_right = std::ceil(new_right);
    if ((new_left == left && new_right == right) || pass == 5) break;
    left = new_left;
    right = new_right;
  }
  const double width = std::max(width_px - left - right, 1.0), height = frame_height;
  const auto px = [&](double v) {
    return left + std::clamp((sx.position(v) - sx.lo) / (sx.hi - sx.lo), 0.0, 1.0) * width;
  };
  const auto py = [&](double v) {
    return top + height - std::clamp((sy.position(v) - sy.lo) / (sy.hi - sy.lo), 0.0, 1.0) * height;
  };

  std::string svg = "<svg class=\"plot\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" + fixed(width_px) +
                    "\" height=\"" + fixed(height_px) + "\" viewBox=\"0 0 " + fixed(width_px) + " " + fixed(height_px) +
                    "\" role=\"img\" aria-label=\"" + escape_html(spec.title) + "\">" + header;
  svg += "<rect class=\"frame\" x=\"" + fixed(left) + "\" y=\"" + fixed(top) + "\" width=\"" + fixed(width) +
         "\" height=\"" + fixed(height) + "\"/>";
  const double x_tick_baseline = top + height + tick_top + kAscent * kTick.px;
  for (const Tick& t : x_ticks) {
    const double x = left + (t.t - sx.lo) / (sx.hi - sx.lo) * width;
    svg += "<line class=\"grid\" x1=\"" + fixed(x) + "\" y1=\"" + fixed(top) + "\" x2=\"" + fixed(x) + "\" y2=\"" +
           fixed(top + height) + "\"/>" + text_element(kTick, "middle", x, x_tick_baseline, t.text);
  }
  for (std::size_t k = 0; k < y_ticks.size(); ++k) {
    const double y = top + height - (y_ticks[k].t - sy.lo) / (sy.hi - sy.lo) * height;
    svg += "<line class=\"grid\" x1=\"" + fixed(left) + "\" y1=\"" + fixed(y) + "\" x2=\"" + fixed(left + width) +
           "\" y2=\"" + fixed(y) + "\"/>";
    const std::vector<std::string>& lines = y_tick_lines[k];
    const double first = y + 0.35 * kTick.px - line_pitch(kTick) * static_cast<double>(lines.size() - 1) / 2.0;
    for (std::size_t i = 0; i < lines.size(); ++i)
      svg += text_element(kTick, "end", left - kTickGap, first + line_pitch(kTick) * static_cast<double>(i), lines[i]);
  }
  if (!spec.x.label.empty()) {
    for (std::size_t i = 0; i < x_label.size(); ++i) {
      const double half = width_of(x_label[i], kLabel) / 2.0;
      const double x = std::clamp(left + width / 2.0, kPad + half, std::max(kPad + half, width_px - kPad - half));
      svg += text_element(kLabel, "middle", x,
                          top + height + label_top + kAscent * kLabel.px + line_pitch(kLabel) * static_cast<double>(i),
                          x_label[i]);
    }
  }
  for (std::size_t i = 0; i < y_label.size(); ++i) {  // read upwards; the first line leftmost
    const double x = kPad + kAscent * kLabel.px + line_pitch(kLabel) * static_cast<double>(i);
    svg += text_element(kLabel, "middle", 0.0, 0.0, y_label[i],
                        "translate(" + fixed(x) + " " + fixed(top + height / 2.0) + ") rotate(-90)");
  }

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

  for (const LegendEntry& e : legend) {
    const double swatch_top = e.y + (line_pitch(kLegend) - kSwatch) / 2.0;
    svg += "<rect x=\"" + fixed(e.x) + "\" y=\"" + fixed(swatch_top) + "\" width=\"" + fixed(kSwatch) + "\" height=\"" +
           fixed(kSwatch) + "\" fill=\"" + escape_html(e.colour) + "\"/>";
    for (std::size_t i = 0; i < e.lines.size(); ++i)
      svg += text_element(kLegend, nullptr, e.x + kSwatch + 3.0,
                          e.y + (line_pitch(kLegend) + kAscent * kLegend.px - kDescent * kLegend.px) / 2.0 +
                              line_pitch(kLegend) * static_cast<double>(i),
                          e.lines[i]);
  }
  for (std::size_t i = 0; i < notes.size(); ++i)
    svg += text_element(kNote, nullptr, kPad,
                        top + height + notes_top + kAscent * kNote.px + line_pitch(kNote) * static_cast<double>(i),
                        notes[i]);
  svg += "</svg>";
  return svg;
}

}  // namespace kincal::report

// host/report: the HTML writer -- escaping, sections present exactly when given, units, errors.
#include <doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <string>

#include "host/report/report.hpp"
#include "host/report/svg_plot.hpp"
#include "sample_report.hpp"

namespace {

using namespace kincal::report;

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

bool has(const std::string& text, const std::string& what) { return text.find(what) != std::string::npos; }

const char* const kSections[] = {"class=\"model\"",     "class=\"identifiability\"", "class=\"accuracy\"",
                                 "class=\"residuals\"", "class=\"sweeps\"",          "class=\"bus\"",
                                 "class=\"comparison\""};

}  // namespace

TEST_CASE("report: every section of the sample is there, with its numbers in the reader's units") {
  const std::string html = render_html(testing::sample_report());
  for (const char* section : kSections) CHECK_MESSAGE(has(html, section), section);
  CHECK(html.rfind("<!DOCTYPE html>", 0) == 0);
  CHECK(has(html, "<nav>"));  // two runs: a table of contents
  CHECK(count(html, "<section class=\"run\"") == 2);
  CHECK(count(html, "<svg class=\"plot\"") == testing::kSamplePlots);
  CHECK(has(html, testing::kSampleNominalMean));
  CHECK(has(html, testing::kSampleIdentifiedRms));
  CHECK(has(html, "<td class=\"n\">431.800 mm</td>"));    // a2 nominal
  CHECK(has(html, "<td class=\"n\">90.0000&deg;</td>"));  // alpha1 nominal
  CHECK(has(html, "<td class=\"n\">0.0300 mm</td>"));     // the base's 1-sigma
  CHECK(has(html, "<td class=\"fixed\">held fixed</td>"));
  CHECK(has(html, "<td class=\"n off\">0.0500 mm</td>"));  // tool_x: 5 sigma from the truth
  CHECK(count(html, "class=\"n off\"") >= 1);
  CHECK(has(html, "2.1000 mrad"));  // orientation mean of the nominal model
  CHECK(has(html, "radius 320.000 mm"));
  CHECK(has(html, "1 rejected"));
  CHECK(has(html, "<td class=\"n\">2163</td>"));
  CHECK(has(html, "6.10 %"));
  CHECK(has(html, "<td class=\"n\">66.100 mm</td>"));  // their a1
  CHECK(has(html, "<td class=\"n\">&mdash;</td>"));    // a value they did not give
  // Self-contained: nothing to fetch, nothing to run.
  CHECK_FALSE(has(html, "<script"));
  CHECK_FALSE(has(html, "src="));
  CHECK_FALSE(has(html, "href=\"http"));
  CHECK_FALSE(has(html, "url("));
  CHECK_FALSE(has(html, "nan"));
  CHECK_FALSE(has(html, "inf\""));
}

TEST_CASE("report: sections not given are left out") {
  Report report;
  report.title = "empty";
  Run run;
  run.title = "nothing measured";
  report.runs.push_back(run);
  const std::string html = render_html(report);
  for (const char* section : kSections) CHECK_MESSAGE(!has(html, section), section);
  CHECK_FALSE(has(html, "<nav>"));
  CHECK_FALSE(has(html, "<svg"));
  CHECK_FALSE(has(html, "class=\"date\""));
  CHECK(has(html, "<h2>nothing measured</h2>"));
  CHECK(has(html, "measured</td>"));

  // One section at a time: only it appears.
  const Report sample = testing::sample_report();
  Run only_bus = run;
  only_bus.bus = sample.runs[1].bus;
  report.runs = {only_bus};
  const std::string bus_only = render_html(report);
  CHECK(has(bus_only, "class=\"bus\""));
  CHECK_FALSE(has(bus_only, "class=\"model\""));
  CHECK_FALSE(has(bus_only, "class=\"accuracy\""));

  Run only_notes = run;
  only_notes.notes = {"a note"};
  report.runs = {only_notes};
  const std::string notes = render_html(report);
  CHECK(has(notes, "class=\"identifiability\""));
  CHECK_FALSE(has(notes, "class=\"held-fixed\""));
  CHECK(has(notes, "<li>a note</li>"));

  // Without true values the model table has no truth columns.
  Run no_truth = run;
  no_truth.parameters = sample.runs[0].parameters;
  for (ParameterRow& p : no_truth.parameters) p.truth.reset();
  report.runs = {no_truth};
  const std::string model = render_html(report);
  CHECK(has(model, "class=\"model\""));
  CHECK_FALSE(has(model, "<th>true</th>"));
  CHECK(has(render_html(testing::sample_report()), "<th>true</th>"));
}

namespace {

// The <svg> plot whose title is `title`, or "".
std::string plot_titled(const std::string& html, const std::string& title) {
  const std::size_t at = html.find(">" + escape_html(title) + "</text>");
  if (at == std::string::npos) return "";
  const std::size_t begin = html.rfind("<svg class=\"plot\"", at), end = html.find("</svg>", at);
  return html.substr(begin, end - begin);
}

}  // namespace

TEST_CASE("report: each sweep has a 3-D view of its points, its fit, its axis and the offsets' scale") {
  Report report = testing::sample_report();
  // One point of the waist's sweep 1 mm off its circle, radially: the largest offset, and the
  // magnification of the offsets follows from it (8 % of the 640 mm circle over 1 mm: x50).
  SweepPlot& waist = report.runs[1].sweeps[0];
  const Eigen::Vector3d centre = waist.axis_point_m;
  const Eigen::Vector3d radial = (waist.points_m[5] - centre).normalized();
  waist.points_m[5] = centre + radial * (waist.radius_m + 1e-3);
  const std::string html = render_html(report);
  CHECK(count(html, ": 3-D view</text>") == 3);
  const std::string circle = plot_titled(html, "Joint 1 (waist): 3-D view");
  REQUIRE_FALSE(circle.empty());
  // 24 points and their 24 offsets, the fitted circle, the axis, the device's x, y and z.
  CHECK(count(circle, "class=\"mark\"") == 24 + 24 + 1 + 1 + 3);
  CHECK(has(circle, ">circle</text>"));
  CHECK(has(circle, ">axis</text>"));
  CHECK(has(circle, "points: offsets from the fit drawn x50 ("));
  const std::size_t max_at = circle.find(", max ");
  REQUIRE(max_at != std::string::npos);
  CHECK(std::stod(circle.substr(max_at + 6)) == doctest::Approx(1000.0).epsilon(0.002));  // um
  const std::string line = plot_titled(html, "Joint 3 (slide): 3-D view");
  REQUIRE_FALSE(line.empty());
  CHECK(count(line, "class=\"mark\"") == 24 + 24 + 1 + 1 + 3);
  CHECK(has(line, ">line</text>"));
}

TEST_CASE("report: all text is escaped") {
  const std::string evil = "<script>alert(\"x\")</script> & 'q'";
  const std::string escaped = "&lt;script&gt;alert(&quot;x&quot;)&lt;/script&gt; &amp; &#39;q&#39;";
  CHECK(escape_html(evil) == escaped);
  Report report = testing::sample_report();
  report.title = evil;
  report.date = evil;
  Run& run = report.runs[1];
  run.title = evil;
  run.robot = evil;
  run.notes = {evil};
  run.held_fixed = {{evil, evil}};
  run.joints[0].name = evil;
  run.accuracy[0].label = evil;
  run.comparisons[0].title = evil;
  run.comparisons[0].columns[0] = evil;
  run.comparisons[0].rows[0].name = evil;
  run.comparisons[0].note = evil;
  run.bus->bus = evil;
  report.runs[0].parameters[0].group = evil;
  report.runs[0].parameters[0].name = evil;
  const std::string html = render_html(report);
  CHECK_FALSE(has(html, "<script"));
  CHECK_FALSE(has(html, "alert(\"x\")"));
  CHECK(count(html, escaped) >= 14);
  // The sample's own title, escaped where it is shown:
  CHECK(has(render_html(testing::sample_report()), "Kapucu &amp; Baysec stereo rig &lt;RRP&gt;"));
}

TEST_CASE("report: bad input is an error naming the run and the item") {
  Report report = testing::sample_report();
  SUBCASE("joint readings of a validation pose") {
    report.runs[0].validation[1].q.pop_back();
    CHECK_THROWS_WITH_AS(
        render_html(report),
        doctest::Contains("run 1 'ARID platform on a PUMA-like 6R arm': validation pose 2: 5 joint readings, the run "
                          "names 6 joints"),
        ReportError);
  }
  SUBCASE("a comparison row") {
    report.runs[1].comparisons[0].rows[2].values.pop_back();
    CHECK_THROWS_WITH_AS(render_html(report),
                         doctest::Contains("run 2 'Kapucu & Baysec stereo rig <RRP>': comparison 'Kapucu & Baysec, "
                                           "Table 1, against ours', row d2: 3 values for 4 columns"),
                         ReportError);
  }
  SUBCASE("a sweep of a joint the run does not have") {
    report.runs[1].sweeps[2].joint = 3;
    CHECK_THROWS_WITH_AS(render_html(report), doctest::Contains("run 2 '"), ReportError);
    CHECK_THROWS_WITH_AS(render_html(report), doctest::Contains("sweep 3: joint index 3, the run names 3 joints"),
                         ReportError);
  }
  SUBCASE("a sweep without an axis") {
    report.runs[1].sweeps[0].axis_direction.setZero();
    CHECK_THROWS_WITH_AS(render_html(report), doctest::Contains("sweep 1: the axis is not a finite line"), ReportError);
  }
  SUBCASE("a number a plot cannot draw") {
    report.runs[0].validation[4].after_m = std::numeric_limits<double>::quiet_NaN();
    CHECK_THROWS_WITH_AS(
        render_html(report),
        doctest::Contains("run 1 'ARID platform on a PUMA-like 6R arm': plot 'Position error per validation pose': "
                          "series 'after' point 5 is not finite"),
        ReportError);
  }
  SUBCASE("a negative sigma") {
    report.runs[0].parameters[3].stddev = -1.0;
    CHECK_THROWS_WITH_AS(render_html(report), doctest::Contains("parameter alpha1: its sigma is negative"),
                         ReportError);
  }
  SUBCASE("a file that cannot be written") {
    CHECK_THROWS_WITH_AS(write_html(report, "/nonexistent-dir/report.html"),
                         doctest::Contains("/nonexistent-dir/report.html: cannot create a temporary file beside it"),
                         ReportError);
  }
}

TEST_CASE("report: write_html writes what render_html returns") {
  const Report report = testing::sample_report();
  const std::string path =
      (std::filesystem::temp_directory_path() / ("kincal_report_test_" + std::to_string(::getpid()) + ".html"))
          .string();
  write_html(report, path);
  std::ifstream in(path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::filesystem::remove(path);
  CHECK(text == render_html(report));
}

TEST_CASE("svg plot: points land inside the frame where the axes say; log axes take zero") {
  PlotSpec spec;
  spec.title = "t";
  spec.width_px = 200;
  spec.height_px = 150;
  spec.x = {"x", false, {}, 0.0, 10.0};
  spec.y = {"y", true, {}, {}, {}};
  spec.series = {{"s", "#000", {0.0, 10.0, 5.0}, {0.01, 1.0, 0.0}, false}};
  const std::string svg = svg_plot(spec);
  CHECK(count(svg, "class=\"mark\"") == 3);
  // Left margin 58, right 12: x = 0 -> 58, x = 10 -> 188. Log axis from 0.01 to 1: y = 1 at the top
  // (40, under the legend row), y = 0.01 at the bottom (150 - 40).
  CHECK(has(svg, "cx=\"58.0\" cy=\"110.0\""));  // (0, 0.01): bottom-left
  CHECK(has(svg, "cx=\"188.0\" cy=\"40.0\""));
  CHECK(has(svg, "cx=\"123.0\" cy=\"110.0\""));  // zero on a log axis: at the bottom
  CHECK(has(svg, ">0.01</text>"));
  CHECK(has(svg, ">0.1</text>"));

  spec.series[0].y.pop_back();
  CHECK_THROWS_WITH_AS(svg_plot(spec), doctest::Contains("series 's' has 3 x values and 2 y values"), ReportError);
}

// host/report: the HTML writer -- escaping, sections present exactly when given, units, errors.
#include <doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <string>

#include "host/report/camera_report.hpp"
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
  CHECK(has(html, "<td>measured</td>"));
  run.simulated.reset();  // a data file that does not say
  report.runs = {run};
  CHECK(has(render_html(report), "<td>not recorded in the data (simulated or measured)</td>"));
  run.simulated = false;

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
  CHECK(has(circle, ">offsets x50</text>"));  // the offsets' colour has its legend entry
  const std::size_t max_at = circle.find(", max ");
  REQUIRE(max_at != std::string::npos);
  CHECK(std::stod(circle.substr(max_at + 6)) == doctest::Approx(1.0).epsilon(0.002));
  CHECK(circle.substr(max_at + 6).find(" mm)") != std::string::npos);  // 1 mm and more: in mm
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

namespace {

// The number in attribute `name` of the first element of `svg` that starts with `tag`.
double attribute(const std::string& svg, const std::string& tag, const std::string& name) {
  const std::size_t element = svg.find(tag);
  REQUIRE(element != std::string::npos);
  const std::size_t at = svg.find(" " + name + "=\"", element);
  REQUIRE(at != std::string::npos);
  return std::stod(svg.substr(at + name.size() + 3));
}

std::string point(double x, double y) {
  char text[64];
  std::snprintf(text, sizeof text, "cx=\"%.1f\" cy=\"%.1f\"", x, y);
  return text;
}

}  // namespace

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
  CHECK(has(svg, "width=\"200.0\" height=\"150.0\""));  // room enough: the size asked
  // x from 0 to 10 across the frame; the log axis from 0.01 (bottom) to 1 (top).
  const double left = attribute(svg, "<rect class=\"frame\"", "x"), top = attribute(svg, "<rect class=\"frame\"", "y");
  const double width = attribute(svg, "<rect class=\"frame\"", "width"),
               height = attribute(svg, "<rect class=\"frame\"", "height");
  CHECK(left > 20.0);
  CHECK(left + width < 200.0);
  CHECK(top + height < 150.0);
  CHECK(has(svg, point(left, top + height)));  // (0, 0.01): bottom-left
  CHECK(has(svg, point(left + width, top)));
  CHECK(has(svg, point(left + width / 2, top + height)));  // zero on a log axis: at the bottom
  CHECK(has(svg, ">0.01</text>"));
  CHECK(has(svg, ">0.1</text>"));

  spec.series[0].y.pop_back();
  CHECK_THROWS_WITH_AS(svg_plot(spec), doctest::Contains("series 's' has 3 x values and 2 y values"), ReportError);
}

TEST_CASE("svg plot: text too long for its room is wrapped, the left margin fits the categories, the plot grows") {
  PlotSpec spec;
  spec.title = "Position error on the validation poses, with a title long enough to need a second line";
  spec.width_px = 400;
  spec.height_px = 120;
  spec.x = {"position error (mm)", true, {}, {}, {}};
  spec.y.categories = {"nominal model", "online correction: corrected targets vs the simulated truth",
                       "online correction: uncorrected targets vs the simulated truth"};
  spec.series = {{"mean", "#d95f02", {1.0, 0.1, 2.0}, {0.0, 1.0, 2.0}, false},
                 {"a series with a long name", "#7570b3", {1.5, 0.2, 2.5}, {0.0, 1.0, 2.0}, false},
                 {"another series with a long name", "#1b9e77", {1.7, 0.3, 2.7}, {0.0, 1.0, 2.0}, false}};
  spec.notes = {"points: offsets from the fit drawn x10 (RMS 4.530 mm, max 10.776 mm), and more words to wrap"};
  const std::string svg = svg_plot(spec);
  CHECK(has(svg, "width=\"400.0\""));
  const double height = attribute(svg, "<svg", "height");
  CHECK(height > 120.0);  // three categories of two lines each need more than 120 px
  // No category's name is cut: each is drawn whole, over lines one after the other.
  std::string names;
  for (std::size_t at = svg.find("text-anchor=\"end\""); at != std::string::npos;
       at = svg.find("text-anchor=\"end\"", at + 1)) {
    const std::size_t begin = svg.find('>', at) + 1;
    names += svg.substr(begin, svg.find("</text>", begin) - begin) + " ";
  }
  CHECK(names ==
        "nominal model online correction: corrected targets vs the simulated truth online correction: "
        "uncorrected targets vs the simulated truth ");
  CHECK(count(svg, "text-anchor=\"end\"") > 3);  // wrapped
  // Every text's estimated box lies inside the plot: left of its anchor by its width (end),
  // half of it (middle) or none (start).
  for (std::size_t at = svg.find("<text"); at != std::string::npos; at = svg.find("<text", at + 1)) {
    const std::size_t open_end = svg.find('>', at), close = svg.find("</text>", at);
    const std::string element = svg.substr(at, open_end - at), text = svg.substr(open_end + 1, close - open_end - 1);
    if (has(element, "transform=")) continue;  // the rotated y label
    const double x = attribute(element, "<text", "x");
    const double size = has(element, "title") ? 12.0 : has(element, "label") ? 11.0 : 10.0;
    const double w = text_width_px(text, size, has(element, "title"));
    const double x0 = has(element, "\"end\"") ? x - w : has(element, "\"middle\"") ? x - w / 2 : x;
    CHECK_MESSAGE(x0 >= 0.0, text);
    CHECK_MESSAGE(x0 + w <= 400.0, text);
    CHECK_MESSAGE(attribute(element, "<text", "y") <= height, text);
  }
}

TEST_CASE("svg plot: widths are estimated on the wide side, per code point") {
  CHECK(text_width_px("mmmm", 10.0) == doctest::Approx(40.0));
  CHECK(text_width_px("0123456789", 10.0) == doctest::Approx(64.0));
  CHECK(text_width_px("\u00b5m", 10.0) == doctest::Approx(20.0));  // two code points, three bytes
  CHECK(text_width_px("ab", 10.0, true) > text_width_px("ab", 10.0));
}

TEST_CASE("report: the model table compares with what the data identify, one unit per row, with a legend") {
  const std::string html = render_html(testing::sample_report());
  // base_z: 1.4 mm from its true value, which takes up the held-fixed d1's error; 0.05 mm from
  // the true value as the data identify it (under 3 sigma of 0.03 mm): not marked.
  CHECK(has(html, "<th>true, as the data identify it</th>"));
  CHECK(has(html,
            "<td class=\"n\">500.650 mm</td><td class=\"n\">502.050 mm<br><span class=\"absorbs\">absorbs "
            "d1</span></td><td class=\"n\">0.0500 mm</td>"));
  // base_rx: every value below 0.1 rad, so the whole row in mrad.
  CHECK(has(html,
            "<tr><td>base_rx</td><td class=\"n\">0.000 mrad</td><td class=\"n\">1.200 mrad</td><td "
            "class=\"n\">1.2000 mrad</td><td class=\"n\">0.1000 mrad</td><td class=\"n\">1.100 mrad</td>"));
  // alpha1: in degrees throughout, its change and sigma too.
  const std::size_t alpha1 = html.find("<tr><td>alpha1</td>");
  REQUIRE(alpha1 != std::string::npos);
  const std::string row = html.substr(alpha1, html.find("</tr>", alpha1) - alpha1);
  CHECK(count(row, "&deg;") == 7);
  CHECK_FALSE(has(row, "mrad"));
  // A legend entry for each mark the table uses.
  CHECK(has(html, "<li><span class=\"off\">bold red</span>: the error is more than 3 sigma</li>"));
  CHECK(has(html, "<li><span class=\"fixed\">held fixed</span>"));
  // Without any marked row, no red in the legend either.
  Report report = testing::sample_report();
  report.runs[0].parameters.pop_back();  // tool_x, the one 5 sigma off
  const std::string clean = render_html(report);
  CHECK_FALSE(has(clean, "class=\"n off\""));
  CHECK_FALSE(has(clean, "<span class=\"off\">"));
}

TEST_CASE("report: a note's further lines are items of their own; text tables; lengths in um or mm by size") {
  Report report = testing::sample_report();
  std::string html = render_html(report);
  CHECK(has(html,
            "<li>noise: position: instrument sigma 0.0200 mm (given)<ul><li>rejected line 14: residual 0.412 "
            "mm</li><li>rejected line 52: residual 0.388 mm</li></ul></li>"));
  CHECK(has(html, "<h3>Joint-type tests</h3>"));
  CHECK(has(html, "<th>p(circle at angle q)</th>"));
  CHECK(has(html, "<td>0.0021</td>"));
  CHECK(has(html, "RMS 50.0 \u00b5m"));  // the sweeps' fits: 0.05 mm
  CHECK_FALSE(has(html, " um"));
  report.runs[1].sweeps[0].rms_m = 5.2551;  // 5255.1 mm: in mm, never "5255100.0 um"
  report.runs[1].sweeps[1].rms_m = 5.2551e-3;
  html = render_html(report);
  CHECK(has(html, "RMS 5255.100 mm"));
  CHECK(has(html, "RMS 5.255 mm"));
  report.runs[1].tables[0].rows[1].pop_back();
  CHECK_THROWS_WITH_AS(render_html(report), doctest::Contains("table 'Joint-type tests', row 2: 4 cells for 5 columns"),
                       ReportError);
}

TEST_CASE("report: priors in the model table, a change beyond 3 prior sigmas marked; fit residuals per joint") {
  Report report = testing::sample_report();
  Run& run = report.runs[0];
  for (ParameterRow& p : run.parameters) {  // every change well within 3 prior sigmas
    p.prior_sigma = 0.01;
    p.data_share = 0.25;
  }
  run.parameters[0].prior_sigma.reset();
  std::string html = render_html(report);
  CHECK(has(html, "<th>prior sigma</th><th>from data</th>"));
  CHECK(has(html, "<td class=\"n\">none</td><td class=\"n\">25.0 %</td>"));
  CHECK(has(html,
            "<tr><td>base_rx</td><td class=\"n\">0.000 mrad</td><td class=\"n\">1.200 mrad</td><td "
            "class=\"n\">1.2000 mrad</td><td class=\"n\">0.1000 mrad</td><td class=\"n\">10.0000 mrad</td><td "
            "class=\"n\">25.0 %</td>"));
  CHECK_FALSE(has(html, "more than 3 prior sigmas"));
  for (ParameterRow& p : run.parameters)
    if (p.name == "base_rx") p.prior_sigma = 0.3e-3;  // 1.2 mrad is 4 prior sigmas
  html = render_html(report);
  CHECK(has(html,
            "<tr><td>base_rx</td><td class=\"n\">0.000 mrad</td><td class=\"n\">1.200 mrad</td><td "
            "class=\"n off\">1.2000 mrad</td>"));
  CHECK(has(html, "<li><span class=\"off\">bold red change</span>: more than 3 prior sigmas from the nominal</li>"));

  CHECK_FALSE(has(html, "class=\"fit-residuals\""));
  const int plots = count(html, "<svg class=\"plot\"");
  run.fit_residuals = {{std::vector<double>(run.joints.size(), 0.1), 0.2e-3, false},
                       {std::vector<double>(run.joints.size(), 0.3), 0.3e-3, false},
                       {std::vector<double>(run.joints.size(), 0.5), 2.5e-3, true}};
  html = render_html(report);
  CHECK(count(html, "<svg class=\"plot\"") == plots + static_cast<int>(run.joints.size()));
  const std::size_t section = html.find("<section class=\"fit-residuals\"");
  REQUIRE(section != std::string::npos);
  const std::string body = html.substr(section, html.find("</section>", section) - section);
  CHECK(count(body, ">rejected</text>") == static_cast<int>(run.joints.size()));
  CHECK(has(body, "the rows rejected as outliers (left out of the fit) marked"));
  run.fit_residuals[1].q.pop_back();
  CHECK_THROWS_WITH_AS(render_html(report), doctest::Contains("fit residual 2: "), ReportError);
}

TEST_CASE("camera page: its tables, each camera's sections exactly when their data are given, rows checked") {
  CameraReport lens;
  lens.title = "Left camera";
  lens.width_px = 640;
  lens.height_px = 480;
  lens.field_x_px = {100, 500};
  lens.field_y_px = {100, 400};
  lens.field_dx_px = {-2, 3};
  lens.field_dy_px = {-1.5, 2};
  CameraReport corners = lens;
  corners.title = "Right camera";
  corners.field_x_px = corners.field_y_px = corners.field_dx_px = corners.field_dy_px = {};
  corners.views.push_back({"right01.jpg", {10, 20}, {30, 40}, {0.1, -0.2}, {0.05, 0.0}, 0.16});
  CameraPage page{"Stereo calibration", "2026-11-26", {"baseline: 0.083 m"}, {}, {lens, corners}};
  page.tables.push_back({"pairs", {"Pairs", {"left / right", "status"}, {{"l01 / r01", "used"}}, "a note"}});
  const std::string html = render_camera_page_html(page);
  CHECK(has(html, "<section class=\"table\" id=\"pairs\"><h3>Pairs</h3>"));
  CHECK(has(html, "<td>l01 / r01</td><td>used</td>"));
  CHECK(has(html, "<p class=\"note\">a note</p>"));
  CHECK(count(html, "<section class=\"camera\">") == 2);
  // The lens-only camera: distortion only; the other: residuals and coverage only.
  CHECK(count(html, "<section class=\"distortion\">") == 1);
  CHECK(count(html, "<section class=\"residuals\">") == 1);
  CHECK(count(html, "<section class=\"coverage\">") == 1);
  CHECK(count(html, "<section class=\"uncertainty\">") == 0);
  CHECK(count(html, "<section class=\"summary\">") == 1);  // the cameras have no facts
  CHECK(html.find("Left camera") < html.find("Right camera"));
  page.tables.front().table.rows.push_back({"l02 / r02"});
  CHECK_THROWS_WITH_AS(render_camera_page_html(page), "table 'Pairs', row 2: 1 cells for 2 columns", ReportError);
}

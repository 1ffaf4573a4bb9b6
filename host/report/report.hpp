// The calibration report people read: one self-contained HTML file (inline CSS, inline SVG
// plots; no scripts, no fonts or images from anywhere) that opens in any browser, from plain
// numbers and strings. The session and the demo fill the structs below from the
// identification's results; this module knows nothing of how they were obtained.
//
// A Report holds one or more runs (the demo calibrates two rigs); each run's section shows, when
// its data are given (an empty vector / absent optional leaves the section out entirely):
//   facts            robot, method, data source, measurement count, simulated or measured (or
//                    that the data do not say);
//   model            per joint, base and tool: each parameter's nominal and identified value,
//                    the change, its 1-sigma, and when simulated the true value and the error --
//                    measured from the true value as the data can identify it when that is
//                    given (the held-fixed parameters it absorbs named), so that a correct
//                    result is never marked; errors beyond 3 sigma are marked, and a legend
//                    under the table says what each mark means;
//                    with a prior (identify's MAP, issue #23): its prior sigma and the share of
//                    its information the data give; a change beyond 3 prior sigmas is marked;
//   identifiability  the parameters held fixed and why, and free-text notes (a note's further
//                    lines, after '\n', are listed under it one by one);
//   accuracy         per model (e.g. nominal, identified): mean, RMS, max position error on the
//                    validation poses, or what accuracy_of names (and orientation when given), as
//                    a table and a dot plot;
//   residuals        position error per validation pose before/after, and after vs each joint's
//                    reading, one small plot per joint;
//   fit residuals    each measurement's position residual under the identified model against
//                    each joint's reading, one small plot per joint, the rows rejected as
//                    outliers marked;
//   sweeps           each single-joint sweep in 3-D (an orthographic view from above the fit's
//                    plane, the axis upright: the points, the fitted circle or line, the axis,
//                    the device frame's directions, the points' offsets from the fit magnified
//                    by a stated factor), then its points projected into the fit plane with the
//                    fitted circle (revolute) or line (prismatic), radius and RMS, and the
//                    residual of every point;
//   bus              CAN statistics (frames, bytes, errors, load);
//   comparisons      tables of values side by side (e.g. Kapucu & Baysec's Table 1, ours, truth);
//   tables           tables of text (e.g. the joint-type tests' p-values).
//
// Units: every input is SI (m, rad, s). Shown as the reader expects, one unit per table row:
// lengths in mm; angles in deg, or in mrad in a row whose values are all below 0.1 rad (small
// angles: base and tool rotations, angle offsets); ratios plain; compliances in urad/(N m) or
// um/N; joint readings in deg (revolute) or mm.
// Lengths in plot notes and axes are in um below 1 mm and in mm from there (one rule,
// length_unit() in report.cpp, for every plot). All text is HTML-escaped.
//
// Cost: O(size of the data); a run with 200 validation poses and 6 joints renders in a few
// milliseconds into about 200 kB. Thread safety: pure functions.
//
// Errors: ReportError, its message naming the run (index and title) and the item at fault --
// a validation pose or a fit residual whose joint readings do not match the run's joints; a comparison row or a
// text table's row with more or fewer values than columns; a sweep of a joint the run does not have, with fewer than
// 3 points or a zero axis direction; a non-finite number where a plot needs it; a negative
// count or sigma. write_html() also throws ReportError when the file cannot be written.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace kincal::report {

class ReportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What a parameter's value measures (SI): a joint's scale is a ratio; a compliance is rad/(N m)
// on a revolute joint, m/N on a prismatic one.
enum class Quantity { length_m, angle_rad, ratio, compliance_rad_per_nm, compliance_m_per_n, mass_kg };

struct ParameterRow {
  std::string group;  // "joint 1", "base", "tool": rows of a group are shown together, in order
  std::string name;   // "a2", "theta3", "base_rx"
  Quantity quantity = Quantity::length_m;
  double nominal = 0.0;          // SI
  double identified = 0.0;       // SI
  std::optional<double> stddev;  // 1-sigma, SI; absent for a parameter held fixed or at_bound
  std::optional<double> truth;   // SI; simulated data only
  // The true value as the data can identify it (simulated data only): the true model fitted in
  // the identified parameters, the held-fixed ones at their starting values -- what a solve
  // from noise-free data at the same poses gives. It differs from `truth` by what the
  // held-fixed parameters' true errors put on this one; `absorbs` names them ("d1-d4, tool_z").
  // The error is measured from it when given.
  std::optional<double> identifiable_truth;
  std::string absorbs;
  // The prior on the deviation from `nominal` (identify's MAP): its 1-sigma, SI (absent: no
  // prior), and the share of the parameter's posterior information the data give, 0..1.
  std::optional<double> prior_sigma;
  std::optional<double> data_share;
  bool at_bound = false;  // ended on its physical bound, which holds it (identify.hpp)
};

struct HeldFixed {
  std::string parameter;
  std::string reason;
};

// Errors of one model on the validation poses (identify::AccuracyStats's numbers).
struct Accuracy {
  std::string label;  // "nominal model", "identified (full)"
  int count = 0;
  double mean_m = 0.0, rms_m = 0.0, max_m = 0.0;
  std::optional<double> mean_rad, rms_rad, max_rad;  // orientation, when measured
};

struct ValidationPose {
  std::vector<double> q;  // joint readings, rad or m (one per Run::joints entry)
  double before_m = 0.0;  // position error of the nominal model
  double after_m = 0.0;   // position error of the identified model
};

// A measurement the model was identified from, and its position error under the identified
// model (the fit's residual; for a rejected row, how far the model misses it).
struct FitResidual {
  std::vector<double> q;  // joint readings, rad or m (one per Run::joints entry)
  double residual_m = 0.0;
  bool rejected = false;  // left out of the fit as an outlier
};

struct JointInfo {
  std::string name;
  bool prismatic = false;
};

// One single-joint sweep and its fit (identify::SweepFit plus the sweep's measured points).
struct SweepPlot {
  int joint = 0;                                           // 0-based index into Run::joints
  bool circle = true;                                      // revolute: circle about the axis; prismatic: line along it
  Eigen::Vector3d axis_point_m = Eigen::Vector3d::Zero();  // on the axis (circle: its centre's line)
  Eigen::Vector3d axis_direction = Eigen::Vector3d::UnitZ();
  double radius_m = 0.0;                  // circle
  double rms_m = 0.0;                     // of the fit's residuals
  int rejected = 0;                       // points the fit rejected as outliers
  std::vector<Eigen::Vector3d> points_m;  // the sweep's measured points, device frame
};

struct BusStatistics {
  std::string bus;  // e.g. "in-process loopback, classic CAN 1 Mbit/s"
  std::uint64_t frames = 0;
  std::uint64_t bytes = 0;  // payload bytes
  std::uint64_t errors = 0;
  double seconds = 0.0;  // time the statistics cover
  double load = 0.0;     // fraction of the bus time used, 0..1
};

struct ComparisonRow {
  std::string name;
  Quantity quantity = Quantity::length_m;
  std::vector<std::optional<double>> values;  // SI, one per column; absent: not given there
};

struct Comparison {
  std::string title;                 // "Kapucu & Baysec, Table 1, vs ours"
  std::vector<std::string> columns;  // "Kapucu & Baysec", "ours (full)", "truth"
  std::vector<ComparisonRow> rows;
  std::string note;
};

// A table of text: rows of cells, one per column.
struct TextTable {
  std::string title;
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;
  std::string note;
};

struct Run {
  std::string title;
  std::string robot;
  std::string method;
  std::string data;  // where the measurements came from
  // Simulated (true values known) or measured; absent: not known (e.g. a data file that does
  // not say), and the report says so.
  std::optional<bool> simulated = false;
  int measurements = 0;
  std::vector<JointInfo> joints;
  std::vector<ParameterRow> parameters;
  std::vector<HeldFixed> held_fixed;
  std::vector<std::string> notes;
  std::vector<Accuracy> accuracy;
  std::string accuracy_of = "the validation poses";  // what the accuracy rows measure on
  std::vector<ValidationPose> validation;
  std::vector<FitResidual> fit_residuals;
  std::vector<SweepPlot> sweeps;
  std::optional<BusStatistics> bus;
  std::vector<Comparison> comparisons;
  std::vector<TextTable> tables;
};

struct Report {
  std::string title;
  std::string date;  // shown as given (e.g. ISO 8601), so reports are reproducible
  std::vector<Run> runs;
};

// The current time as reports date themselves ("2026-11-24 04:20 UTC").
std::string utc_date_now();

// The whole HTML document. Throws ReportError (see above).
std::string render_html(const Report& report);
// A page in the report's style around `body_html` (already escaped): title, date and the CSS;
// the camera report (camera_report.hpp) shares it.
std::string html_page(const std::string& title, const std::string& date, const std::string& body_html);
// A TextTable as a <section class="table" id="`id`">; ReportError for a row with more or fewer
// cells than columns (render_html refuses it first, naming the run).
std::string table_section(const TextTable& table, const std::string& id);
// `html` written whole to `path` (host/files/output_file.hpp); ReportError naming the path.
void write_page(const std::string& html, const std::string& path);
// render_html() written whole to `path`, replacing it (host/files/output_file.hpp).
void write_html(const Report& report, const std::string& path);

}  // namespace kincal::report

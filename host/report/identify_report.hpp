// The report of one `kincal identify` run (issue #23): the calibration report (report.hpp, one
// self-contained HTML page) for measured data, filled from identify's own results -- what a user
// reads to judge a calibration from a laser tracker's export and to trace a rejected row back to
// the tracker's record.
//
// One run section (report.hpp's sections, in its order):
//   facts            the robot, the method and how the model was chosen, the data file with its
//                    rows, the rows used and rejected; "measured" is not claimed (a dataset does
//                    not say);
//   model            every identified parameter: nominal, identified, change, posterior 1-sigma,
//                    prior sigma and the share of its information the data give; a change beyond
//                    3 prior sigmas is marked. Link parameters are the chain's values (joint
//                    offsets folded in), in the parameterization identify solved in (a standard-DH
//                    pair promoted to Doty keeps its beta); base and tool rows are small motions
//                    of those frames from the registered start (nominal 0, or the prior's centre);
//   identifiability  the parameters held fixed and why; notes: the rank and condition number,
//                    the solver's termination, identify's notes, the noise model;
//   accuracy         the registered nominal (the baseline: only the registration and the tool
//                    fitted) and the calibrated model on the rows used, and on held-out rows when
//                    given;
//   fit residuals    each row's position error under the identified model against each joint's
//                    reading, the rejected rows marked;
//   tables           the model selection table with its reason (when cross-validation ran), and
//                    the rejected rows: the dataset's line, the row's id or time stamp (`kincal
//                    import --id`), the residual, the statistic over its threshold and how far
//                    removing the row moves the predicted tool; and the rows the rejection gate
//                    let back into the fit (IdentifyResult::rejection_gate.undone) in a table of
//                    their own, each table's note with the gate's figures, its t and its verdict,
//                    as identify prints them.
//
// Cost: one forward kinematics per row (the residuals, the held-out accuracy). Thread safety:
// pure functions. Errors: ReportError (report.hpp) for rows whose readings do not match the
// robot's joints.
#pragma once

#include <optional>
#include <string>

#include "host/identify/identify.hpp"
#include "host/identify/model_selection.hpp"
#include "host/model/dataset.hpp"
#include "host/report/report.hpp"

namespace kincal::report {

struct IdentifyRun {
  const model::RobotModel& nominal;
  const model::Dataset& data;  // the rows identified from (all of them, the rejected too)
  const identify::IdentifyResult& result;
  std::string model_choice;                              // how the model was chosen, as identify printed it
  const identify::Selection* selection = nullptr;        // when cross-validation ran
  const identify::IdentifyResult* registered = nullptr;  // the baseline (identify_registration)
  const model::Dataset* held_out = nullptr;              // --validate's rows
};

// The report of one run, dated `date` (utc_date_now(), or fixed for a reproducible file); render
// with render_html() or write with write_html().
Report identify_report(const IdentifyRun& run, const std::string& date);

// A parameter as the reports show it (see "model" above), shared by identify's report and the
// session's (host/session/session_report.hpp): its value in `model` (base and tool: the small
// motion from `start`), its table group ("joint 2", "base", "tool", the joints' scales and
// compliances together) and what it measures.
double parameter_value(const model::RobotModel& model, const model::RobotModel& start, core::ParameterId id);
// The model table's row of `result`'s k-th identified parameter (see "model" above): group, name,
// quantity, nominal, identified, posterior sigma, prior sigma and the data's share; the session's
// report adds the truth.
ParameterRow parameter_row(const identify::IdentifyResult& result, std::size_t k);
std::string parameter_group(core::ParameterId id);
Quantity parameter_quantity(const model::RobotModel& model, core::ParameterId id);

// identify's accuracy figures as a report row labelled `label` (orientation when it has them).
Accuracy report_accuracy(const std::string& label, const identify::AccuracyStats& s);

}  // namespace kincal::report

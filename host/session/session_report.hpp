// A calibration run as the report shows it (issue #6): host/report's plain numbers filled from a
// session's data and its identification, so that `kincal session` and `kincal demo` write the
// same report.
//
//   parameters  every identified parameter as identify's report shows it (report::parameter_row:
//               the nominal -- in the parameters identify solved in, from a cpa start the
//               prior's centre --, the identified value, its 1-sigma, its prior sigma and the
//               share of its information the data give; link parameters are the chain's values,
//               joint offsets folded in; base and tool rows are small motions of those frames
//               from the starting model) and, when the data are simulated, the true value and
//               the true value as the data can identify it: the true model's tool poses at the
//               calibration readings fitted in the identified parameters (Gauss-Newton, weighted
//               as the identification weighs a measurement), the held-fixed ones at their
//               starting values; a held-fixed parameter whose true error moves an identified one
//               by more than half its sigma (to first order) is named as absorbed by it.
//   validation  per validation pose, the position error of the nominal and the identified model.
//   sweeps      each single-joint sweep of the calibration data with its circle or line fit,
//               when circle-point analysis ran (cpa).
//   bus         frames, payload bytes and bus load from the session's candump log.
// Errors: model::InputError (a truth model of another joint count), can::CanError (log).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "host/identify/cpa.hpp"
#include "host/report/identify_report.hpp"
#include "host/session/session.hpp"

namespace kincal::session {

struct RunDescription {
  std::string title, robot, method, data;
  bool simulated = false;
};

report::Run report_run(const RunDescription& description, const model::RobotModel& nominal, const SessionData& data,
                       const Calibration& calibration, const std::optional<model::RobotModel>& truth,
                       const identify::CpaResult* cpa);

// identify's figures as the reports show them (host/report/identify_report.hpp).
using report::parameter_value;
using report::report_accuracy;

// Each fit's sweep for the report: the fit (device frame) with the sweep's measured points,
// found in `data` as identify::find_sweeps finds them; fits of joints without a sweep are left
// out. report_run uses it for cpa; `kincal discover --report` for the discovered fits.
std::vector<report::SweepPlot> report_sweeps(const model::Dataset& data, const std::vector<identify::SweepFit>& fits,
                                             double still_tolerance = 0.0);

// Frames, payload bytes, span and load of a candump -L log of a bus at `bit_rate` (worst-case
// bit stuffing, as host/can/bus_budget counts frames).
report::BusStatistics bus_statistics(const std::string& candump_log, const std::string& bus, double bit_rate);

}  // namespace kincal::session

#include "host/report/identify_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "host/identify/problem.hpp"
#include "host/report/svg_plot.hpp"

namespace kincal::report {

namespace {

std::string mm_text(double m) {
  char text[48];
  std::snprintf(text, sizeof text, "%.4f mm", m * 1e3);
  return text;
}

TextTable selection_table(const identify::Selection& s) {
  const std::string folds = s.leave_one_out ? std::string("leave-one-out") : std::to_string(s.folds) + "-fold";
  TextTable t;
  t.title = "Model selection";
  t.columns = {"candidate", "parameters", folds + " RMS", "out-of-range RMS", "score", "chosen / why not scored"};
  for (const identify::CandidateScore& x : s.scores) {
    const auto rms = [](double v) { return v < 0.0 ? std::string("-") : mm_text(v); };
    t.rows.push_back({x.name, std::to_string(x.parameters), rms(x.kfold_rms_m), rms(x.out_of_range_rms_m),
                      rms(x.score_m), x.name == s.chosen.name ? "chosen" : x.why});
  }
  t.note = "Position RMS of rows each candidate was not identified from: " + folds +
           " cross-validation, and an out-of-range fold (train on the " + std::to_string(s.out_of_range_train_rows) +
           " rows inside the central " + fixed_text(s.out_of_range_fraction * 100.0, 0) +
           " % of every joint's range, predict the other " + std::to_string(s.out_of_range_test_rows) +
           "). Chosen: " + s.reason;
  return t;
}

// The rejection gate's figures and verdict, as identify prints them (identify.hpp).
std::string gate_text(const identify::RejectionGate& g) {
  std::string text = "The rejection gate: 5-fold cross-validated position RMS " + mm_text(g.kfold_with_m) +
                     " with the rejection rule, " + mm_text(g.kfold_without_m) + " without (paired t " +
                     fixed_text(g.kfold_t, 2) + ")";
  if (g.out_of_range_with_m >= 0.0)
    text += "; out-of-range fold " + mm_text(g.out_of_range_with_m) + " with, " + mm_text(g.out_of_range_without_m) +
            " without";
  return text + ". The rejections stand only when they lower the 5-fold errors by 2 standard errors (t <= -2) and " +
         "do not raise the out-of-range fold's RMS: " +
         (g.kept ? "they stand."
                 : "they did not, so the rows stay in the fit (it does not clearly lower the held-out "
                   "error).");
}

// The rows of `rejections` with the dataset's line and the row's id or time stamp.
TextTable rejection_rows(std::string title, const std::vector<identify::Rejection>& rejections,
                         const std::map<int, const model::Measurement*>& by_line) {
  TextTable t;
  t.title = std::move(title);
  t.columns = {"line", "id / time stamp", "residual", "statistic / threshold", "removing it moves the tool by up to"};
  for (const identify::Rejection& x : rejections) {
    const auto row = by_line.find(x.line);
    t.rows.push_back({std::to_string(x.line), row != by_line.end() ? row->second->id : std::string(),
                      mm_text(x.residual_m), fixed_text(x.statistic_ratio, 2), mm_text(x.tool_shift_max_m)});
  }
  return t;
}

const char* const kRejectionColumns =
    "line in the dataset, the row's id or time stamp from the export (kincal import --id), the position residual "
    "of the fit with the row, its studentized statistic over the rejection threshold, and the largest change of "
    "the predicted tool position over the data when it is removed (first order).";

TextTable rejection_table(const identify::IdentifyResult& r, const std::map<int, const model::Measurement*>& by_line) {
  TextTable t = rejection_rows("Rejected rows", r.rejections, by_line);
  t.note = std::string("Rows left out of the fit as outliers: ") + kRejectionColumns +
           " Model error before rejection " + mm_text(r.model_error_before_rejection_m) + ", after " +
           mm_text(r.model_error_position_m) + " per axis." +
           (r.rejection_gate.judged ? " " + gate_text(r.rejection_gate) : std::string());
  return t;
}

// The rows the outlier test rejected and the rejection gate let back in (they are in the fit).
TextTable undone_table(const identify::RejectionGate& g, const std::map<int, const model::Measurement*>& by_line) {
  TextTable t = rejection_rows("Rejections undone by the rejection gate", g.undone, by_line);
  t.note = std::string("Rows the outlier test rejected and the rejection gate let back into the fit: ") +
           kRejectionColumns + " " + gate_text(g);
  return t;
}

}  // namespace

Report identify_report(const IdentifyRun& in, const std::string& date) {
  const identify::IdentifyResult& r = in.result;
  Report report;
  report.title = "kincal identify: " + in.nominal.name;
  report.date = date;
  Run run;
  run.title = "Identification from " + in.data.source;
  run.robot = in.nominal.name;
  run.method = (r.model.calibration ? r.model.calibration->method : std::string("?")) + "; model: " + in.model_choice;
  run.data = in.data.source + ": " + std::to_string(in.data.rows.size()) + " rows, " +
             std::to_string(r.residuals.count) + " used, " + std::to_string(r.outlier_lines.size()) +
             " rejected as outliers";
  run.simulated = std::nullopt;
  run.measurements = static_cast<int>(in.data.rows.size());
  for (const model::Joint& j : in.nominal.joints) run.joints.push_back({j.name, j.type == core::JointType::prismatic});

  for (std::size_t k = 0; k < r.identifiability.identified.size(); ++k) run.parameters.push_back(parameter_row(r, k));
  for (const identify::HeldFixed& h : r.identifiability.held_fixed)
    run.held_fixed.push_back({model::parameter_name(h.id), h.reason});
  const identify::ParameterIds& ids = r.identifiability.identified;
  if (!ids.empty()) {
    char condition[48];
    std::snprintf(condition, sizeof condition, "%.3g", r.identifiability.condition);
    run.notes.push_back("identifiability: rank " + std::to_string(r.identifiability.rank) + " of " +
                        std::to_string(r.identifiability.singular_values.size()) + " candidate parameters; " +
                        std::to_string(ids.size()) + " identified, condition number (unit-scaled columns) " +
                        condition);
  }
  run.notes.push_back("solver: " + r.termination +
                      (r.iterations > 0 ? ", " + std::to_string(r.iterations) + " iterations" : std::string()));
  run.notes.insert(run.notes.end(), r.notes.begin(), r.notes.end());
  run.notes.insert(run.notes.end(), r.cpa_sweeps.begin(), r.cpa_sweeps.end());
  run.notes.push_back(identify::format_noise(r));

  run.accuracy_of = in.held_out ? "the rows used and the held-out rows" : "the rows used";
  if (in.registered)
    run.accuracy.push_back(report_accuracy("nominal, registered: rows used", in.registered->residuals));
  run.accuracy.push_back(report_accuracy("calibrated: rows used", r.residuals));
  if (in.held_out) {
    if (in.registered)
      run.accuracy.push_back(report_accuracy("nominal, registered: held out (" + in.held_out->source + ")",
                                             identify::accuracy(in.registered->model, *in.held_out)));
    run.accuracy.push_back(report_accuracy("calibrated: held out (" + in.held_out->source + ")",
                                           identify::accuracy(r.model, *in.held_out)));
  }

  std::map<int, const model::Measurement*> by_line;
  for (const model::Measurement& m : in.data.rows) by_line[m.line] = &m;
  for (const model::Measurement& m : in.data.rows) {
    if (m.q.size() != in.nominal.joints.size())
      throw ReportError("identify report: " + in.data.source + ":" + std::to_string(m.line) + ": " +
                        std::to_string(m.q.size()) + " joint readings, the model has " +
                        std::to_string(in.nominal.joints.size()) + " joints");
    const double residual = (model::forward_kinematics(r.model, m.q).translation - m.position).norm();
    const bool rejected = std::find(r.outlier_lines.begin(), r.outlier_lines.end(), m.line) != r.outlier_lines.end();
    run.fit_residuals.push_back({m.q, residual, rejected});
  }
  if (in.selection) run.tables.push_back(selection_table(*in.selection));
  if (!r.rejections.empty()) run.tables.push_back(rejection_table(r, by_line));
  if (!r.rejection_gate.undone.empty()) run.tables.push_back(undone_table(r.rejection_gate, by_line));
  report.runs.push_back(std::move(run));
  return report;
}

ParameterRow parameter_row(const identify::IdentifyResult& r, std::size_t k) {
  const identify::ParameterIds& ids = r.identifiability.identified;
  const bool priors = r.prior_sigma.size() == r.change.size() && r.prior_centre.size() == r.change.size();
  const auto i = static_cast<Eigen::Index>(k);
  ParameterRow row;
  row.group = parameter_group(ids[k]);
  row.name = model::parameter_name(ids[k]);
  row.quantity = parameter_quantity(r.start, ids[k]);
  // The nominal in the start's parameters: the prior's centre (0 but from a cpa start).
  row.nominal = parameter_value(r.start, r.start, ids[k]) + (priors ? r.prior_centre(i) : 0.0);
  row.identified = parameter_value(r.model, r.start, ids[k]);
  row.at_bound = k < r.at_bound.size() && r.at_bound[k];
  if (i < r.stddev.size() && !row.at_bound) row.stddev = r.stddev(i);
  if (priors && std::isfinite(r.prior_sigma(i))) row.prior_sigma = r.prior_sigma(i);
  if (priors && i < r.prior_share.size() && !row.at_bound) row.data_share = 1.0 - r.prior_share(i);
  return row;
}

double parameter_value(const model::RobotModel& model, const model::RobotModel& start, core::ParameterId id) {
  using K = core::ParameterKind;
  if (id.kind == model::kJointScale) return model.joints.at(id.link).scale.value_or(1.0);
  if (id.kind == model::kJointCompliance) return model.joints.at(id.link).compliance.value_or(0.0);
  if (id.kind == model::kLinkMass) return model.joints.at(id.link).mass_kg;
  if (model::is_mass_parameter(id.kind))
    return model.joints.at(id.link).centre_of_mass_m(static_cast<int>(id.kind) - static_cast<int>(model::kLinkCentreX));
  if (model::is_gravity_direction_parameter(id.kind)) {  // the turn from the start's direction
    const Eigen::Vector3d turn = start.gravity_mps2.normalized().cross(model.gravity_mps2.normalized());
    return std::asin(std::clamp(turn(id.kind == model::kGravityRx ? 0 : 1), -1.0, 1.0));
  }
  if (id.kind == model::kJointCoupling) {
    const std::vector<double>& row = model.joints.at(id.link).coupling;
    return row.empty() ? 0.0 : row.at(id.link - 1U);
  }
  if (id.kind >= K::base_x && id.kind <= K::base_rz)
    return identify::small_motion(start.base_T_frame0,
                                  model.base_T_frame0)(static_cast<int>(id.kind) - static_cast<int>(K::base_x));
  if (id.kind >= K::tool_x)
    return identify::small_motion(start.flange_T_tool,
                                  model.flange_T_tool)(static_cast<int>(id.kind) - static_cast<int>(K::tool_x));
  const core::LinkParameters<double> p = model::to_chain(model).links[id.link].parameters;
  switch (id.kind) {
    case K::link_d:
      return p.d_m;
    case K::link_theta:
      return p.theta_rad;
    case K::link_a:
      return p.a_m;
    case K::link_alpha:
      return p.alpha_rad;
    default:
      return p.beta_rad;
  }
}

Quantity parameter_quantity(const model::RobotModel& model, core::ParameterId id) {
  using K = core::ParameterKind;
  if (id.kind == model::kJointScale || id.kind == model::kJointCoupling) return Quantity::ratio;
  if (id.kind == model::kJointCompliance)
    return model.joints.at(id.link).type == core::JointType::prismatic ? Quantity::compliance_m_per_n
                                                                       : Quantity::compliance_rad_per_nm;
  if (id.kind == model::kLinkMass) return Quantity::mass_kg;
  if (model::is_mass_parameter(id.kind)) return Quantity::length_m;
  if (model::is_gravity_direction_parameter(id.kind)) return Quantity::angle_rad;
  const bool angle = id.kind == K::link_theta || id.kind == K::link_alpha || id.kind == K::link_beta ||
                     (id.kind >= K::base_rx && id.kind <= K::base_rz) || id.kind >= K::tool_rx;
  return angle ? Quantity::angle_rad : Quantity::length_m;
}

std::string parameter_group(core::ParameterId id) {
  using K = core::ParameterKind;
  if (id.kind >= K::base_x && id.kind <= K::base_rz) return "base";
  if (model::is_mass_parameter(id.kind)) return "link masses (in the sag's gauge)";
  if (model::is_gravity_direction_parameter(id.kind)) return "gravity's direction in frame 0";
  if (model::is_joint_map_parameter(id.kind)) return "joint readings: scales, compliances and couplings";
  if (id.kind >= K::tool_x) return "tool";
  return "joint " + std::to_string(id.link + 1);
}

Accuracy report_accuracy(const std::string& label, const identify::AccuracyStats& s) {
  Accuracy a;
  a.label = label;
  a.count = s.count;
  a.mean_m = s.mean_m;
  a.rms_m = s.rms_m;
  a.max_m = s.max_m;
  if (s.has_orientation) {
    a.mean_rad = s.mean_rad;
    a.rms_rad = s.rms_rad;
    a.max_rad = s.max_rad;
  }
  return a;
}

}  // namespace kincal::report

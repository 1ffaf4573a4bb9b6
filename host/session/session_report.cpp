#include "host/session/session_report.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <Eigen/QR>

#include "host/can/bus_budget.hpp"
#include "host/can/candump_log.hpp"
#include "host/identify/problem.hpp"

namespace kincal::session {

namespace {

double error_of(const model::RobotModel& model, std::span<const double> q, const model::Vector3& measured) {
  return (model::forward_kinematics(model, q).translation - measured).norm();
}

// The truth as the data can identify it (report.hpp, ParameterRow::identifiable_truth).
struct IdentifiableTruth {
  model::RobotModel model;           // the true model fitted in the identified parameters
  std::vector<std::string> absorbs;  // per identified parameter: held-fixed ones it takes up
};

// "d1, d2, d3, d4, tool_z" as "d1-d4, tool_z": runs of 3 or more consecutive numbers of a name.
std::string name_list(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size();) {
    const auto split = [](const std::string& n) {
      const std::size_t digits = n.find_last_not_of("0123456789") + 1;
      return std::pair<std::string, int>(n.substr(0, digits), digits < n.size() ? std::stoi(n.substr(digits)) : -1);
    };
    const auto [stem, number] = split(names[i]);
    std::size_t j = i + 1;
    while (number >= 0 && j < names.size() && split(names[j]) == std::pair(stem, number + static_cast<int>(j - i))) ++j;
    out += (out.empty() ? "" : ", ") + (j - i >= 3 ? names[i] + "\u2013" + names[j - 1] : names[i]);
    if (j - i < 3) j = i + 1;
    i = j;
  }
  return out;
}

// Fits the identified parameters (from r.start, the held-fixed ones at their starting values)
// to the true model's tool poses at the calibration readings by Gauss-Newton from the identified
// change, each pose weighted as the identification weighs a measurement (its position and
// orientation sigmas with the model error); the held-fixed parameters whose true errors move an
// identified one by more than half its sigma (to first order) are named as absorbed by it.
IdentifiableTruth identifiable_truth(const identify::IdentifyResult& r, const model::Dataset& calibration,
                                     const model::RobotModel& truth) {
  const identify::ParameterIds& ids = r.identifiability.identified;
  const bool orientation = r.orientation_used && calibration.has_orientation;
  model::Dataset poses;
  poses.joint_count = calibration.joint_count;
  poses.has_orientation = orientation;
  for (const model::Measurement& m : calibration.rows) {
    const model::Transform pose = model::forward_kinematics(truth, m.q);
    model::Measurement row;
    row.q = m.q;
    row.position = pose.translation;
    if (orientation) row.orientation = Eigen::Quaterniond(pose.rotation);
    poses.rows.push_back(std::move(row));
  }
  const auto positive = [](double v, double fallback) { return v > 0.0 ? v : fallback; };
  const identify::Weights weights = identify::make_weights(
      poses, positive(std::hypot(r.median_instrument_sigma_m, r.model_error_position_m), 1e-4),
      orientation ? positive(std::hypot(r.orientation_sigma_rad, r.model_error_orientation_rad), 1e-3) : 0.0);
  std::vector<int> rows(poses.rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) rows[i] = static_cast<int>(i);

  identify::Parameterization fit(r.start, ids);
  Eigen::VectorXd delta = r.change.size() == fit.size() ? r.change : Eigen::VectorXd::Zero(fit.size());
  Eigen::VectorXd residual;
  Eigen::MatrixXd jacobian;
  for (int iteration = 0; iteration < 20 && fit.size() > 0; ++iteration) {
    fit.set(std::span<const double>(delta.data(), static_cast<std::size_t>(delta.size())));
    identify::stacked(fit, poses, weights, rows, residual, &jacobian);
    const Eigen::VectorXd step = jacobian.colPivHouseholderQr().solve(-residual);
    delta += step;
    if (!(step.norm() > 1e-12 * (1.0 + delta.norm()))) break;
  }
  fit.set(std::span<const double>(delta.data(), static_cast<std::size_t>(delta.size())));
  IdentifiableTruth out{fit.model(), std::vector<std::string>(ids.size())};

  // What each held-fixed parameter's true error puts on the identified ones: its column
  // projected on theirs, times the error.
  identify::ParameterIds all = ids;
  for (const identify::HeldFixed& h : r.identifiability.held_fixed) all.push_back(h.id);
  identify::Parameterization linear(r.start, all);
  Eigen::VectorXd at = Eigen::VectorXd::Zero(linear.size());
  at.head(delta.size()) = delta;
  linear.set(std::span<const double>(at.data(), static_cast<std::size_t>(at.size())));
  identify::stacked(linear, poses, weights, rows, residual, &jacobian);
  const Eigen::Index n = static_cast<Eigen::Index>(ids.size());
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(jacobian.leftCols(n));
  std::vector<std::vector<std::string>> names(ids.size());
  for (std::size_t h = 0; h < r.identifiability.held_fixed.size(); ++h) {
    const core::ParameterId id = r.identifiability.held_fixed[h].id;
    const double error = parameter_value(truth, r.start, id) - parameter_value(r.start, r.start, id);
    if (error == 0.0) continue;
    const Eigen::VectorXd shift = qr.solve(jacobian.col(n + static_cast<Eigen::Index>(h)) * error);
    for (Eigen::Index k = 0; k < n; ++k) {
      const double sigma = k < r.stddev.size() ? r.stddev(k) : 0.0;
      if (std::abs(shift(k)) > 0.5 * sigma && std::abs(shift(k)) > 0.0)
        names[static_cast<std::size_t>(k)].push_back(model::parameter_name(id));
    }
  }
  for (std::size_t k = 0; k < names.size(); ++k) out.absorbs[k] = name_list(names[k]);
  return out;
}

}  // namespace

report::Run report_run(const RunDescription& description, const model::RobotModel& nominal, const SessionData& data,
                       const Calibration& calibration, const std::optional<model::RobotModel>& truth,
                       const identify::CpaResult* cpa) {
  const identify::IdentifyResult& r = calibration.result;
  if (truth && truth->joint_count() != nominal.joint_count())
    throw model::InputError("report: the true model has " + std::to_string(truth->joint_count()) + " joints, the " +
                            "nominal one " + std::to_string(nominal.joint_count()));
  report::Run run;
  run.title = description.title;
  run.robot = description.robot;
  run.method = description.method;
  run.data = description.data;
  run.simulated = description.simulated;
  run.measurements = static_cast<int>(data.calibration.rows.size());
  for (const model::Joint& j : nominal.joints) run.joints.push_back({j.name, j.type == core::JointType::prismatic});

  const identify::ParameterIds& ids = r.identifiability.identified;
  const std::optional<IdentifiableTruth> identifiable =
      truth && !data.calibration.rows.empty() ? std::optional(identifiable_truth(r, data.calibration, *truth))
                                              : std::nullopt;
  for (std::size_t k = 0; k < ids.size(); ++k) {
    report::ParameterRow row = report::parameter_row(r, k);
    if (truth) row.truth = parameter_value(*truth, r.start, ids[k]);
    if (identifiable) {
      row.identifiable_truth = parameter_value(identifiable->model, r.start, ids[k]);
      row.absorbs = identifiable->absorbs[k];
    }
    run.parameters.push_back(row);
  }
  for (const identify::HeldFixed& h : r.identifiability.held_fixed)
    run.held_fixed.push_back({model::parameter_name(h.id), h.reason});
  run.notes = r.notes;
  run.notes.push_back(identify::format_noise(r));

  if (!data.validation.rows.empty()) {
    run.accuracy.push_back(report_accuracy("nominal model", calibration.before));
    run.accuracy.push_back(report_accuracy("identified model", calibration.after));
    for (const model::Measurement& m : data.validation.rows)
      run.validation.push_back({m.q, error_of(nominal, m.q, m.position), error_of(r.model, m.q, m.position)});
  }

  if (cpa) run.sweeps = report_sweeps(data.calibration, cpa->fits);
  return run;
}

std::vector<report::SweepPlot> report_sweeps(const model::Dataset& data, const std::vector<identify::SweepFit>& fits,
                                             double still_tolerance) {
  std::vector<report::SweepPlot> plots;
  const std::vector<identify::Sweep> sweeps = identify::find_sweeps(data, still_tolerance);
  for (const identify::SweepFit& fit : fits) {
    const auto sweep = std::find_if(sweeps.begin(), sweeps.end(), [&](const auto& s) { return s.joint == fit.joint; });
    if (sweep == sweeps.end()) continue;
    report::SweepPlot plot;
    plot.joint = fit.joint;
    plot.circle = fit.curved;
    plot.axis_point_m = fit.axis.point;
    plot.axis_direction = fit.axis.direction;
    plot.radius_m = fit.radius_m;
    plot.rms_m = fit.rms_m;
    plot.rejected = static_cast<int>(fit.rejected_lines.size());
    for (int row : sweep->rows) plot.points_m.push_back(data.rows[static_cast<std::size_t>(row)].position);
    plots.push_back(std::move(plot));
  }
  return plots;
}

report::BusStatistics bus_statistics(const std::string& candump_log, const std::string& bus, double bit_rate) {
  report::BusStatistics s;
  s.bus = bus;
  can::CandumpReader reader(candump_log);
  can::BusConfig config;
  config.nominal_bit_rate = bit_rate;
  config.data_bit_rate = bit_rate;
  std::uint64_t first = 0, last = 0;
  double busy_s = 0;
  while (const std::optional<can::LoggedFrame> f = reader.next()) {
    if (s.frames == 0) first = f->time_us;
    last = f->time_us;
    ++s.frames;
    s.bytes += f->frame.length;
    busy_s +=
        (f->frame.fd ? can::fd_frame_time(f->frame.length, config) : can::classic_frame_time(f->frame.length, config))
            .seconds;
  }
  s.seconds = static_cast<double>(last - first) * 1e-6;
  s.load = s.seconds > 0 ? busy_s / s.seconds : 0.0;
  return s;
}

}  // namespace kincal::session

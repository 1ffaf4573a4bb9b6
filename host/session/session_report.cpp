#include "host/session/session_report.hpp"

#include <algorithm>

#include "host/can/bus_budget.hpp"
#include "host/can/candump_log.hpp"
#include "host/identify/problem.hpp"

namespace kincal::session {

namespace {

bool is_angle(core::ParameterKind k) {
  using K = core::ParameterKind;
  return k == K::link_theta || k == K::link_alpha || k == K::link_beta || (k >= K::base_rx && k <= K::base_rz) ||
         k >= K::tool_rx;
}

std::string group_of(core::ParameterId id) {
  using K = core::ParameterKind;
  if (id.kind >= K::base_x && id.kind <= K::base_rz) return "base";
  if (id.kind >= K::tool_x && !model::is_joint_map_parameter(id.kind)) return "tool";
  return "joint " + std::to_string(id.link + 1);
}

double error_of(const model::RobotModel& model, std::span<const double> q, const model::Vector3& measured) {
  return (model::forward_kinematics(model, q).translation - measured).norm();
}

}  // namespace

double parameter_value(const model::RobotModel& model, const model::RobotModel& start, core::ParameterId id) {
  using K = core::ParameterKind;
  if (id.kind == model::kJointScale) return model.joints.at(id.link).scale.value_or(1.0);
  if (id.kind == model::kJointCompliance) return model.joints.at(id.link).compliance.value_or(0.0);
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
  for (std::size_t k = 0; k < ids.size(); ++k) {
    report::ParameterRow row;
    row.group = group_of(ids[k]);
    row.name = model::parameter_name(ids[k]);
    row.quantity = is_angle(ids[k].kind) ? report::Quantity::angle_rad : report::Quantity::length_m;
    row.nominal = parameter_value(r.start, r.start, ids[k]);
    row.identified = parameter_value(r.model, r.start, ids[k]);
    if (static_cast<Eigen::Index>(k) < r.stddev.size()) row.stddev = r.stddev(static_cast<Eigen::Index>(k));
    if (truth) row.truth = parameter_value(*truth, r.start, ids[k]);
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

report::Accuracy report_accuracy(const std::string& label, const identify::AccuracyStats& s) {
  report::Accuracy a;
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

#include "host/demo/demo.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <numbers>
#include <ostream>
#include <random>

#include "host/demo/simulated_rig.hpp"
#include "host/identify/cpa.hpp"
#include "host/identify/problem.hpp"
#include "host/model/model_file.hpp"
#include "host/report/report.hpp"
#include "host/session/pose_plan.hpp"
#include "host/session/session_report.hpp"

namespace kincal::session {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

std::string text(const char* format, double a, double b = 0, double c = 0, double d = 0) {
  char line[256];
  std::snprintf(line, sizeof line, format, a, b, c, d);
  return line;
}

double rms_to_truth(const model::RobotModel& model, const model::RobotModel& truth, const model::Dataset& data) {
  double sum = 0;
  for (const model::Measurement& m : data.rows)
    sum += (model::forward_kinematics(model, m.q).translation - model::forward_kinematics(truth, m.q).translation)
               .squaredNorm();
  return std::sqrt(sum / static_cast<double>(data.rows.size()));
}

double noise_rms(const model::RobotModel& truth, const model::Dataset& data) {
  double sum = 0;
  for (const model::Measurement& m : data.rows)
    sum += (m.position - model::forward_kinematics(truth, m.q).translation).squaredNorm();
  return std::sqrt(sum / static_cast<double>(data.rows.size()));
}

// The rig's driver, remembering the joint readings of each move by pose index: the simulated
// robot stands exactly at its readings (simulated_rig.hpp), so they are its true joint positions.
class RecordingDriver : public RobotDriver {
 public:
  explicit RecordingDriver(RobotDriver& inner) : inner_(inner) {}
  std::vector<double> move_to(int index, const std::vector<double>& target) override {
    std::vector<double> readings = inner_.move_to(index, target);
    readings_[index] = readings;
    return readings;
  }
  std::string name() const override { return inner_.name(); }
  const std::map<int, std::vector<double>>& readings() const { return readings_; }

 private:
  RobotDriver& inner_;
  std::map<int, std::vector<double>> readings_;
};

// The errors of true tool poses against goals: position and orientation statistics.
identify::AccuracyStats pose_errors(const std::vector<model::Transform>& goals,
                                    const std::vector<model::Transform>& actual) {
  std::vector<double> position_m, angle_rad;
  for (std::size_t i = 0; i < goals.size(); ++i) {
    position_m.push_back((actual[i].translation - goals[i].translation).norm());
    angle_rad.push_back(identify::so3_log(goals[i].rotation.transpose() * actual[i].rotation).norm());
  }
  return identify::error_stats(position_m, angle_rad);
}

// The online correction judged by the truth: for each validation target q_nom, the true tool pose
// at q_nom (uncorrected) and at the joint readings the corrected target gave, against the target's
// goal -- the controller's model at q_nom placed with the identified base registration, as
// verify_online_correction() places it (the block corrects the arm, not the registration).
CorrectionTruth correction_vs_truth(const model::RobotModel& truth, const Calibration& calibration,
                                    const SessionData& data, const RecordingDriver& moves) {
  model::RobotModel goal_model = calibration.result.start;
  goal_model.base_T_frame0 = calibration.result.model.base_T_frame0;
  std::vector<model::Transform> goals, uncorrected, corrected;
  for (std::size_t i = 0; i < data.validation.rows.size(); ++i) {
    const int index = static_cast<int>(data.calibration.rows.size() + i);
    const auto moved = moves.readings().find(index);
    if (moved == moves.readings().end())
      throw SessionError("demo: validation pose " + std::to_string(i) + " was not moved to with its correction");
    const std::vector<double>& q = data.validation.rows[i].q;
    goals.push_back(model::forward_kinematics(goal_model, q));
    uncorrected.push_back(model::forward_kinematics(truth, q));
    corrected.push_back(model::forward_kinematics(truth, moved->second));
  }
  return {pose_errors(goals, uncorrected), pose_errors(goals, corrected)};
}

void print_accuracy(std::ostream& out, const char* label, const identify::AccuracyStats& s) {
  out << "  " << label
      << text(": position mean %.3f mm, RMS %.3f mm, max %.3f mm", s.mean_m * 1e3, s.rms_m * 1e3, s.max_m * 1e3);
  if (s.has_orientation) out << text(";  orientation RMS %.3f mrad", s.rms_rad * 1e3);
  out << "\n";
}

// The identified parameters beside the truth (lengths in mm, angles in deg). An identified
// parameter also carries what the held-fixed ones it absorbs are off by, so it is compared with
// the truth in its own gauge (the true tool poses fitted in the identified parameters:
// ParameterRow::identifiable_truth); the truth's own value is beside it, with what it absorbs.
void print_parameters(std::ostream& out, const report::Run& run) {
  out << "  parameter        nominal      identified  +- 1 sigma  truth, this gauge   truth itself   (mm, deg)\n";
  for (const report::ParameterRow& p : run.parameters) {
    const bool angle = p.quantity == report::Quantity::angle_rad;
    const double k = angle ? 180.0 / std::numbers::pi : 1e3;
    char line[200];
    std::snprintf(line, sizeof line, "  %-10s %12.4f %14.4f %11.4f %18.4f %14.4f", p.name.c_str(), p.nominal * k,
                  p.identified * k, p.stddev.value_or(0.0) * k, p.identifiable_truth.value_or(NAN) * k,
                  p.truth.value_or(NAN) * k);
    out << line << (p.absorbs.empty() ? "" : "   absorbs " + p.absorbs) << '\n';
  }
}

// Kapucu & Baysec's Table 1 (a: theirs from visual data, b: their rig), ours and the simulated
// truth, in their DH terms (cm, deg).
report::Comparison kapucu_table(const model::RobotModel& ours, const model::RobotModel& truth) {
  report::Comparison c;
  c.title = "Kapucu & Baysec, Table 1, beside this run";
  c.columns = {"their identification (1a)", "their rig (1b)", "kincal", "simulated truth"};
  c.note =
      "Their d3 and the joint angles are readings at their first data point, not parameters; the simulated truth "
      "is their rig with hidden errors of about 1 mm and 0.1 deg.";
  const core::ChainModel<double> o = model::to_chain(ours), t = model::to_chain(truth);
  struct Row {
    const char* name;
    int link;
    bool angle;
    double paper_a, paper_b;  // cm or deg
    double core::LinkParameters<double>::*field;
  };
  const Row rows[] = {
      {"a1", 0, false, -0.28, 0.00, &core::LinkParameters<double>::a_m},
      {"d1", 0, false, 120.71, 127.00, &core::LinkParameters<double>::d_m},
      {"alpha1", 0, true, 90, 90, &core::LinkParameters<double>::alpha_rad},
      {"a2", 1, false, 9.78, 10.00, &core::LinkParameters<double>::a_m},
      {"d2", 1, false, -4.69, -5.00, &core::LinkParameters<double>::d_m},
      {"alpha2", 1, true, 90, 90, &core::LinkParameters<double>::alpha_rad},
      {"a3", 2, false, 0.00, 0.00, &core::LinkParameters<double>::a_m},
      {"alpha3", 2, true, 0, 0, &core::LinkParameters<double>::alpha_rad},
  };
  for (const Row& r : rows) {
    report::ComparisonRow row;
    row.name = r.name;
    row.quantity = r.angle ? report::Quantity::angle_rad : report::Quantity::length_m;
    const double si = r.angle ? kDeg : 0.01;
    row.values = {r.paper_a * si, r.paper_b * si, o.links[static_cast<std::size_t>(r.link)].parameters.*r.field,
                  t.links[static_cast<std::size_t>(r.link)].parameters.*r.field};
    c.rows.push_back(row);
  }
  return c;
}

void print_comparison(std::ostream& out, const report::Comparison& c) {
  out << "  " << c.title << " (cm, deg):\n  parameter ";
  for (const std::string& column : c.columns) out << "  " << column;
  out << "\n";
  for (const report::ComparisonRow& r : c.rows) {
    const double k = r.quantity == report::Quantity::angle_rad ? 180.0 / std::numbers::pi : 100.0;
    char line[64];
    std::snprintf(line, sizeof line, "  %-9s", r.name.c_str());
    out << line;
    for (std::size_t i = 0; i < r.values.size(); ++i) {
      std::snprintf(line, sizeof line, "%*.2f", static_cast<int>(c.columns[i].size()) + 2,
                    r.values[i].value_or(NAN) * k);
      out << line;
    }
    out << "\n";
  }
}

struct RigRun {
  DemoRigResult result;
  report::Run section;
};

RigRun run_rig(RigKind kind, const DemoOptions& options, std::ostream& out) {
  const auto start = std::chrono::steady_clock::now();
  const bool platform = kind == RigKind::platform, stereo = kind == RigKind::stereo;
  const std::string name = platform ? "arid" : stereo ? "kapucu" : "board";
  const std::filesystem::path dir(options.output_dir);
  const model::RobotModel file = model::load_model(options.robots_dir + (platform ? "/arid_prrr.yaml"
                                                                         : stereo ? "/stanford_rrp.yaml"
                                                                                  : "/ur5.yaml"));
  RigOptions rig_options;
  rig_options.seed = options.seed;
  rig_options.candump_log = platform ? (dir / (name + ".candump.log")).string() : std::string();
  // The camera rig's home: a bent UR5 (elbow up, wrist turned toward the board), the camera
  // on its flange.
  if (kind == RigKind::camera) rig_options.home = {0.3, -1.3, 1.5, -1.4, 1.2, 0.4};
  const std::unique_ptr<SimulatedRig> rig = make_simulated_rig(kind, file, rig_options);
  out << "\n== " << rig->description() << "\n";

  std::mt19937_64 rng(options.seed * 7919u + (platform ? 1u : stereo ? 2u : 3u));
  SessionPlan plan;
  const int validation = options.quick ? 12 : 30;
  if (!stereo) {
    // Random poses the camera can use: the strip covers a band of the arm's reach (the board a
    // patch seen from near home), so most poses of a planner's pool over the whole joint space
    // would not see it.
    plan.calibration = rig->random_poses(options.quick ? 24 : 40, rng);
  } else {
    // Their home posture; each sweep as wide as the cameras' view allows (at most 40 % of the
    // joint's range).
    const std::vector<double> home = {0.0, 100 * kDeg, 0.9};
    for (double span = 0.4;; span *= 0.9) {
      plan.calibration = single_joint_sweeps(rig->nominal(), home, 10, span);
      if (std::all_of(plan.calibration.begin(), plan.calibration.end(),
                      [&](const std::vector<double>& q) { return rig->observable(q); }))
        break;
      if (span < 0.02) throw model::InputError("demo: the stereo pair does not see the beacon at home");
    }
  }
  plan.validation = rig->random_poses(validation, rng);
  out << "plan: " << plan.calibration.size() << " calibration poses ("
      << (platform ? "random poses in view of the strip, full pose"
          : stereo ? "single-joint sweeps, 10 readings per joint"
                   : "random poses near home with the whole board in view, full pose with its 6x6 covariance")
      << "), " << plan.validation.size() << " validation poses\n";

  SessionOptions session;
  session.journal_path = (dir / (name + ".journal")).string();
  session.identity = {{"demo", name}, {"seed", std::to_string(options.seed)}};
  std::filesystem::remove(session.journal_path);
  const SessionData data = run_session(rig->nominal(), plan, rig->driver(), rig->sensor(), session, out);

  identify::IdentifyOptions identify_options;
  identify_options.method = identify::Method::full;
  std::optional<identify::CpaResult> cpa;
  if (stereo) {
    identify::CpaOptions c;
    cpa = identify::circle_point_analysis(rig->nominal(), data.calibration, c);
    identify_options.start = identify::Start::cpa;
  }
  const Calibration calibration = calibrate(rig->nominal(), data, identify_options);
  const model::RobotModel& identified = calibration.result.model;

  RigRun run;
  DemoRigResult& r = run.result;
  r.name = name;
  r.before = calibration.before;
  r.after = calibration.after;
  r.identified_vs_truth_rms_m = rms_to_truth(identified, rig->truth(), data.validation);
  r.nominal_vs_truth_rms_m = rms_to_truth(rig->nominal(), rig->truth(), data.validation);
  r.noise_rms_m = noise_rms(rig->truth(), data.validation);

  RunDescription description;
  description.title = platform ? "Doty's ARID with its camera-and-ranger platform (simulated)"
                      : stereo ? "Kapucu & Baysec's stereo rig and Stanford-type arm (simulated)"
                               : "A camera on the flange and a printed board: the everyday rig (simulated)";
  description.robot = file.name;
  description.method = stereo ? "circle-point analysis, then full nonlinear least squares from it"
                              : "full nonlinear least squares (Ceres) from the nominal model";
  description.data = platform ? "the platform's poses over CAN (loopback bus, real firmware)"
                     : stereo ? "beacon centroids and stereo triangulation (firmware core)"
                              : "board poses from rendered views (solvePnP and LM through the lens model)";
  description.simulated = true;
  run.section = report_run(description, rig->nominal(), data, calibration, rig->truth(), cpa ? &*cpa : nullptr);

  out << "identified (" << calibration.result.identifiability.identified.size() << " parameters, "
      << calibration.result.identifiability.held_fixed.size() << " held fixed), beside the truth:\n";
  print_parameters(out, run.section);
  if (stereo) {
    const report::Comparison table = kapucu_table(identified, rig->truth());
    print_comparison(out, table);
    run.section.comparisons.push_back(table);
  }
  out << "validation poses (" << data.validation.rows.size() << "):\n";
  print_accuracy(out, "nominal model vs measured   ", r.before);
  print_accuracy(out, "identified model vs measured", r.after);
  out << text(
      "  against the true tool positions: nominal %.3f mm, identified %.3f mm RMS; measurement noise %.3f mm "
      "RMS -> %.2f x the noise floor\n",
      r.nominal_vs_truth_rms_m * 1e3, r.identified_vs_truth_rms_m * 1e3, r.noise_rms_m * 1e3,
      r.identified_vs_truth_rms_m / r.noise_rms_m);

  if (can::PlatformClient* client = rig->platform()) {
    RecordingDriver driver(rig->driver());
    r.correction = verify_online_correction(*client, rig->fd(), calibration, data, driver, rig->sensor(), out);
    r.correction_vs_truth = correction_vs_truth(rig->truth(), calibration, data, driver);
    out << "online correction, as the platform measures it (its noise included):\n";
    print_accuracy(out, "targets without correction  ", r.correction->before);
    print_accuracy(out, "with the platform's correction", r.correction->after);
    out << "online correction against the simulated truth (true tool pose at the corrected targets vs the goals):\n";
    print_accuracy(out, "targets vs truth, uncorrected", r.correction_vs_truth->uncorrected);
    print_accuracy(out, "corrected targets vs truth  ", r.correction_vs_truth->corrected);
    run.section.accuracy.push_back(
        report_accuracy("online correction: corrected targets, as the platform measures them", r.correction->after));
    run.section.accuracy.push_back(report_accuracy("online correction: corrected targets vs the simulated truth",
                                                   r.correction_vs_truth->corrected));
    run.section.accuracy.push_back(report_accuracy("online correction: uncorrected targets vs the simulated truth",
                                                   r.correction_vs_truth->uncorrected));
    run.section.bus = bus_statistics(rig_options.candump_log, "in-process loopback, classic CAN 1 Mbit/s", 1e6);
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out << text("(%.1f s)\n", r.seconds);
  return run;
}

}  // namespace

DemoResult run_demo(const DemoOptions& options, std::ostream& out) {
  std::filesystem::create_directories(options.output_dir);
  out << "kincal demo: the calibration loop on three simulated rigs, seed " << options.seed << "\n";
  report::Report report;
  report.title = "kincal demo";
  report.date = report::utc_date_now();
  DemoResult result;
  for (const RigKind kind : {RigKind::platform, RigKind::stereo, RigKind::camera}) {
    RigRun run = run_rig(kind, options, out);
    result.rigs.push_back(run.result);
    report.runs.push_back(std::move(run.section));
  }
  result.report_path = (std::filesystem::path(options.output_dir) / "report.html").string();
  report::write_html(report, result.report_path);
  out << "\nwrote " << result.report_path << "\n";
  return result;
}

}  // namespace kincal::session

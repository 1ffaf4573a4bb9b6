#include "host/cli/correct_command.hpp"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>

#include <Eigen/Geometry>

#include "host/cli/model_option.hpp"
#include "host/correct/target_table.hpp"
#include "host/correct/urscript.hpp"
#include "host/files/output_file.hpp"
#include "host/identify/plausibility.hpp"
#include "host/model/model_file.hpp"
#include "host/model/number_text.hpp"
#include "host/model/reading_coverage.hpp"

namespace kincal::cli {

namespace {

// Exit status when every input was good but some target was not reached (the CSV is written
// with their outcome; a program is not).
constexpr int kNotReached = 3;

struct CorrectArgs {
  ModelOption model;
  std::string nominal, joints, poses, urscript, frame = "base", out;
  std::vector<double> seed, tcp;
  bool position_only = false;
  double max_change_deg = 5.0, max_change_mm = 5.0;
};

// The point `correct` aims, the same in both models (robot_model.hpp): --tcp, else the TCP the
// calibrated model or --nominal names (with its flange), else each model's tool -- the measured
// point, for a model that names no TCP. Returns how the log names it.
std::string aim_at_tcp(const CorrectArgs& a, model::RobotModel& nominal, model::RobotModel& calibrated) {
  const auto take_flange = [](model::RobotModel& to, const model::RobotModel& from) {
    to.flange_link = from.flange_link;
    to.frame_n_T_flange = from.frame_n_T_flange;
    to.flange_T_tcp = from.flange_T_tcp;
  };
  if (!calibrated.flange_T_tcp && nominal.flange_T_tcp) take_flange(calibrated, nominal);
  if (!nominal.flange_T_tcp && calibrated.flange_T_tcp) take_flange(nominal, calibrated);
  if (!a.tcp.empty()) {
    if (a.tcp.size() != 3 && a.tcp.size() != 6)
      throw model::InputError("--tcp: give x,y,z (m) or x,y,z,roll,pitch,yaw (m, rad), not " +
                              std::to_string(a.tcp.size()) + " numbers");
    model::Transform tcp;
    tcp.translation = model::Vector3(a.tcp[0], a.tcp[1], a.tcp[2]);
    if (a.tcp.size() == 6) tcp.rotation = model::rotation_from_rpy(model::Vector3(a.tcp[3], a.tcp[4], a.tcp[5]));
    nominal.flange_T_tcp = calibrated.flange_T_tcp = tcp;
  }
  if (!calibrated.flange_T_tcp) return "the model's tool (it names no TCP: give --tcp for another point)";
  std::ostringstream out;
  out.precision(4);
  const model::Vector3 p = calibrated.flange_T_tcp->translation * 1e3 + model::Vector3::Zero();
  out << "the TCP (" << p.x() << ", " << p.y() << ", " << p.z() << " mm from the flange, "
      << model::flange_name(calibrated) << "), not the measured point";
  nominal = model::tool_at_tcp(nominal);
  calibrated = model::tool_at_tcp(calibrated);
  return out.str();
}

// Cartesian targets in millimetres read as metres lie kilometres from the arm: when every target
// with a seed reading (its own, or --seed) lies farther than kFarM from where the calibrated
// model puts the aimed point at that seed, the table is refused up front, naming the likely
// cause, where each target would otherwise be "out of reach" by kilometres.
void refuse_targets_in_mm(const std::vector<correct::Target>& targets, const std::vector<double>& seed,
                          const model::RobotModel& calibrated, bool device_frame, const std::string& source) {
  constexpr double kFarM = 100.0;  // the largest arms reach 4 m
  model::RobotModel arm = calibrated;
  if (!device_frame) arm.base_T_frame0 = model::Transform{};
  double nearest = std::numeric_limits<double>::infinity(), farthest = 0.0;
  for (const correct::Target& t : targets) {
    const std::vector<double>& q = t.q.empty() ? seed : t.q;
    if (!t.cartesian || q.empty()) continue;
    const double d = (model::forward_kinematics(arm, q).translation - t.pose.translation).norm();
    nearest = std::min(nearest, d);
    farthest = std::max(farthest, d);
  }
  if (std::isfinite(nearest) && nearest > kFarM)
    throw model::InputError(source + ": every target lies " + model::shortest_number_text(std::round(nearest)) +
                            " to " + model::shortest_number_text(std::round(farthest)) +
                            " m from where the model puts the TCP at its seed readings, where an arm reaches a few "
                            "metres: are the targets in millimetres? (--poses takes metres)");
}

// Joint readings in degrees (or millimetres) where the model takes radians (metres): every target's
// readings, or every seed, far beyond the joints' limits and inside them divided by 57.3 (1000)
// -- plausibility.hpp's check on the data, held against the targets: refused up front, where
// each target would otherwise end at a joint limit or turn a joint by thousands of degrees.
void refuse_readings_in_degrees(const std::vector<correct::Target>& targets, const model::RobotModel& model,
                                const std::string& source) {
  std::vector<std::vector<double>> readings;
  for (const correct::Target& t : targets)
    if (!t.q.empty()) readings.push_back(t.q);
  if (readings.empty()) return;
  std::string found;
  for (const identify::JointFinding& f : identify::joint_readings_outside(model, readings))
    if (f.unit_mistake) found += (found.empty() ? "" : "; ") + f.text;
  if (!found.empty())
    throw model::InputError(source +
                            ": the joint readings of the targets (or their seeds) are not in the model's "
                            "units (rad, m): " +
                            found);
}

// The motions a program leaves as written (urscript.hpp): named, at most 5, with the count.
void warn_left(const correct::UrProgram& program) {
  if (program.left.empty()) return;
  std::cerr << "kincal correct: warning: " << program.left.size() << " of "
            << program.left.size() + program.motions.size()
            << " motions left as written: their targets are computed when the program runs, so no correction "
               "is computed for them (write a target out to have it corrected)\n";
  for (std::size_t k = 0; k < program.left.size() && k < 5; ++k) std::cerr << "  " << program.left[k].why << '\n';
  if (program.left.size() > 5) std::cerr << "  ... and " << program.left.size() - 5 << " more\n";
}

// A program's pose and its qnear (PolyScope's Waypoint_1_p and Waypoint_1_q) are one waypoint: the
// controller's pose of the TCP at those readings. The distance of each such pose from where the
// nominal model puts the TCP at its qnear readings (the program's line, m).
constexpr double kSeedGapM = 0.01;  // farther than a controller's own calibration moves a TCP

std::vector<std::pair<int, double>> seed_gaps(const correct::UrProgram& program, const model::RobotModel& nominal) {
  model::RobotModel arm = nominal;
  arm.base_T_frame0 = model::Transform{};  // the program's poses are in the robot's base frame
  std::vector<std::pair<int, double>> gaps;
  for (const correct::UrMotion& m : program.motions)
    if (m.seed && m.target.cartesian)
      gaps.emplace_back(m.target.line,
                        (model::forward_kinematics(arm, m.target.q).translation - m.target.pose.translation).norm());
  return gaps;
}

double largest_gap(const std::vector<std::pair<int, double>>& gaps) {
  double largest = 0.0;
  for (const auto& [line, gap] : gaps) largest = std::max(largest, gap);
  return largest;
}

// The point a program's targets are aimed at. PolyScope writes the installation's TCP as
// set_tcp(p[...]) and every waypoint's pose is of it. Without --tcp, when the program sets one TCP
// and its waypoints' poses and qnear readings agree (within kSeedGapM) with that TCP on the nominal
// model and not with the point aim_at_tcp would take, the program's TCP is aimed. A program that
// sets a TCP other than the one aimed is named; so is each waypoint far from its qnear (another
// TCP, robot or base than the model's), before the solve, which then usually refuses them by the
// joint-change limit.
std::string aim_program(const CorrectArgs& a, const correct::UrProgram& program, model::RobotModel& nominal,
                        model::RobotModel& calibrated) {
  std::optional<correct::UrTcp> set;  // the one TCP the program sets
  bool one = !program.tcps.empty();
  for (const correct::UrTcp& t : program.tcps) {
    one = one && t.flange_T_tcp &&
          (!set || (t.flange_T_tcp->translation - set->flange_T_tcp->translation).norm() +
                           (t.flange_T_tcp->rotation - set->flange_T_tcp->rotation).norm() <
                       1e-9);
    if (!set && t.flange_T_tcp) set = t;
  }
  const model::RobotModel nominal_as_given = nominal, calibrated_as_given = calibrated;
  std::string aimed = aim_at_tcp(a, nominal, calibrated);
  std::vector<std::pair<int, double>> gaps = seed_gaps(program, nominal);
  const auto mm = [](const model::Vector3& v) {
    std::ostringstream out;
    out.precision(4);
    out << v.x() * 1e3 << ", " << v.y() * 1e3 << ", " << v.z() * 1e3 << " mm";
    return out.str();
  };
  if (set) {
    const model::Transform& t = *set->flange_T_tcp;
    const model::Vector3 rpy = model::rpy_from_rotation(t.rotation);
    CorrectArgs with = a;
    with.tcp = {t.translation.x(), t.translation.y(), t.translation.z(), rpy.x(), rpy.y(), rpy.z()};
    if (one && a.tcp.empty() && !gaps.empty() && largest_gap(gaps) > kSeedGapM) {
      model::RobotModel n = nominal_as_given, c = calibrated_as_given;
      const std::string aimed_there = aim_at_tcp(with, n, c);
      if (const std::vector<std::pair<int, double>> there = seed_gaps(program, n); largest_gap(there) <= kSeedGapM) {
        nominal = n, calibrated = c;
        return "the program's TCP (set_tcp, line " + std::to_string(set->line) +
               ": its waypoints' poses and qnear readings agree with it) -- " + aimed_there;
      }
    }
    const bool differs =
        !calibrated.flange_T_tcp || (calibrated.flange_T_tcp->translation - t.translation).norm() > 1e-3;
    if (differs) {
      std::cerr << program.source << ':' << set->line << ": warning: the program sets its TCP at " << mm(t.translation)
                << " from the flange, not the point correct aims (" << aimed
                << "): if its targets are meant for that TCP, give --tcp";
      for (std::size_t k = 0; k < with.tcp.size(); ++k)
        std::cerr << (k == 0 ? " " : ",") << model::shortest_number_text(with.tcp[k]);
      std::cerr << '\n';
    }
  }
  std::size_t far = 0;
  for (const auto& [line, gap] : gaps) {
    if (gap <= kSeedGapM || ++far > 3) continue;
    std::cerr << program.source << ':' << line << ": warning: the target pose is " << gap * 1e3
              << " mm from where the nominal model puts the TCP at its qnear readings: the program was made for "
                 "another TCP (set_tcp; --tcp), robot or base than the model's (--nominal)\n";
  }
  if (far > 3) std::cerr << program.source << ": warning: " << far << " targets so, the first 3 named\n";
  return aimed;
}

std::string csv(const correct::TargetTable& table, const std::vector<correct::TargetResult>& results, int n) {
  std::ostringstream out;
  for (int j = 1; j <= n; ++j) out << 'q' << j << ',';
  if (table.cartesian)
    out << "command_x,command_y,command_z"
        << (table.orientation ? ",command_qw,command_qx,command_qy,command_qz," : ",");
  out << "outcome,residual_m,residual_rad";
  const bool spread = !results.empty() && results.front().spread;
  if (spread) out << ",position_sd_m,orientation_sd_rad";
  out << '\n';
  const auto number = [&out](double v) { out << model::shortest_number_text(v); };
  for (const correct::TargetResult& r : results) {
    for (double v : r.solution.q) number(v), out << ',';
    if (table.cartesian) {
      for (int k = 0; k < 3; ++k) number(r.command.translation(k)), out << ',';
      if (table.orientation) {
        Eigen::Quaterniond q(r.command.rotation);
        if (q.w() < 0) q.coeffs() *= -1.0;
        for (double v : {q.w(), q.x(), q.y(), q.z()}) number(v), out << ',';
      }
    }
    out << correct::outcome_name(r.solution.outcome) << ',';
    number(r.solution.residual_m), out << ',';
    number(r.solution.residual_rad);
    if (spread) out << ',', number(r.spread->position_m), out << ',', number(r.spread->orientation_rad);
    out << '\n';
  }
  return out.str();
}

int run_correct(const CorrectArgs& a) {
  try {
    const int inputs = (a.joints.empty() ? 0 : 1) + (a.poses.empty() ? 0 : 1) + (a.urscript.empty() ? 0 : 1);
    if (inputs != 1) throw model::InputError("give one of --joints, --poses and --urscript");
    if (!a.urscript.empty() && a.frame != "base")
      throw model::InputError("--urscript: a program's poses are in the robot's base frame (leave out --frame)");
    files::refuse_overwriting({{"-o", a.out, true}}, {{"--model", a.model.path},
                                                      {"--nominal", a.nominal},
                                                      {"--joints", a.joints},
                                                      {"--poses", a.poses},
                                                      {"--urscript", a.urscript}});
    model::RobotModel calibrated = a.model.load();
    model::RobotModel nominal =
        a.nominal.empty() ? correct::nominal_from_record(calibrated) : model::load_model(a.nominal, a.model.ends);
    const int n = calibrated.joint_count();
    if (nominal.joint_count() != n)
      throw model::InputError("--nominal " + a.nominal + " has " + std::to_string(nominal.joint_count()) +
                              " joints, --model " + std::to_string(n));
    if (!a.seed.empty() && static_cast<int>(a.seed.size()) != n)
      throw model::InputError("--seed has " + std::to_string(a.seed.size()) + " readings, the model " +
                              std::to_string(n) + " joints");
    std::vector<correct::Target> targets;
    correct::TargetTable table;
    correct::UrProgram program;
    std::string source;
    if (!a.urscript.empty()) {
      program = correct::read_urscript(a.urscript, n);
      source = a.urscript;
      for (const correct::UrMotion& m : program.motions) targets.push_back(m.target);
      if (targets.empty() && !program.left.empty())
        throw model::InputError(a.urscript +
                                ": no motion's target is known before the program runs, nothing to "
                                "correct: " +
                                program.left.front().why);
      if (targets.empty())
        throw model::InputError(a.urscript + ": no movej, movel, movep, movec, servoj or servoc line to correct");
      warn_left(program);
    } else {
      source = a.joints.empty() ? a.poses : a.joints;
      table = correct::read_target_table(source, n, correct::kMaxTargets);
      if (table.cartesian != a.joints.empty())
        throw model::InputError(source + ": " +
                                (table.cartesian ? "Cartesian targets (x,y,z) given as --joints"
                                                 : "joint targets (no x,y,z) given as --poses"));
      for (const correct::TargetRow& row : table.rows)
        targets.push_back({row.line, table.cartesian, row.q, row.pose, table.orientation});
    }
    correct::JointCorrectionOptions options;
    // The calibration's own tool says what the data measured: a point leaves the orientation free.
    options.orientation = !a.position_only && calibrated.tool == model::ToolKind::frame;
    std::optional<correct::ParameterCovariance> covariance;
    try {
      covariance = correct::record_covariance(calibrated);
    } catch (const model::InputError& e) {
      throw model::InputError(a.model.path + ": " + e.what());
    }
    const std::string aimed =
        a.urscript.empty() ? aim_at_tcp(a, nominal, calibrated) : aim_program(a, program, nominal, calibrated);
    refuse_readings_in_degrees(targets, calibrated, source);
    if (!a.poses.empty()) refuse_targets_in_mm(targets, a.seed, calibrated, a.frame == "device", source);
    correct::JointChangeLimit limit;
    limit.revolute_rad = a.max_change_deg * std::numbers::pi / 180.0;
    limit.prismatic_m = a.max_change_mm * 1e-3;
    correct::TargetCorrector corrector(nominal, calibrated,
                                       a.frame == "device" ? correct::TargetFrame::device : correct::TargetFrame::base,
                                       covariance, options, limit);
    const std::vector<correct::TargetResult> results = corrector.correct(targets, a.seed, source);
    std::ostream& log = a.out.empty() || a.out == "-" ? std::cerr : std::cout;
    int not_reached = 0;
    for (std::size_t i = 0; i < results.size(); ++i) {
      const correct::Solution& s = results[i].solution;
      if (results[i].short_of)
        std::cerr << source << ':' << targets[i].line << ": reached within the prediction's spread: residual "
                  << s.residual_m * 1e3 << " mm, " << s.residual_rad * 1e3 << " mrad where the model predicts to "
                  << results[i].spread->position_m * 1e3 << " mm, " << results[i].spread->orientation_rad * 1e3
                  << " mrad (sd); the solve alone: " << correct::outcome_name(*results[i].short_of) << '\n';
      if (s.outcome == correct::Outcome::reached) continue;
      ++not_reached;
      std::cerr << source << ':' << targets[i].line << ": not reached: " << correct::outcome_name(s.outcome);
      if (s.outcome == correct::Outcome::joint_change_limit) {
        const bool prismatic =
            calibrated.joints[static_cast<std::size_t>(results[i].change_joint)].type == core::JointType::prismatic;
        std::cerr << ": joint " << results[i].change_joint + 1 << " ("
                  << calibrated.joints[static_cast<std::size_t>(results[i].change_joint)].name << ") would change by "
                  << (prismatic ? results[i].change * 1e3 : results[i].change * 180.0 / std::numbers::pi)
                  << (prismatic ? " mm, beyond --max-joint-change-mm " : " deg, beyond --max-joint-change-deg ")
                  << (prismatic ? a.max_change_mm : a.max_change_deg)
                  << "; the target's readings are left as they were";
        if (const auto& w = results[i].within_limit) {
          std::cerr << "; held within the limit, the model misses it by " << w->residual_m * 1e3 << " mm, "
                    << w->residual_rad * 1e3 << " mrad";
          if (w->spread)
            std::cerr << " where it predicts to " << w->spread->position_m * 1e3 << " mm, "
                      << w->spread->orientation_rad * 1e3 << " mrad (sd)";
        }
      }
      std::cerr << " (residual " << s.residual_m * 1e3 << " mm, " << s.residual_rad * 1e3 << " mrad)\n";
    }
    std::vector<std::vector<double>> readings;
    for (const correct::TargetResult& r : results) readings.push_back(r.solution.q);
    for (const model::CoverageFinding& f : model::readings_outside_calibration(calibrated, readings, "targets"))
      std::cerr << "kincal correct: " << (f.still ? "warning: " : "note: ") << f.text << '\n';
    if (!a.urscript.empty()) {
      if (not_reached > 0)
        throw model::InputError(std::to_string(not_reached) + " target(s) not reached: no program written");
      files::write_output(a.out, correct::write_urscript(program, correct::urscript_values(program, results)));
    } else {
      files::write_output(a.out, csv(table, results, n));
    }
    log << "kincal correct: aimed " << aimed << ", "
        << (options.orientation ? "position and orientation" : "position only") << '\n';
    log << "kincal correct: " << correct::summary_line(results) << '\n';
    return not_reached > 0 ? kNotReached : 0;
  } catch (const std::exception& e) {
    std::cerr << "kincal correct: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

void add_correct_command(CLI::App& app, int& status) {
  auto a = std::make_shared<CorrectArgs>();
  auto* cmd = app.add_subcommand(
      "correct", "Rewrite joint or Cartesian targets (CSV) or a URScript program for the calibrated arm");
  add_model_option(*cmd, a->model, "the calibrated model");
  cmd->add_option("--nominal", a->nominal,
                  "the model the robot controller computes with (default: the calibrated model's record undone)");
  auto* joints = cmd->add_option("--joints", a->joints, "joint targets (CSV: q1..qN, rad or m)");
  cmd->add_option("--poses", a->poses,
                  "Cartesian targets (CSV: x,y,z[,qw,qx,qy,qz][,q1..qN seed], m) -> readings by inverse kinematics");
  cmd->add_option(
      "--urscript", a->urscript,
      "a URScript program: movej/movel/movep/movec/servoj/servoc targets rewritten (literals, waypoint "
      "variables, get_inverse_kin, pose_trans; targets computed when it runs left as written and named), every "
      "other byte kept");
  cmd->add_option("--frame", a->frame,
                  "frame of --poses: base (the robot's, default) or device (the measuring device's)")
      ->check(CLI::IsMember({"base", "device"}))
      ->excludes(joints);
  cmd->add_option("--seed", a->seed, "seed reading for Cartesian targets before any other (N numbers, rad or m)")
      ->delimiter(',')
      ->excludes(joints);  // joint targets need no inverse kinematics to seed
  cmd->add_flag("--position-only", a->position_only,
                "joint targets: correct the TCP's position alone, not its orientation (always so when the "
                "calibration measured points: a point tool)");
  cmd->add_option("--tcp", a->tcp,
                  "the controller's TCP from the flange, x,y,z (m) or x,y,z,roll,pitch,yaw (m, rad): the point "
                  "corrected (default: the model's tcp, a URDF's tip link, else the model's tool)")
      ->delimiter(',');
  cmd->add_option("--max-joint-change-deg", a->max_change_deg,
                  "refuse a target whose correction turns a joint by more than this (default 5 deg)")
      ->check(CLI::Range(1e-6, 360.0));
  cmd->add_option("--max-joint-change-mm", a->max_change_mm, "the same for a prismatic joint's travel (default 5 mm)")
      ->check(CLI::Range(1e-6, 1e6));
  cmd->add_option("-o,--out", a->out, "output: the CSV or the program (default or '-': standard output)");
  cmd->footer(
      "Exit status: 0 every target reached; 1 bad input (nothing written); 3 some target not reached or refused "
      "(named on standard error; the CSV is written with its outcome, a program is not). A target the model "
      "misses by at most " +
      model::shortest_number_text(correct::kWithinSpread) +
      " times its own predicted spread there (what its own error reaches 19 times in 20; a stretched arm at the "
      "edge of its reach) counts as reached, named on standard error with its residual.");
  cmd->callback([a, &status] { status = run_correct(*a); });
}

}  // namespace kincal::cli

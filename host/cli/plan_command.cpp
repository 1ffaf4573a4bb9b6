#include "host/cli/plan_command.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "host/cli/model_option.hpp"
#include "host/cli/number_options.hpp"
#include "host/correct/target_table.hpp"
#include "host/files/output_file.hpp"
#include "host/identify/plan.hpp"
#include "host/model/model_file.hpp"

namespace kincal::cli {

namespace {

struct PlanArgs {
  ModelOption model;
  std::string out, candidates, constraints;
  identify::ConstraintOptions constraint_options;
  std::vector<std::string> joint_ranges;  // NAME=LOWER,UPPER
  int count = 30, pool = 1000;
  std::uint64_t seed = 1;
  bool orientation = false;
  std::string criterion = "prediction";
};

// A figure of the summary: "%.<digits>g", or "n/a" for NaN and infinities (a ratio of zeros, a
// comparison that has no random plan), so that no NaN is ever printed.
std::string figure(double value, int digits) {
  if (!std::isfinite(value)) return "n/a";
  char text[64];
  std::snprintf(text, sizeof text, "%.*g", digits, value);
  return text;
}

// The candidates and what each constraint did to them.
void constraint_lines(std::ostream& out, const PlanArgs& a, const model::RobotModel& m, const identify::PlanOptions& o,
                      const identify::PlanResult& r, const std::vector<int>& candidate_lines) {
  out << "# candidates: " << r.considered << (a.candidates.empty() ? " drawn" : " from " + a.candidates) << ", "
      << r.feasible << " meet every constraint\n";
  for (const identify::ConstraintOutcome& c : r.constraints) {
    out << "# constraint " << identify::describe(c.constraint, o.constraints, m) << ": rejected " << c.rejected
        << " of " << r.considered;
    if (c.active && r.criterion == identify::PlanCriterion::d_optimal)
      out << "; active: a candidate it alone rejects would raise O1 " << figure(c.index_gain, 4) << "x";
    else if (c.active)
      out << "; active: a candidate it alone rejects would lower the predicted position rms " << figure(c.index_gain, 4)
          << "x";
    else if (c.constraint == identify::Constraint::joint_ranges && a.candidates.empty())
      out << "; the candidates are drawn within the ranges";
    else
      out << "; not active";
    out << '\n';
  }
  if (candidate_lines.empty()) return;
  out << "# chosen candidates (lines of " << a.candidates << "):";
  for (std::size_t k : r.chosen) out << ' ' << candidate_lines[k];
  out << '\n';
}

// The summary as comment lines, which the dataset reader skips.
std::string summary(const PlanArgs& a, const model::RobotModel& m, const identify::PlanResult& r) {
  const identify::PlanOptions defaults;
  std::ostringstream out;
  out << "# kincal plan: " << a.count << " configurations of " << m.name << " for " << r.identified.size()
      << " identifiable parameters (" << r.held_fixed.size() << " held fixed"
      << (r.gravity ? "; the geometry, each joint's gravity compliance and gravity's direction: the model's masses"
                    : "")
      << ")\n";
  if (r.gravity_needs > 0)
    out << "# the geometry alone: the gravity compliances the model's masses call for need at least " << r.gravity_needs
        << " configurations\n";
  out << "# criterion: "
      << (r.criterion == identify::PlanCriterion::prediction
              ? "prediction (the mean predicted position variance over the candidates)"
              : "d-optimal (O1)");
  if (r.lever_m > 0.0) out << "; rotation rows weighted by the joints' lever arm, " << figure(r.lever_m, 3) << " m";
  out << '\n';
  if (r.random_full_rank == 0) {
    out << "# observability index O1: planned " << figure(r.index, 6) << "; none of " << defaults.random_sets
        << " random plans of " << a.count << " of the " << r.feasible
        << " candidates identifies every parameter (no comparison; a larger --pool gives one)\n"
        << "# predicted position rms over the workspace per unit sigma: planned " << figure(r.prediction_rms, 4)
        << '\n';
    return out.str();
  }
  out << "# observability index O1: planned " << figure(r.index, 6) << ", random plans mean "
      << figure(r.random_index_mean, 6) << " (best of " << r.random_full_rank << ": " << figure(r.random_index_best, 6)
      << "): " << figure(r.index / r.random_index_mean, 3) << "x\n"
      << "# predicted position rms over the workspace per unit sigma: planned " << figure(r.prediction_rms, 4)
      << ", random " << figure(r.random_prediction_rms, 4) << ": "
      << figure(r.random_prediction_rms / r.prediction_rms, 3) << "x smaller\n";
  return out.str();
}

// The constraint options as the constraints file's keys; none given: nothing.
std::optional<identify::ConstraintOptions> constraint_options(const PlanArgs& a) {
  identify::ConstraintOptions o = a.constraint_options;
  if (o.floor.size() == 1) o.floor = {"0", "0", o.floor[0], "0", "0", "1"};  // --floor Z: the plane z = Z, z up
  for (const std::string& text : a.joint_ranges) {
    const std::size_t equals = text.rfind('=');
    if (equals == std::string::npos || equals == 0)
      throw model::InputError("--joint-range '" + text + "': expected NAME=LOWER,UPPER (a joint name or qN)");
    std::vector<std::string> range;
    std::istringstream values(text.substr(equals + 1));
    for (std::string value; std::getline(values, value, ',');) range.push_back(value);
    o.joints.emplace_back(text.substr(0, equals), std::move(range));
  }
  const bool none = o.workspace.empty() && o.floor.empty() && o.joints.empty() && o.sight.empty();
  if (none && o.angles.empty()) return std::nullopt;  // --angles alone: refused by the reader
  return o;
}

int run_plan(const PlanArgs& a) {
  try {
    files::refuse_overwriting(
        {{"-o", a.out, true}},
        {{"--model", a.model.path}, {"--candidates", a.candidates}, {"--constraints", a.constraints}});
    const model::RobotModel m = a.model.load();
    identify::PlanOptions options;
    if (!a.constraints.empty()) options.constraints = identify::read_plan_constraints(a.constraints, m);
    if (const std::optional<identify::ConstraintOptions> given = constraint_options(a)) {
      options.constraints = identify::combine_plan_constraints(options.constraints, a.constraints,
                                                               identify::plan_constraints_from_options(*given, m));
    }
    std::vector<int> candidate_lines;
    if (!a.candidates.empty()) {
      const correct::TargetTable table =
          correct::read_target_table(a.candidates, m.joint_count(), identify::kMaxCandidates);
      if (table.cartesian)
        throw model::InputError(a.candidates + ": the candidates are Cartesian targets; give joint readings q1..q" +
                                std::to_string(m.joint_count()));
      for (const correct::TargetRow& row : table.rows) {
        options.candidates.push_back(row.q);
        options.candidate_names.push_back(a.candidates + ":" + std::to_string(row.line));
        candidate_lines.push_back(row.line);
      }
    }
    options.count = a.count;
    options.pool = a.pool;
    options.seed = a.seed;
    options.orientation = a.orientation;
    options.criterion =
        a.criterion == "d-optimal" ? identify::PlanCriterion::d_optimal : identify::PlanCriterion::prediction;
    options.progress = [](int sweep, std::size_t done, std::size_t total) {
      std::cerr << "kincal plan: exchange sweep " << sweep << ": " << done << " of " << total << " configurations\n";
    };
    const identify::PlanResult r = identify::plan_configurations(m, options);
    std::ostringstream out;
    std::ostringstream constraints;
    constraint_lines(constraints, a, m, options, r, candidate_lines);
    const std::string lines = summary(a, m, r) + constraints.str();
    const bool to_file = !a.out.empty() && a.out != "-";
    out << lines;
    if (to_file) std::cout << lines;
    for (int j = 1; j <= m.joint_count(); ++j) out << 'q' << j << (j < m.joint_count() ? "," : "\n");
    for (const auto& q : r.configurations) {
      for (std::size_t j = 0; j < q.size(); ++j) {
        char buffer[64];
        const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, q[j]);
        out << std::string(buffer, ec == std::errc() ? end : buffer) << (j + 1 < q.size() ? "," : "\n");
      }
    }
    files::write_output(a.out, out.str());
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "kincal plan: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

void add_plan_command(CLI::App& app, int& status) {
  auto a = std::make_shared<PlanArgs>();
  auto* cmd = app.add_subcommand("plan", "Propose calibration configurations that maximize observability");
  add_model_option(*cmd, a->model, "model with joint limits");
  cmd->add_option("-n,--count", a->count, "number of configurations (default 30)")->check(whole_in(1, 100000));
  auto* pool = cmd->add_option("--pool", a->pool,
                               "random candidate configurations to choose from (default 1000; not with --candidates)")
                   ->check(whole_in(1, static_cast<long long>(identify::kMaxCandidates)));
  cmd->add_option("--seed", a->seed, "random seed (default 1)");
  cmd->add_option("--candidates", a->candidates,
                  "choose from these configurations (CSV q1..qN: ones the robot reaches and the device sees) "
                  "instead of a random pool")
      ->excludes(pool);
  cmd->add_option("--constraints", a->constraints,
                  "YAML: workspace box, floor plane, joint ranges, line-of-sight cone (plan_constraints.hpp); "
                  "no planned configuration violates them");
  cmd->add_option("--workspace", a->constraint_options.workspace,
                  "the tool point inside this box of frame 0: MINX,MINY,MINZ,MAXX,MAXY,MAXZ (m)")
      ->delimiter(',');
  cmd->add_option("--floor", a->constraint_options.floor,
                  "the tool point and every frame origin above this plane: Z (the plane z = Z, z up) or "
                  "PX,PY,PZ,NX,NY,NZ (a point and the normal toward the allowed side; m)")
      ->delimiter(',');
  cmd->add_option("--joint-range", a->joint_ranges,
                  "a joint's readings within LOWER..UPPER: NAME=LOWER,UPPER (a joint name or qN; rad or m, "
                  "or deg with --angles deg); repeatable");
  cmd->add_option("--sight", a->constraint_options.sight,
                  "the tool point in the line of sight of a device at APEX: AX,AY,AZ,DX,DY,DZ,HALF_ANGLE (m; the "
                  "cone's axis from the apex; rad, or deg with --angles deg)")
      ->delimiter(',');
  cmd->add_option("--angles", a->constraint_options.angles, "the unit of --joint-range and --sight angles: rad or deg")
      ->check(CLI::IsMember({"rad", "deg"}));
  cmd->add_flag("--orientation", a->orientation, "plan for pose measurements (tool frame) instead of points");
  cmd->add_option("--criterion", a->criterion,
                  "prediction (default: the least mean predicted position variance over the candidates) or "
                  "d-optimal (the largest O1)")
      ->check(CLI::IsMember({"prediction", "d-optimal"}));
  cmd->add_option("-o,--out", a->out, "output CSV q1..qN (default or '-': standard output)");
  cmd->callback([a, &status] { status = run_plan(*a); });
}

}  // namespace kincal::cli

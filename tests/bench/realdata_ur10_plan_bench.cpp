// Issue #23: does a plan chosen by `kincal plan --candidates` identify the real UR10 better than
// random choices of the same size? The shared laser-tracker set read through kincal import's
// reader, the fixed held-out set of 500 rows (tests/host/model/ur10_realdata.hpp, as
// realdata_ur10_bench), the other 995 rows' joint readings as the candidates. 30 rows chosen by
// the plan (pose measurements, as identify uses the set), identified as `kincal identify` does by
// default (model selection, then the chosen candidate), judged by the position RMS over the 500
// held-out rows; each figure below but _index_over_random, _prediction_over_random and
// _plan_seconds also with suffix _geometry: the rows identified with the geometry alone (the
// default options without selection, what the figures measured before issue #41's last round). A
// plan depends on its seed (the exchange's random start: different local optima of nearly the same
// criterion, 0.465 to 0.477 mm held out), so the plan's figures are means over the plans of seeds 1..5 (issue #41: one
// seed's plan measured the draw as much as the planner); the random choices' mean over 50 draws (its standard error
// about 0.003 mm, 0.06 of the share below; 20 draws gave 0.005):
//   realdata_ur10_plan_heldout_rms_mm        held-out position RMS of the planned 30 rows
//   realdata_ur10_plan_heldout_worst_mm      the worst of the five plans
//   realdata_ur10_random30_heldout_rms_mm    mean over 50 random 30-row choices (seeds 1..50)
//   realdata_ur10_random30_heldout_sem_mm    its standard error
//   realdata_ur10_plan_share_of_achievable   (random-30 - plan-30) / (random-30 - all 995
//                                            candidates): how much of what more rows could gain a
//                                            30-row plan gains (issue #41: >= 0.6; it replaces the
//                                            withdrawn plan/random ratio, whose 0.9 was below what
//                                            the data allow)
//   realdata_ur10_random30_better_than_plan  how many of the 50 random choices beat the plans' mean
//   realdata_ur10_plan_index_over_random     O1 of the plan over the random choices' mean (seed 1)
//   realdata_ur10_plan_prediction_over_random  the predicted position rms (the criterion the plan
//                                            minimizes, plan.hpp) over the random choices' (seed 1)
//   realdata_ur10_plan_seconds               one plan's run time (mean of the five)
//   realdata_ur10_plan_dopt_heldout_rms_mm   the same with --criterion d-optimal (seeds 1..5)
//   realdata_ur10_plan_positions_heldout_rms_mm   the plan made for positions only (seeds 1..5)
//   realdata_ur10_plan_for_geometry_heldout_rms_mm   the plan made for the geometry alone, not for
//                                            the gravity compliances the UR10's masses give (seeds 1..5)
//   realdata_ur10_all_candidates_over_random  all 995 candidate rows identified, over the random
//                                            30-row mean: about the least any 30-row choice can
//                                            reach, the arm's unexplained error being the floor
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "host/identify/identify.hpp"
#include "host/identify/model_selection.hpp"
#include "host/identify/plan.hpp"
#include "host/identify/statistics.hpp"
#include "host/model/model_file.hpp"
#include "tests/host/model/ur10_realdata.hpp"

namespace {

using namespace kincal;

void figure(const std::string& name, double value, const char* unit) {
  std::printf("FIGURE %s %.4f %s\n", name.c_str(), value, unit);
}

constexpr int kRows = 30;

// The held-out position RMS of rows identified two ways: as `kincal identify` runs by default (the
// model chosen by selection, model_selection.hpp), and the geometry with the default options alone
// (what these figures measured before issue #41's last round).
struct Judged {
  double defaults_m = 0.0, geometry_m = 0.0;
};

Judged heldout_rms_m(const model::RobotModel& nominal, const model::Dataset& all, const std::vector<int>& rows,
                     const model::Dataset& held_out) {
  const model::Dataset train = realdata::subset(all, rows);
  const identify::Selection s = identify::select_model(nominal, train, {});
  Judged out;
  out.defaults_m =
      identify::accuracy(identify::identify(s.chosen.model, train, s.chosen.options, s.chosen_cross_validation).model,
                         held_out)
          .rms_m;
  out.geometry_m = identify::accuracy(identify::identify(nominal, train, {}).model, held_out).rms_m;
  return out;
}

// The plans of seeds 1..kPlanSeeds among the training candidates, identified and judged.
struct PlanOutcome {
  Judged mean, worst;
  double seconds = 0.0;
  identify::PlanResult first;  // seed 1's plan
};

constexpr int kPlanSeeds = 5;

PlanOutcome planned(const model::RobotModel& nominal, const model::Dataset& all, const std::vector<int>& train,
                    const model::Dataset& held_out, bool orientation, identify::PlanCriterion criterion,
                    bool gravity = true) {
  PlanOutcome out;
  for (int seed = 1; seed <= kPlanSeeds; ++seed) {
    identify::PlanOptions o;
    o.count = kRows;
    o.orientation = orientation;
    o.criterion = criterion;
    o.gravity = gravity;
    o.seed = static_cast<std::uint64_t>(seed);
    for (int r : train) o.candidates.push_back(all.rows[static_cast<std::size_t>(r)].q);
    const auto start = std::chrono::steady_clock::now();
    identify::PlanResult plan = identify::plan_configurations(nominal, o);
    out.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / kPlanSeeds;
    std::vector<int> rows;
    for (std::size_t k : plan.chosen) rows.push_back(train[k]);
    const Judged rms = heldout_rms_m(nominal, all, rows, held_out);
    out.mean.defaults_m += rms.defaults_m / kPlanSeeds;
    out.mean.geometry_m += rms.geometry_m / kPlanSeeds;
    out.worst.defaults_m = std::max(out.worst.defaults_m, rms.defaults_m);
    out.worst.geometry_m = std::max(out.worst.geometry_m, rms.geometry_m);
    if (seed == 1) out.first = std::move(plan);
  }
  return out;
}

}  // namespace

int main() {
  const model::RobotModel nominal = model::load_model(KINCAL_ROBOTS_DIR "/ur10.yaml");
  const model::Dataset all = realdata::import_ur10(KINCAL_REALDATA_DIR).data;
  const realdata::Split split = realdata::split_rows(static_cast<int>(all.rows.size()), 500);
  const model::Dataset held_out = realdata::subset(all, split.held_out);

  const PlanOutcome plan =
      planned(nominal, all, split.train_order, held_out, true, identify::PlanCriterion::prediction);
  const PlanOutcome dopt = planned(nominal, all, split.train_order, held_out, true, identify::PlanCriterion::d_optimal);
  const PlanOutcome positions =
      planned(nominal, all, split.train_order, held_out, false, identify::PlanCriterion::prediction);
  const PlanOutcome geometry_plan =
      planned(nominal, all, split.train_order, held_out, true, identify::PlanCriterion::prediction, false);

  constexpr int kDraws = 50;
  std::vector<Judged> random_rms;
  for (std::uint64_t seed = 1; seed <= kDraws; ++seed) {
    std::vector<int> rows = split.train_order;
    std::mt19937_64 rng(seed);
    std::shuffle(rows.begin(), rows.end(), rng);
    rows.resize(kRows);
    random_rms.push_back(heldout_rms_m(nominal, all, rows, held_out));
  }
  const Judged all_rms = heldout_rms_m(nominal, all, split.train_order, held_out);
  // The figures of one way of identifying (suffix "" for the defaults, "_geometry" for the other).
  const auto figures = [&](double Judged::*way, const std::string& suffix) {
    double random_mean = 0.0, random_var = 0.0;
    for (const Judged& r : random_rms) random_mean += r.*way / kDraws;
    for (const Judged& r : random_rms) random_var += (r.*way - random_mean) * (r.*way - random_mean) / (kDraws - 1);
    const double planned_m = plan.mean.*way, all_m = all_rms.*way;
    const auto better =
        std::count_if(random_rms.begin(), random_rms.end(), [&](const Judged& r) { return r.*way < planned_m; });
    figure("realdata_ur10_plan_heldout_rms_mm" + suffix, planned_m * 1e3, "mm");
    figure("realdata_ur10_plan_heldout_worst_mm" + suffix, plan.worst.*way * 1e3, "mm");
    figure("realdata_ur10_random30_heldout_rms_mm" + suffix, random_mean * 1e3, "mm");
    figure("realdata_ur10_random30_heldout_sem_mm" + suffix, std::sqrt(random_var / kDraws) * 1e3, "mm");
    figure("realdata_ur10_plan_share_of_achievable" + suffix, (random_mean - planned_m) / (random_mean - all_m),
           "ratio");
    figure("realdata_ur10_random30_better_than_plan" + suffix, static_cast<double>(better), "of_50");
    figure("realdata_ur10_plan_dopt_heldout_rms_mm" + suffix, dopt.mean.*way * 1e3, "mm");
    figure("realdata_ur10_plan_positions_heldout_rms_mm" + suffix, positions.mean.*way * 1e3, "mm");
    figure("realdata_ur10_plan_for_geometry_heldout_rms_mm" + suffix, geometry_plan.mean.*way * 1e3, "mm");
    figure("realdata_ur10_all_candidates_heldout_rms_mm" + suffix, all_m * 1e3, "mm");
    figure("realdata_ur10_all_candidates_over_random" + suffix, all_m / random_mean, "ratio");
  };
  figures(&Judged::defaults_m, "");
  figures(&Judged::geometry_m, "_geometry");
  figure("realdata_ur10_plan_index_over_random", plan.first.index / plan.first.random_index_mean, "ratio");
  figure("realdata_ur10_plan_prediction_over_random", plan.first.prediction_rms / plan.first.random_prediction_rms,
         "ratio");
  figure("realdata_ur10_plan_seconds", plan.seconds, "s");
  return 0;
}

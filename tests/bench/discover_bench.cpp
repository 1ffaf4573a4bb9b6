// Issue #14, discovery without a model (host/identify/discover.hpp).
//
// Kapucu & Baysec's rig at their noise (tests/bench/kapucu_rig.hpp: 0.0481 px, the level at which
// their own method reproduces their Table 1; 10 readings per joint), 200 seeds:
//   discover_topology_success  fraction of seeds whose joint types come out R, R, P;
//   discover_over_cpa_rms      held-out beacon prediction RMS (100 random configurations within
//                              the limits per seed, pooled) of the discovered model over that of
//                              cpa given the true nominal model, on the same data.
// A PUMA 560 (host/model/robots/puma560.yaml, every parameter perturbed as sim::perturbed does)
// swept joint by joint, 10 readings over half of each joint's range around a home with the wrist
// bent 57 deg (with it straight the beacon circles the forearm's axis at 11 mm, and that axis's
// direction, 1-5 mrad off, moves a3 by up to 2.7 mm over the 0.43 m to the elbow), laser-tracker
// noise 0.02 mm per axis (not recorded: estimated), 20 seeds:
//   discover_6r_worst_length_error_mm  worst |a_i - a_i true| and |d_i - d_i true| over the joints
//                              and the seeds, both models written on their axes with the truth's
//                              conventions (so the DH lengths are comparable).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "host/identify/cpa.hpp"
#include "host/identify/discover.hpp"
#include "host/model/axes.hpp"
#include "host/model/model_file.hpp"
#include "tests/bench/kapucu_rig.hpp"
#include "tests/host/identify/simulation.hpp"

namespace {

using namespace kincal;
using model::RobotModel;

double worst_length_error(const RobotModel& m, const RobotModel& truth, const std::vector<double>& home) {
  const RobotModel a =
      model::chain_from_axes(truth, model::joint_axes(m, home), home, model::forward_kinematics(m, home));
  const RobotModel b =
      model::chain_from_axes(truth, model::joint_axes(truth, home), home, model::forward_kinematics(truth, home));
  double worst = 0.0;
  for (std::size_t i = 0; i < a.joints.size(); ++i) {
    const bool rev = a.joints[i].type == core::JointType::revolute;
    worst = std::max(worst, std::abs(a.joints[i].parameters.a_m - b.joints[i].parameters.a_m));
    worst = std::max(worst, std::abs(a.joints[i].parameters.d_m + (rev ? 0 : a.joints[i].offset) -
                                     b.joints[i].parameters.d_m - (rev ? 0 : b.joints[i].offset)));
  }
  return worst;
}

}  // namespace

int main() {
  const double sigma_px = 0.0481;
  const RobotModel rrp = model::load_model(std::string(KINCAL_ROBOTS_DIR) + "/stanford_rrp.yaml");
  const auto qs = kapucu::sweep_configurations();
  const int seeds = 200;
  int found = 0;
  double discovered2 = 0.0, cpa2 = 0.0;
  for (int s = 0; s < seeds; ++s) {
    std::mt19937_64 rng(30'000u + static_cast<unsigned>(s));
    const model::Dataset d = kapucu::measure(rrp, qs, sigma_px, rng);
    const identify::DiscoverResult r = identify::discover(d, {});
    bool ok = r.fits.size() == 3;
    for (std::size_t j = 0; ok && j < 3; ++j) ok = r.model.joints[j].type == rrp.joints[j].type;
    found += ok ? 1 : 0;
    const RobotModel cpa = identify::circle_point_analysis(rrp, d, {}).model;
    for (const auto& q : sim::random_configurations(rrp, 100, rng)) {
      const model::Vector3 t = model::forward_kinematics(rrp, q).translation;
      discovered2 += (model::forward_kinematics(r.model, q).translation - t).squaredNorm();
      cpa2 += (model::forward_kinematics(cpa, q).translation - t).squaredNorm();
    }
  }
  const double points = 100.0 * seeds;
  std::printf(
      "Kapucu & Baysec's rig, %.4f px, %d seeds: held-out rms discovered %.2f mm, cpa with the true nominal "
      "%.2f mm\n",
      sigma_px, seeds, std::sqrt(discovered2 / points) * 1e3, std::sqrt(cpa2 / points) * 1e3);
  std::printf("FIGURE discover_topology_success %.3f fraction\n", found / static_cast<double>(seeds));
  std::printf("FIGURE discover_over_cpa_rms %.3f ratio\n", std::sqrt(discovered2 / cpa2));

  const RobotModel puma = model::load_model(std::string(KINCAL_ROBOTS_DIR) + "/puma560.yaml");
  std::vector<double> home;
  for (const auto& j : puma.joints) home.push_back(0.5 * (j.lower + j.upper) + 0.1);
  home[4] = 1.0;  // the wrist bent, so the beacon circles the forearm's axis well off it
  std::vector<std::vector<double>> readings;
  for (std::size_t j = 0; j < puma.joints.size(); ++j) {
    const double span = 0.5 * (puma.joints[j].upper - puma.joints[j].lower);
    std::vector<double> r;
    for (int k = 0; k < 10; ++k) r.push_back(home[j] - 0.5 * span + span * k / 9.0);
    readings.push_back(r);
  }
  double worst = 0.0;
  std::vector<double> per_seed;
  for (int s = 0; s < 20; ++s) {
    std::mt19937_64 rng(40'000u + static_cast<unsigned>(s));
    const RobotModel truth = sim::perturbed(puma, rng);
    const model::Dataset d =
        simulation::measure(truth, simulation::single_joint_sweeps(home, readings), rng, 2e-5, false, 0.0, false);
    const identify::DiscoverResult r = identify::discover(d, {});
    per_seed.push_back(worst_length_error(r.model, truth, home));
    worst = std::max(worst, per_seed.back());
  }
  std::sort(per_seed.begin(), per_seed.end());
  std::printf("PUMA 560, 0.02 mm tracker noise, 20 seeds: median worst a/d error %.3f mm\n", per_seed[10] * 1e3);
  std::printf("FIGURE discover_6r_worst_length_error_mm %.3f mm\n", worst * 1e3);
  return 0;
}

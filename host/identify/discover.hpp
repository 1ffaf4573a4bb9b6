// Discovery of an unknown arm (Kapucu & Baysec's manipulator-independent program): from
// single-joint sweeps alone, with no model, each joint's type (the calibrated tests of cpa.hpp),
// its axis as a line in space with standard deviations, the range of mobility observed and, for a
// revolute joint, the beacon's radius; then the link table.
//
// The joint count is the data's. Sweeps are fitted as in cpa.hpp, with each joint's type taken
// from the test's verdict. The model is written by model::chain_from_axes (axes.hpp) on a template
// of the discovered types: standard DH, or Doty/Hayati where consecutive axes are within
// parallel_tolerance_rad of parallel; joint offsets carry each joint's zero. Conventions, since
// nothing else fixes them (and the printout says so): frame 0 is the device's frame moved to the
// foot of the perpendicular from the device origin onto axis 1, its z along axis 1 and its x the
// device's x made normal to it; the last link's d, a and alpha are 0 and the tool point (frame,
// when the data has orientations) takes up the rest; joint limits are the readings observed.
//
// Standard deviations of the link parameters come from `samples` draws of the axes from their
// fitted covariances, each redone through the chain (seeded: reproducible).
//
// Cost: a few Ceres fits per joint plus `samples` chain constructions (milliseconds).
// Errors: model::InputError naming the joint without a single-joint sweep, or data with no joint
// columns.
#pragma once

#include <string>
#include <vector>

#include "host/identify/cpa.hpp"

namespace kincal::identify {

struct DiscoverOptions {
  CpaOptions cpa;
  int samples = 200;
  std::string name = "discovered";
};

// A link parameter's value and its 1-sigma spread (SI units).
struct LinkSpread {
  double theta_rad = 0.0, d_m = 0.0, a_m = 0.0, alpha_rad = 0.0, beta_rad = 0.0;
};

struct DiscoverResult {
  RobotModel model;
  std::vector<SweepFit> fits;      // one per joint, in the device frame
  std::vector<LinkSpread> stddev;  // one per joint: theta (with the offset), d, a, alpha, beta
  std::vector<std::string> notes;  // conventions, rejections, inconclusive types
};

// Throws InputError as analyse_sweeps (cpa.hpp).
DiscoverResult discover(const model::Dataset& data, const DiscoverOptions& options);

// What was found and how sure: per joint the type with its p-values, the axis, the range and the
// radius; the link table with standard deviations; the conventions and the notes.
std::string format_discovery(const DiscoverResult& result);

}  // namespace kincal::identify

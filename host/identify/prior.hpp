// Priors of identification (issue #23): every parameter's deviation from its nominal value is
// N(0, sigma^2) a priori -- the manufacturing tolerance -- and identification is the maximum a
// posteriori estimate: the residual delta_k / sigma_k of each parameter joins the whitened
// measurement residuals, in the solve and in the information matrix J^T J + diag(1 / sigma^2)
// whose inverse is the reported covariance. A parameter the data barely see stays near its
// nominal with about its prior's sigma instead of running off; one the data see well is hardly
// touched (its data information dwarfs 1 / sigma^2).
//
// Defaults (PriorOptions): tolerances of the kind a maker states, not fitted to data; checked on
// the shared UR10 laser-tracker set (realdata_ur10_bench) to leave its held-out RMS as it was
// (0.4428 mm with them, 0.4429 without) while the DH table's poorly seen a5, d5 stay near nominal:
//   link lengths d, a        1 mm     a machined arm's tolerance; the UR10's identified link
//                                     length changes are a few tenths of a mm to 1-2 mm
//   link angles theta, alpha, beta   0.5 deg   zero offsets and axis tilts of an assembled arm
//   base x, y, z / rotations 100 mm / 10 deg   the registration to the measuring device: known
//                                     only roughly before the fit (the start is the rigid
//                                     registration when the model's base is a placeholder)
//   tool x, y, z / rotations 10 mm / 5 deg   a probe or tool mounted by hand
//   scale<i>                 0.01     a gear ratio's error (1 %)
//   coupling<i>_<i-1>        0.01     a transmission's share of the upstream joint's motion
//                                     (model_selection.hpp's geometry+couplings), 1 % like a
//                                     ratio: the zoo's elbow couplings are 0.2-0.5 %
//   compliance<i>            0.1 deg  a joint's deflection under gravity at its largest load over
//                                     the data (0.1 mm for a prismatic joint), over that load:
//                                     sigma = 0.1 deg / max |G_i| in rad/(N m) (GravityLoads, at
//                                     the start's masses; none where the data do not load the
//                                     joint or no loads are given: identify gives them where the
//                                     masses are identified too, sag.hpp's
//                                     compliance_prior_loads). A stiffness has no tolerance
//                                     a maker states, but a deflection has a size: an arm's
//                                     joints sag by hundredths to tenths of a degree. Without it
//                                     geometry+sag's compliances ran free on 20 rows (the zoo's
//                                     SIA10F by motion capture: a wrist's 8329 +- 8042 urad/Nm in
//                                     the gauge's units, 1.67 x the oracle held out)
//   mass<i>                  1 kg     geometry+sag's masses (model_selection.hpp, sag.hpp):
//                                     in the gauge's units, where the start is 1 kg per link,
//                                     so a width of the start's size; the data rescale it (below)
//   com_x<i> .. com_z<i>     0.1 m    their centres, from the start at the link frame's origin
//                                     (sag.hpp): without a prior the masses' 4 parameters per
//                                     link fitted 20 rows' noise (0.83 mm held out on the zoo's
//                                     IRB 6640, 12 times the oracle); with these widths scaled by
//                                     the evidence, 0.085 mm, and a model with the data to see
//                                     the masses lets them go (the scale's bound is 100 x)
//   com_x<i> .. com_z<i>     1 mm     a centre whose mass is given, not identified (geometry+
//     (mass given)                    gravity's, robot_model.hpp's identify_centre): a
//                                     calibrated joint zero turns a link's mass where the truth may
//                                     not have (a tenth of a degree over half a metre is a
//                                     millimetre); the data widen it where the file's centre is
//                                     off (a CAD estimate: sag_test's UR10 with centres 50 mm off)
//   gravity_rx, gravity_ry   1 deg    an arm's base against level (floors, a first joint's tilt)
// `sigma` overrides a parameter by name (--prior on the command line, `priors:` in the model
// file); `strength` multiplies every 1 / sigma (0: no prior at all, the plain least squares of
// before).
// These are the classes' default widths: identify scales each class to what its data call for
// (prior_scale.hpp: the evidence, type-II maximum likelihood), unless estimate_scales is off; a
// sigma named in `sigma` is kept as given.
//
// The deviations are counted from the nominal after reparameterization and base registration
// (identify.hpp), whatever the start: with --start cpa the solve starts from cpa's fit and the
// prior stays centred on the nominal (identify.cpp's nominal_in_start).
#pragma once

#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "host/identify/problem.hpp"

namespace kincal::identify {

struct PriorOptions {
  double strength = 1.0;  // multiplies each 1 / sigma; 0 turns the priors off
  double length_m = 1e-3;
  double angle_rad = 0.5 * std::numbers::pi / 180.0;
  double base_length_m = 0.1;
  double base_angle_rad = 10.0 * std::numbers::pi / 180.0;
  double tool_length_m = 0.01;
  double tool_angle_rad = 5.0 * std::numbers::pi / 180.0;
  double scale = 0.01;
  double coupling = 0.01;
  double deflection_rad = 0.1 * std::numbers::pi / 180.0;  // a compliance's width: its joint's deflection
  double deflection_m = 1e-4;                              // ... a prismatic joint's
  double gravity_direction_rad = 1.0 * std::numbers::pi / 180.0;
  double mass_kg = 1.0;          // an identified link mass (geometry+sag's gauge units)
  double centre_m = 0.1;         // an identified centre of mass, per axis
  double given_centre_m = 1e-3;  // ... of a given mass (given_centres)
  // The data choose each class's width (prior_scale.hpp), within [min_scale, max_scale] times
  // the sigmas above; off: the widths above as they are.
  bool estimate_scales = true;
  double min_scale = 0.1;
  double max_scale = 100.0;
  double min_ratio_scale = 1e-4;  // a joint ratio's own class (prior_scale.hpp): 1 ppm of the 1 %
  // Per-parameter sigmas (SI: m, rad, 1, rad/(N m)), by parameter name (theta5, a2, base_x,
  // tool_rz, scale3, ...); later entries win. Infinity: no prior on that parameter.
  std::vector<std::pair<std::string, double>> sigma;
};

// Each joint's largest gravity load over the data at the start's masses (sag.hpp's
// largest_gravity_loads: N m, a prismatic joint's N) and its kind: what turns a compliance's
// default width, a deflection, into rad/(N m) or m/N. Empty: no compliance has a default prior.
struct GravityLoads {
  std::vector<double> largest;
  std::vector<bool> prismatic;
};

// Per link, whether its centre of mass is identified with its mass given by the model
// (Joint::identify_centre: geometry+gravity's); such a centre's default width is given_centre_m,
// its class prior_scale.hpp's given centres. Per link because identifiability may hold a mass
// fixed whose centres it identifies.
std::vector<bool> given_centres(const RobotModel& model);
bool is_given_centre(core::ParameterId id, const std::vector<bool>& given_centres);

// The prior sigma of each parameter (infinity: none), before `strength`. Throws
// model::InputError for an unknown name in options.sigma (naming it and `where`) or a sigma that
// is not positive.
Eigen::VectorXd prior_sigmas(const PriorOptions& options, const ParameterIds& ids, int joint_count,
                             const std::string& where, const GravityLoads& loads = {},
                             const std::vector<bool>& given_centres = {});

// The whitened prior weights strength / sigma (0 where there is no prior).
Eigen::VectorXd prior_weights(const PriorOptions& options, const Eigen::VectorXd& sigmas);

// Parses one --prior entry NAME=VALUE with a unit: mm, m, deg, rad, or none for a ratio (scale)
// or compliance (SI), e.g. "a5=0.5mm", "theta5=0.2deg", "base_x=inf". Throws model::InputError
// naming the entry.
std::pair<std::string, double> parse_prior_entry(const std::string& entry);

}  // namespace kincal::identify

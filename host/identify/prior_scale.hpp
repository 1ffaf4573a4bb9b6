// Prior scales chosen by the data (issue #41): a stage of identify's noise-model loop
// (identify.hpp) that sets the width of each class of priors (prior.hpp) by type-II maximum
// likelihood, so that a precise industrial arm and a service arm with millimetre errors each get
// the regularization their data call for. The defaults of prior.hpp were chosen on the UR10 (a
// link length's tolerance 1 mm, an angle's 0.5 deg); on a service arm whose real deviations are
// millimetres they pulled the fit toward the nominal and cost 22 % held out against no prior.
//
// Model: each identified parameter k of class c has the prior delta_k - centre_k ~ N(0, (lambda_c
// b_k)^2), b_k its default sigma (prior.hpp, over `strength`) and lambda_c the class's scale,
// one number for the class:
//   link lengths     d, a of every link
//   link angles      theta, alpha, beta of every link
//   registration     base_* (the device-to-robot registration)
//   measured point   tool_* (the measured point or the tool, known to a few millimetres at best)
//   joint compliance compliance<i>: each a class of its own, as a joint ratio (its width a
//                    deflection at the joint's largest load: prior.hpp); the stiffness of one
//                    joint's gear says nothing of another's, and one class for all let two wrists
//                    at their bound of 0 pull the UR10's loaded shoulder to a tenth of its width
//                    (geometry+gravity, when its compliances had this prior too)
//   joint ratio      scale<i>, coupling<i>_<i-1>: each a class of its own (automatic relevance
//                    determination): a gear's ratio or a transmission's coupling is wrong on one
//                    joint, not across a population of them, and one class for all let the data's
//                    one scaled joint widen every joint's prior (the zoo's scaled cases: five
//                    scales fitted at their noise, 1.2x the oracle's held-out error, which frees
//                    only the true one)
//   link masses      mass<i> (geometry+sag's, in its gauge: sag.hpp)
//   mass centres     com_x<i> .. com_z<i>: each a class of its own (a length has no ratio to a
//                    mass, and one link's centre says nothing of another's: one width for all, on
//                    the zoo's service cases, was set by the links the data see least -- a 7-joint
//                    arm's 40 tracker rows, 1.42x the oracle's held-out error; each its own, 1.21x)
//   given centres    com_x<i> .. com_z<i> of a mass the model gives (geometry+gravity's,
//                    prior.hpp's given_centres): one class -- the model's centres stand together,
//                    and where they moved it is mostly the calibrated joint zeros' one small turn
//                    of each link; each its own width from 10 mm fitted the noise of the zoo's KR 16
//                    with 300 tracker points (1.25x the oracle's held-out error; one class 1.13x,
//                    each held at 1 mm 0.99x, but a centre 50 mm off its file's then stays there)
// A parameter whose prior the user named (--prior, a model file's `priors:`) keeps it as given
// and is in no class: the user's word wins for what it names. The gravity direction (gravity_rx,
// gravity_ry) is in no class either and keeps its default, an arm's base against level: a tilt
// of gravity and a mass centre off its link's line load the joints alike, so the evidence trades
// the two, and with the centres' own widths it ran the direction's to its lower bound on the
// zoo's 20 tracker rows of a 7-joint service arm (1.33x the oracle's; its default kept, 1.20x).
//
// Estimate: the lambda_c that maximize the evidence (the marginal likelihood of the data, the
// parameters integrated out) in the linearized model at the current solution -- MacKay's fixed
// point (D. J. C. MacKay, "Bayesian interpolation", Neural Computation 4(3), 1992, eq. 4.9 per
// class): with A = J^T J + diag(1 / (lambda b)^2) the posterior information of the whitened data
// Jacobian J and Sigma = A^-1,
//   gamma_c    = sum_{k in c} (1 - Sigma_kk / (lambda_c b_k)^2)   (the class's well-determined
//                                                                  parameters, 0..n_c)
//   lambda_c^2 = sum_{k in c} ((delta_k - centre_k) / b_k)^2 / gamma_c
// iterated (delta the linear MAP step at each lambda) until every lambda_c moves by less than
// 1e-4 relative. A class of one (a joint ratio, a compliance, a mass centre) takes its maximum
// in closed form instead (M. E. Tipping and A. C. Faul, "Fast marginal likelihood maximisation
// for sparse Bayesian models", AISTATS 2003, the others' priors held): with
// s = 1 / Sigma_kk - 1 / (lambda b)^2 the data's information on the parameter with the others
// integrated out, and m - centre = (delta - centre) (s + 1 / (lambda b)^2) / s its estimate from
// the data alone, the evidence's width is (lambda b)^2 = (m - centre)^2 - 1 / s, and none (the
// lower bound) when the estimate is within its own standard error of the centre (the fixed point
// above gets there too, but slowly: each step shrinks the width by the ratio of the two, near 1
// at the edge). A joint ratio asks for kRatioStandardErrors of them instead: (lambda b)^2 =
// (m - centre)^2 - kRatioStandardErrors^2 / s, none within that many standard errors of nominal.
// identify alternates the scales with the REML of the model-error components s_p, s_o: solve,
// REML of the noise at the solution, the scales at the solution and that noise, solve again,
// until both settle (coordinate ascent on one marginal likelihood; the noise's REML treats the
// parameters as free, as before).
//
// Guards (a class's evidence is a chi-square with about gamma_c degrees of freedom: a handful
// of parameters give a noisy estimate):
//   barely seen   a class whose gamma_c at the default scale is below kMinSeenParameters (less
//                 than half a parameter's worth of information from the data) keeps its default:
//                 the evidence says nothing about it, and the fixed point would run to a bound
//   bounds        lambda_c within [PriorOptions::min_scale, max_scale], by default [0.1, 100]:
//                 below a tenth the default (0.1 mm, 0.05 deg: less than the UR10's own
//                 identified link changes) the prior would hold a class at its nominal on the
//                 word of a few noisy parameters; at a hundred times (100 mm, 50 deg) it no longer
//                 constrains anything an arm could have, i.e. least squares; a joint ratio's
//                 lower bound is min_ratio_scale, by default 1e-4 (1 ppm: a joint the data do
//                 not call scaled is held at its nominal ratio)
// Off with PriorOptions::estimate_scales = false (the fixed-width candidates of model selection)
// or strength 0 (no prior).
//
// Cost: per noise pass, one Jacobian of the data (N x P) and a P x P factorization per inner
// iteration (tens), against the pass's Ceres solve.
#pragma once

#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "host/identify/prior.hpp"
#include "host/identify/problem.hpp"
#include "host/model/dataset.hpp"

namespace kincal::identify {

enum class PriorClass {
  link_length,
  link_angle,
  registration,
  measured_point,
  joint_compliance,
  joint_ratio,
  link_mass,
  mass_centre,
  given_centre
};

// A joint ratio is freed from its nominal when its estimate lies this many standard errors from it
// (see above; the evidence's own rule is 1). A gear's ratio or a coupling is wrong on one joint of
// an arm, not on most: at 1 standard error a third of the joints the data do not call scaled or
// coupled kept a ratio fitted to their noise. 2, the level model selection's row-by-row test asks
// too: the zoo's scaled cases on draws 0-3 (32; every instrument, 20 to 300 rows) went from a
// worst of 1.22 x the oracle's held-out error to 1.11 (27 better, one worse by 0.02), the coupled
// ones from 1.11 to 1.06 (15 better, 3 worse by up to 0.03); realdata_ur10_bench the same.
inline constexpr double kRatioStandardErrors = 2.0;

// Less than this many parameters' worth of a class determined by the data (gamma_c at the default
// scale): the class keeps its default (see above). Half a parameter: one parameter the data
// determine alone counts (gamma just below 1), one they see as much as its prior does not.
inline constexpr double kMinSeenParameters = 0.5;

// "link lengths", "link angles", "registration", "measured point", "joint compliance", "joint
// ratio", "link masses", "mass centres".
const char* prior_class_name(PriorClass c);

// How a class's scale was chosen.
enum class ScaleReason { evidence, lower_bound, upper_bound, barely_seen };

struct ClassScale {
  PriorClass kind = PriorClass::link_length;
  std::string parameter;         // a class of one's parameter (scale3, compliance2, com_x4); empty for the others
  bool prismatic = false;        // a compliance's joint is prismatic: its width a length
  int parameters = 0;            // identified parameters of the class with a default prior
  double scale = 1.0;            // lambda_c: multiplies the class's default sigmas
  double determined = 0.0;       // gamma_c at the chosen scale
  double seen_at_default = 0.0;  // gamma_c at the default scale
  ScaleReason reason = ScaleReason::evidence;
};

struct PriorScales {
  bool estimated = false;           // the stage ran (estimate_scales, a prior, a class present)
  std::vector<int> class_of;        // of each identified parameter: its index in classes, or -1 for none
  std::vector<ClassScale> classes;  // those with parameters, in PriorClass order (joint ratios by parameter)
  PriorOptions options;             // the default widths and bounds it scales (for the report)
};

// The classes of the identified parameters `ids` with every scale 1 (`loads` and
// `given_centres` as prior_sigmas takes them); estimated = false when the stage is off (see
// above) or no parameter has a class.
PriorScales initial_prior_scales(const PriorOptions& options, const ParameterIds& ids, int joint_count,
                                 const GravityLoads& loads = {}, const std::vector<bool>& given_centres = {});

// The sigmas (SI, infinity: none) with each class's scale applied to `sigmas` (prior_sigmas').
Eigen::VectorXd scaled_sigmas(const Eigen::VectorXd& sigmas, const PriorScales& scales);

// One evidence update at a linearization: `information` = J^T J and `gradient` = J^T r of the
// whitened data rows at `delta` (without the prior rows), the priors' `sigmas` (prior_sigmas',
// unscaled) and `centre`. Returns `current` with new scales, gammas and reasons.
PriorScales update_prior_scales(const Eigen::MatrixXd& information, const Eigen::VectorXd& gradient,
                                const Eigen::VectorXd& delta, const Eigen::VectorXd& centre,
                                const Eigen::VectorXd& sigmas, const PriorOptions& options, const PriorScales& current);

// The same at the current point `delta` of `p` over the data rows `rows`, whitened by `weights`
// (identify's noise model at its current components).
PriorScales update_prior_scales(const Parameterization& p, std::span<const double> delta, const model::Dataset& data,
                                const Weights& weights, const std::vector<int>& rows, const Eigen::VectorXd& centre,
                                const Eigen::VectorXd& sigmas, const PriorOptions& options, const PriorScales& current);

// Whether two estimates differ by more than `relative` in some class's scale.
bool scales_moved(const PriorScales& a, const PriorScales& b, double relative);

// `to` with each class's scale half way from `from`'s in log scale (the geometric mean): the
// damped update of identify's loop once the estimates cycle (geometry+sag's masses' class and a
// link's centres can trade one first moment, m x c, back and forth pass after pass). Same fixed
// points, the cycle damped.
PriorScales halfway_scales(const PriorScales& from, const PriorScales& to);

// The report's lines: per class the scale the data chose, the resulting sigmas and why
// (evidence, a bound, or the default kept); empty when the stage did not run.
std::string format_prior_scales(const PriorScales& scales);

}  // namespace kincal::identify

#include "host/identify/prior_scale.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include <Eigen/Cholesky>

#include "host/model/robot_model.hpp"

namespace kincal::identify {

namespace {

int class_of_kind(core::ParameterKind kind) {
  using K = core::ParameterKind;
  if (kind == model::kLinkMass) return static_cast<int>(PriorClass::link_mass);
  if (model::is_mass_parameter(kind)) return static_cast<int>(PriorClass::mass_centre);
  if (model::is_joint_map_parameter(kind)) return static_cast<int>(PriorClass::non_geometric);
  if (kind == K::link_d || kind == K::link_a) return static_cast<int>(PriorClass::link_length);
  if (kind <= K::link_beta) return static_cast<int>(PriorClass::link_angle);
  if (kind <= K::base_rz) return static_cast<int>(PriorClass::registration);
  return static_cast<int>(PriorClass::measured_point);
}

// The class's default widths as the report prints them, times `scale`.
std::string class_sigmas(PriorClass c, const PriorOptions& o, double scale) {
  constexpr double kDeg = 180.0 / std::numbers::pi;
  const double f = scale / o.strength;
  char text[96];
  switch (c) {
    case PriorClass::link_length:
      std::snprintf(text, sizeof text, "%.3g mm", o.length_m * f * 1e3);
      break;
    case PriorClass::link_angle:
      std::snprintf(text, sizeof text, "%.3g deg", o.angle_rad * f * kDeg);
      break;
    case PriorClass::registration:
      std::snprintf(text, sizeof text, "%.3g mm, %.3g deg", o.base_length_m * f * 1e3, o.base_angle_rad * f * kDeg);
      break;
    case PriorClass::measured_point:
      std::snprintf(text, sizeof text, "%.3g mm, %.3g deg", o.tool_length_m * f * 1e3, o.tool_angle_rad * f * kDeg);
      break;
    case PriorClass::link_mass:
      std::snprintf(text, sizeof text, "%.3g kg", o.mass_kg * f);
      break;
    case PriorClass::mass_centre:
      std::snprintf(text, sizeof text, "%.3g mm", o.centre_m * f * 1e3);
      break;
    default:
      std::snprintf(text, sizeof text, "scale %.3g %%, gravity direction %.3g deg", o.scale * f * 100.0,
                    o.gravity_direction_rad * f * kDeg);
      break;
  }
  return text;
}

// The posterior's diagonal and the linear MAP step of the linearization at the prior weights w2
// (1 / sigma^2, 0 for none).
struct LinearPosterior {
  Eigen::VectorXd variance;  // Sigma_kk
  Eigen::VectorXd delta;
};

LinearPosterior linear_posterior(const Eigen::MatrixXd& information, const Eigen::VectorXd& gradient,
                                 const Eigen::VectorXd& delta, const Eigen::VectorXd& centre,
                                 const Eigen::VectorXd& w2) {
  const Eigen::MatrixXd a = information + Eigen::MatrixXd(w2.asDiagonal());
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(a);
  LinearPosterior out;
  out.variance = ldlt.solve(Eigen::MatrixXd::Identity(a.rows(), a.cols())).diagonal().cwiseMax(0.0);
  out.delta = delta - ldlt.solve(Eigen::VectorXd(gradient + w2.cwiseProduct(delta - centre)));
  return out;
}

}  // namespace

const char* prior_class_name(PriorClass c) {
  switch (c) {
    case PriorClass::link_length:
      return "link lengths";
    case PriorClass::link_angle:
      return "link angles";
    case PriorClass::registration:
      return "registration";
    case PriorClass::measured_point:
      return "measured point";
    case PriorClass::link_mass:
      return "link masses";
    case PriorClass::mass_centre:
      return "mass centres";
    default:
      return "non-geometric";
  }
}

PriorScales initial_prior_scales(const PriorOptions& options, const ParameterIds& ids, int joint_count) {
  PriorScales s;
  PriorOptions defaults = options;
  defaults.sigma.clear();
  const Eigen::VectorXd sigma = prior_sigmas(defaults, ids, joint_count, "prior");
  std::vector<int> count(kPriorClasses, 0);
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const std::string name = model::parameter_name(ids[k]);
    const bool named = std::any_of(options.sigma.begin(), options.sigma.end(), [&](const auto& entry) {
      return model::parameter_name(model::parse_parameter_name(entry.first, joint_count)) == name;
    });
    const int c = named || !std::isfinite(sigma(static_cast<Eigen::Index>(k))) ? -1 : class_of_kind(ids[k].kind);
    s.class_of.push_back(c);
    if (c >= 0) ++count[static_cast<std::size_t>(c)];
  }
  for (int c = 0; c < kPriorClasses; ++c)
    if (count[static_cast<std::size_t>(c)] > 0)
      s.classes.push_back({static_cast<PriorClass>(c), count[static_cast<std::size_t>(c)]});
  s.estimated = options.estimate_scales && options.strength > 0.0 && !s.classes.empty();
  s.options = options;
  return s;
}

Eigen::VectorXd scaled_sigmas(const Eigen::VectorXd& sigmas, const PriorScales& scales) {
  Eigen::VectorXd out = sigmas;
  if (!scales.estimated) return out;
  for (const ClassScale& c : scales.classes)
    for (std::size_t k = 0; k < scales.class_of.size(); ++k)
      if (scales.class_of[k] == static_cast<int>(c.kind)) out(static_cast<Eigen::Index>(k)) *= c.scale;
  return out;
}

PriorScales update_prior_scales(const Eigen::MatrixXd& information, const Eigen::VectorXd& gradient,
                                const Eigen::VectorXd& delta, const Eigen::VectorXd& centre,
                                const Eigen::VectorXd& sigmas, const PriorOptions& options,
                                const PriorScales& current) {
  PriorScales next = current;
  if (!next.estimated) return next;
  const Eigen::Index p = delta.size();
  const Eigen::VectorXd b = sigmas / options.strength;  // the default sigma of each parameter
  // 1 / (scale b)^2 at each class's scale; the fixed priors (named, no class) as they are.
  const auto weights2 = [&](const std::vector<double>& scale) {
    Eigen::VectorXd w2 = Eigen::VectorXd::Zero(p);
    for (Eigen::Index k = 0; k < p; ++k) {
      if (!std::isfinite(b(k))) continue;
      const int c = next.class_of[static_cast<std::size_t>(k)];
      const double s = c >= 0 ? scale[static_cast<std::size_t>(c)] : 1.0;
      w2(k) = 1.0 / (s * b(k) * s * b(k));
    }
    return w2;
  };
  // gamma_c and the squared normalized deviation of every class at the scales `scale`.
  const auto gammas = [&](const std::vector<double>& scale, const LinearPosterior& post, std::vector<double>& gamma,
                          std::vector<double>& deviation2) {
    gamma.assign(kPriorClasses, 0.0);
    deviation2.assign(kPriorClasses, 0.0);
    for (Eigen::Index k = 0; k < p; ++k) {
      const int c = next.class_of[static_cast<std::size_t>(k)];
      if (c < 0) continue;
      const auto u = static_cast<std::size_t>(c);
      const double prior2 = scale[u] * b(k) * scale[u] * b(k);
      gamma[u] += 1.0 - std::min(1.0, post.variance(k) / prior2);
      deviation2[u] += (post.delta(k) - centre(k)) * (post.delta(k) - centre(k)) / (b(k) * b(k));
    }
  };
  std::vector<double> ones(kPriorClasses, 1.0), gamma, deviation2;
  gammas(ones, linear_posterior(information, gradient, delta, centre, weights2(ones)), gamma, deviation2);
  std::vector<double> scale = ones;
  for (ClassScale& c : next.classes) {
    const auto u = static_cast<std::size_t>(c.kind);
    c.seen_at_default = gamma[u];
    scale[u] = c.seen_at_default < kMinSeenParameters ? 1.0 : c.scale;
  }
  for (int iteration = 0; iteration < 200; ++iteration) {
    const LinearPosterior post = linear_posterior(information, gradient, delta, centre, weights2(scale));
    gammas(scale, post, gamma, deviation2);
    double moved = 0.0;
    for (ClassScale& c : next.classes) {
      const auto u = static_cast<std::size_t>(c.kind);
      c.determined = gamma[u];
      if (c.seen_at_default < kMinSeenParameters) {
        c.reason = ScaleReason::barely_seen;
        continue;
      }
      const double wanted = std::sqrt(deviation2[u] / std::max(gamma[u], 1e-12));
      const double bounded = std::clamp(wanted, options.min_scale, options.max_scale);
      c.reason = wanted < options.min_scale   ? ScaleReason::lower_bound
                 : wanted > options.max_scale ? ScaleReason::upper_bound
                                              : ScaleReason::evidence;
      moved = std::max(moved, std::abs(std::log(bounded / scale[u])));
      scale[u] = bounded;
    }
    if (moved < 1e-4) break;
  }
  for (ClassScale& c : next.classes) c.scale = scale[static_cast<std::size_t>(c.kind)];
  return next;
}

PriorScales update_prior_scales(const Parameterization& p, std::span<const double> delta, const model::Dataset& data,
                                const Weights& weights, const std::vector<int>& rows, const Eigen::VectorXd& centre,
                                const Eigen::VectorXd& sigmas, const PriorOptions& options,
                                const PriorScales& current) {
  if (!current.estimated) return current;
  Eigen::VectorXd r;
  Eigen::MatrixXd j;
  stacked(p, data, weights, rows, r, &j);
  return update_prior_scales(j.transpose() * j, j.transpose() * r,
                             Eigen::Map<const Eigen::VectorXd>(delta.data(), static_cast<Eigen::Index>(delta.size())),
                             centre, sigmas, options, current);
}

bool scales_moved(const PriorScales& a, const PriorScales& b, double relative) {
  if (a.classes.size() != b.classes.size()) return true;
  for (std::size_t c = 0; c < a.classes.size(); ++c)
    if (std::abs(a.classes[c].scale - b.classes[c].scale) > relative * std::max(a.classes[c].scale, b.classes[c].scale))
      return true;
  return false;
}

PriorScales halfway_scales(const PriorScales& from, const PriorScales& to) {
  PriorScales out = to;
  if (from.classes.size() != to.classes.size()) return out;
  for (std::size_t c = 0; c < out.classes.size(); ++c)
    out.classes[c].scale = std::sqrt(from.classes[c].scale * to.classes[c].scale);
  return out;
}

std::string format_prior_scales(const PriorScales& scales) {
  if (!scales.estimated) return "";
  const PriorOptions& options = scales.options;
  char line[256];
  std::snprintf(line, sizeof line,
                "prior widths chosen by the data (evidence, type-II maximum likelihood; %g to %g x the defaults):\n",
                options.min_scale, options.max_scale);
  std::string out = line;
  for (const ClassScale& c : scales.classes) {
    std::string why;
    char figures[128];
    std::snprintf(figures, sizeof figures, "%.1f of %d parameters determined by the data", c.determined, c.parameters);
    switch (c.reason) {
      case ScaleReason::evidence:
        why = std::string("evidence: ") + figures;
        break;
      case ScaleReason::lower_bound:
        why = std::string("the lower bound: the evidence asks for less; ") + figures;
        break;
      case ScaleReason::upper_bound:
        why = std::string("the upper bound: the evidence asks for more; ") + figures;
        break;
      case ScaleReason::barely_seen:
        std::snprintf(figures, sizeof figures, "%.2f", c.seen_at_default);
        why = std::string("the default kept: the data barely see this class (") + figures + " of " +
              std::to_string(c.parameters) + " parameters determined)";
        break;
    }
    std::snprintf(line, sizeof line, "  %-15s %7.3g x  sigma %-20s (%s)\n", prior_class_name(c.kind), c.scale,
                  class_sigmas(c.kind, options, c.scale).c_str(), why.c_str());
    out += line;
  }
  return out;
}

}  // namespace kincal::identify

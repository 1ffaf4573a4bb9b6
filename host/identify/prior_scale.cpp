#include "host/identify/prior_scale.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>

#include <Eigen/Cholesky>

#include "host/model/robot_model.hpp"

namespace kincal::identify {

namespace {

// A parameter's class; none for gravity's direction, which keeps its default (prior_scale.hpp).
std::optional<PriorClass> class_of_parameter(core::ParameterId id, const std::vector<bool>& given_centres) {
  using K = core::ParameterKind;
  const core::ParameterKind kind = id.kind;
  if (model::is_gravity_direction_parameter(kind)) return std::nullopt;
  if (kind == model::kLinkMass) return PriorClass::link_mass;
  if (is_given_centre(id, given_centres)) return PriorClass::given_centre;
  if (model::is_mass_parameter(kind)) return PriorClass::mass_centre;
  if (kind == model::kJointCompliance) return PriorClass::joint_compliance;
  if (model::is_joint_map_parameter(kind)) return PriorClass::joint_ratio;
  if (kind == K::link_d || kind == K::link_a) return PriorClass::link_length;
  if (kind <= K::link_beta) return PriorClass::link_angle;
  if (kind <= K::base_rz) return PriorClass::registration;
  return PriorClass::measured_point;
}

// A class of one parameter, its width the evidence's closed form (prior_scale.hpp): a joint
// ratio's, a compliance's or a mass centre's, a property of its own joint or link.
bool own_class(PriorClass kind) {
  return kind == PriorClass::joint_ratio || kind == PriorClass::joint_compliance || kind == PriorClass::mass_centre;
}

// The class's default widths as the report prints them, times `scale`.
std::string class_sigmas(const ClassScale& c, const PriorOptions& o, double scale) {
  constexpr double kDeg = 180.0 / std::numbers::pi;
  const double f = scale / o.strength;
  char text[96];
  switch (c.kind) {
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
    case PriorClass::given_centre:
      std::snprintf(text, sizeof text, "%.3g mm", o.given_centre_m * f * 1e3);
      break;
    case PriorClass::joint_compliance:
      if (c.prismatic)
        std::snprintf(text, sizeof text, "%.3g mm at its load", o.deflection_m * f * 1e3);
      else
        std::snprintf(text, sizeof text, "%.3g deg at its load", o.deflection_rad * f * kDeg);
      break;
    default:
      std::snprintf(text, sizeof text, "%.3g %%",
                    (c.parameter.rfind("scale", 0) == 0 ? o.scale : o.coupling) * f * 100.0);
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
    case PriorClass::given_centre:
      return "given centres";
    case PriorClass::joint_compliance:
      return "joint compliance";
    default:
      return "joint ratio";
  }
}

PriorScales initial_prior_scales(const PriorOptions& options, const ParameterIds& ids, int joint_count,
                                 const GravityLoads& loads, const std::vector<bool>& given_centres) {
  PriorScales s;
  PriorOptions defaults = options;
  defaults.sigma.clear();
  const Eigen::VectorXd sigma = prior_sigmas(defaults, ids, joint_count, "prior", loads, given_centres);
  std::vector<int> kind_of;  // each parameter's PriorClass, or -1 for none
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const std::string name = model::parameter_name(ids[k]);
    const bool named = std::any_of(options.sigma.begin(), options.sigma.end(), [&](const auto& entry) {
      return model::parameter_name(model::parse_parameter_name(entry.first, joint_count)) == name;
    });
    const std::optional<PriorClass> kind = class_of_parameter(ids[k], given_centres);
    kind_of.push_back(named || !std::isfinite(sigma(static_cast<Eigen::Index>(k))) || !kind ? -1
                                                                                            : static_cast<int>(*kind));
  }
  s.class_of.assign(ids.size(), -1);
  for (int kind = 0; kind <= static_cast<int>(PriorClass::given_centre); ++kind)
    for (std::size_t k = 0; k < ids.size(); ++k) {
      if (kind_of[k] != kind) continue;
      const bool own = own_class(static_cast<PriorClass>(kind));
      if (own || s.classes.empty() || s.classes.back().kind != static_cast<PriorClass>(kind))
        s.classes.push_back({static_cast<PriorClass>(kind), own ? model::parameter_name(ids[k]) : "",
                             ids[k].kind == model::kJointCompliance && ids[k].link < loads.prismatic.size() &&
                                 loads.prismatic[ids[k].link]});
      ++s.classes.back().parameters;
      s.class_of[k] = static_cast<int>(s.classes.size()) - 1;
    }
  s.estimated = options.estimate_scales && options.strength > 0.0 && !s.classes.empty();
  s.options = options;
  return s;
}

Eigen::VectorXd scaled_sigmas(const Eigen::VectorXd& sigmas, const PriorScales& scales) {
  Eigen::VectorXd out = sigmas;
  if (!scales.estimated) return out;
  for (std::size_t k = 0; k < scales.class_of.size(); ++k)
    if (scales.class_of[k] >= 0)
      out(static_cast<Eigen::Index>(k)) *= scales.classes[static_cast<std::size_t>(scales.class_of[k])].scale;
  return out;
}

PriorScales update_prior_scales(const Eigen::MatrixXd& information, const Eigen::VectorXd& gradient,
                                const Eigen::VectorXd& delta, const Eigen::VectorXd& centre,
                                const Eigen::VectorXd& sigmas, const PriorOptions& options,
                                const PriorScales& current) {
  PriorScales next = current;
  if (!next.estimated) return next;
  const Eigen::Index p = delta.size();
  const std::size_t classes = next.classes.size();
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
  // gamma_c and, per class, the scale the evidence asks for at the scales `scale` (MacKay's
  // fixed point's next step; a class of one's maximum in closed form, 0 for none).
  std::vector<double> gamma, wanted;
  const auto evidence = [&](const std::vector<double>& scale, const LinearPosterior& post) {
    gamma.assign(classes, 0.0);
    std::vector<double> deviation2(classes, 0.0);
    wanted.assign(classes, 0.0);
    for (Eigen::Index k = 0; k < p; ++k) {
      const int c = next.class_of[static_cast<std::size_t>(k)];
      if (c < 0) continue;
      const auto u = static_cast<std::size_t>(c);
      const double prior2 = scale[u] * b(k) * scale[u] * b(k);
      const double deviation = post.delta(k) - centre(k);
      gamma[u] += 1.0 - std::min(1.0, post.variance(k) / prior2);
      deviation2[u] += deviation * deviation / (b(k) * b(k));
      if (own_class(next.classes[u].kind)) {
        const double seen = 1.0 / std::max(post.variance(k), 1e-300) - 1.0 / prior2;       // s
        const double alone = seen > 0.0 ? deviation * (seen + 1.0 / prior2) / seen : 0.0;  // m - centre
        const double se2 = next.classes[u].kind == PriorClass::joint_ratio ? kRatioStandardErrors * kRatioStandardErrors
                                                                           : 1.0;  // (standard errors)^2
        const double width2 = seen > 0.0 ? alone * alone - se2 / seen : 0.0;
        wanted[u] = width2 > 0.0 ? std::sqrt(width2) / b(k) : 0.0;
      }
    }
    for (std::size_t u = 0; u < classes; ++u)
      if (!own_class(next.classes[u].kind)) wanted[u] = std::sqrt(deviation2[u] / std::max(gamma[u], 1e-12));
  };
  const std::vector<double> ones(classes, 1.0);
  evidence(ones, linear_posterior(information, gradient, delta, centre, weights2(ones)));
  std::vector<double> scale(classes, 1.0);
  for (std::size_t u = 0; u < classes; ++u) {
    ClassScale& c = next.classes[u];
    c.seen_at_default = gamma[u];
    scale[u] = c.seen_at_default < kMinSeenParameters ? 1.0 : c.scale;
  }
  for (int iteration = 0; iteration < 200; ++iteration) {
    evidence(scale, linear_posterior(information, gradient, delta, centre, weights2(scale)));
    double moved = 0.0;
    for (std::size_t u = 0; u < classes; ++u) {
      ClassScale& c = next.classes[u];
      c.determined = gamma[u];
      if (c.seen_at_default < kMinSeenParameters) {
        c.reason = ScaleReason::barely_seen;
        continue;
      }
      const double lowest = c.kind == PriorClass::joint_ratio ? options.min_ratio_scale : options.min_scale;
      const double bounded = std::clamp(wanted[u], lowest, options.max_scale);
      c.reason = wanted[u] < lowest              ? ScaleReason::lower_bound
                 : wanted[u] > options.max_scale ? ScaleReason::upper_bound
                                                 : ScaleReason::evidence;
      moved = std::max(moved, std::abs(std::log(bounded / scale[u])));
      scale[u] = bounded;
    }
    if (moved < 1e-4) break;
  }
  for (std::size_t u = 0; u < classes; ++u) next.classes[u].scale = scale[u];
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
                "prior widths chosen by the data (evidence, type-II maximum likelihood; %g to %g x the defaults",
                options.min_scale, options.max_scale);
  std::string out = line;
  const bool ratios = std::any_of(scales.classes.begin(), scales.classes.end(),
                                  [](const ClassScale& c) { return c.kind == PriorClass::joint_ratio; });
  if (ratios) {
    std::snprintf(line, sizeof line, ", a joint ratio's own from %g", options.min_ratio_scale);
    out += line;
  }
  out += "):\n";
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
    const std::string label = c.parameter.empty() ? prior_class_name(c.kind) : c.parameter;
    std::snprintf(line, sizeof line, "  %-17s %7.3g x  sigma %-20s (%s)\n", label.c_str(), c.scale,
                  class_sigmas(c, options, c.scale).c_str(), why.c_str());
    out += line;
  }
  return out;
}

}  // namespace kincal::identify

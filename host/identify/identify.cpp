#include "host/identify/identify.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <memory>
#include <numbers>
#include <random>
#include <sstream>

#include "host/identify/cpa.hpp"
#include "host/identify/statistics.hpp"
#include "host/model/axes.hpp"

namespace kincal::identify {

namespace {

using model::InputError;

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

class RowCost final : public ceres::CostFunction {
 public:
  RowCost(Parameterization& p, const model::Measurement& m, const Eigen::Matrix3d& w, double wo, int size)
      : p_(p), m_(m), w_(w), wo_(wo), size_(size) {
    set_num_residuals(size);
    mutable_parameter_block_sizes()->push_back(p.size());
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    p_.set(std::span<const double>(parameters[0], static_cast<std::size_t>(p_.size())));
    const bool want = jacobians != nullptr && jacobians[0] != nullptr;
    Eigen::MatrixXd j;
    row_residual(p_, m_, w_, wo_, residuals, want ? &j : nullptr);
    if (want) {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(jacobians[0], size_,
                                                                                         p_.size()) = j;
    }
    return true;
  }

 private:
  Parameterization& p_;
  const model::Measurement& m_;
  Eigen::Matrix3d w_;
  double wo_;
  int size_;
};

std::vector<int> all_rows(const model::Dataset& data) {
  std::vector<int> rows(data.rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) rows[i] = static_cast<int>(i);
  return rows;
}

// Whitened squared residual norms per row (position part, orientation part).
void row_norms(const Parameterization& p, const model::Dataset& data, const Weights& w, std::vector<double>& position,
               std::vector<double>& orientation) {
  position.clear();
  orientation.clear();
  double r[6];
  for (std::size_t i = 0; i < data.rows.size(); ++i) {
    row_residual(p, data.rows[i], w.position[i], w.orientation, r, nullptr);
    position.push_back(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    orientation.push_back(w.orientation > 0 ? r[3] * r[3] + r[4] * r[4] + r[5] * r[5] : 0.0);
  }
}

struct SolveSummary {
  int iterations = 0;
  std::string termination;
};

SolveSummary solve_ceres(Parameterization& p, const model::Dataset& data, const Weights& w,
                         const std::vector<int>& rows, bool robust, int max_iterations, std::vector<double>& delta) {
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  const int size = residual_size(w);
  std::unique_ptr<ceres::LossFunction> loss;
  if (robust) loss = std::make_unique<ceres::HuberLoss>(std::sqrt(chi_square_quantile(0.999, size)));
  for (int r : rows) {
    const auto k = static_cast<std::size_t>(r);
    problem.AddResidualBlock(new RowCost(p, data.rows[k], w.position[k], w.orientation, size), loss.get(),
                             delta.data());
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = max_iterations;
  options.num_threads = 1;
  options.function_tolerance = 1e-12;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-12;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  p.set(delta);
  SolveSummary out;
  out.iterations = static_cast<int>(summary.iterations.size());
  out.termination = ceres::TerminationTypeToString(summary.termination_type);
  if (summary.termination_type == ceres::NO_CONVERGENCE) out.termination += " (iteration limit)";
  return out;
}

// Parses --fix / --params entries; "base" and "tool" stand for their six motions.
ParameterIds parse_names(const std::vector<std::string>& names, const RobotModel& m) {
  ParameterIds ids;
  for (const std::string& name : names) {
    if (name == "base" || name == "tool") {
      const int first = static_cast<int>(name == "base" ? core::ParameterKind::base_x : core::ParameterKind::tool_x);
      for (int k = 0; k < 6; ++k) ids.push_back({static_cast<core::ParameterKind>(first + k), 0});
      continue;
    }
    ids.push_back(model::parse_parameter_name(name, m.joint_count()));
  }
  return ids;
}

bool same_id(core::ParameterId a, core::ParameterId b) {
  return a.kind == b.kind && (a.kind > core::ParameterKind::link_beta || a.link == b.link);
}

bool contains(const ParameterIds& ids, core::ParameterId id) {
  return std::any_of(ids.begin(), ids.end(), [&](core::ParameterId x) { return same_id(x, id); });
}

void check_data(const RobotModel& m, const model::Dataset& data) {
  model::check_joint_count(m, data.joint_count, data.source);
  if (data.rows.empty()) throw InputError(data.source + ": no measurements");
  for (int j = 0; j < data.joint_count; ++j) {
    double lo = data.rows[0].q[static_cast<std::size_t>(j)], hi = lo;
    for (const auto& row : data.rows) {
      lo = std::min(lo, row.q[static_cast<std::size_t>(j)]);
      hi = std::max(hi, row.q[static_cast<std::size_t>(j)]);
    }
    if (hi == lo) {
      std::ostringstream msg;
      msg << data.source << ": joint " << j + 1 << " (" << m.joints[static_cast<std::size_t>(j)].name
          << ") never moved: every row has q" << j + 1 << " = " << lo
          << "; its axis cannot be identified (move it, or calibrate a model without it)";
      throw InputError(msg.str());
    }
  }
}

Eigen::VectorXd standard_deviations(const Eigen::MatrixXd& j) {
  const Eigen::MatrixXd info = j.transpose() * j;
  const Eigen::MatrixXd cov = info.ldlt().solve(Eigen::MatrixXd::Identity(info.rows(), info.cols()));
  return cov.diagonal().cwiseMax(0.0).cwiseSqrt();
}

// Identifiability over 100 random configurations within the limits (revolute joints without
// limits: [-pi, pi]; prismatic: [-1, 1] m): what no choice of configurations can improve on.
Identifiability structural_identifiability(const RobotModel& m, const ParameterIds& candidates, bool orientation) {
  std::mt19937_64 rng(12345);
  const int rows = orientation ? 6 : 3;
  const int count = 100;
  Eigen::MatrixXd j(rows * count, static_cast<Eigen::Index>(candidates.size()));
  for (int k = 0; k < count; ++k) {
    std::vector<double> q;
    for (const model::Joint& joint : m.joints) {
      const double span = joint.type == core::JointType::revolute ? std::numbers::pi : 1.0;
      const double lo = std::isfinite(joint.lower) ? joint.lower : -span;
      const double hi = std::isfinite(joint.upper) ? joint.upper : span;
      q.push_back(std::uniform_real_distribution<double>(lo, hi)(rng));
    }
    Eigen::MatrixXd e = model::parameter_jacobian(m, q, candidates);
    j.middleRows(rows * k, rows) = e.topRows(rows);
  }
  return analyze_identifiability(j, candidates);
}

}  // namespace

AccuracyStats accuracy(const RobotModel& m, const model::Dataset& data, const std::vector<int>& rows_in) {
  const std::vector<int> rows = rows_in.empty() ? all_rows(data) : rows_in;
  AccuracyStats s;
  s.has_orientation = data.has_orientation && m.tool == model::ToolKind::frame;
  double sum = 0, sum2 = 0, osum = 0, osum2 = 0;
  for (int r : rows) {
    const model::Measurement& row = data.rows[static_cast<std::size_t>(r)];
    const Transform pose = model::forward_kinematics(m, row.q);
    const double e = (pose.translation - row.position).norm();
    sum += e;
    sum2 += e * e;
    s.max_m = std::max(s.max_m, e);
    if (s.has_orientation && row.orientation) {
      const double a = so3_log(row.orientation->toRotationMatrix() * pose.rotation.transpose()).norm();
      osum += a;
      osum2 += a * a;
      s.max_rad = std::max(s.max_rad, a);
    }
    ++s.count;
  }
  if (s.count > 0) {
    s.mean_m = sum / s.count;
    s.rms_m = std::sqrt(sum2 / s.count);
    s.mean_rad = osum / s.count;
    s.rms_rad = std::sqrt(osum2 / s.count);
  }
  return s;
}

// Candidates in order of preference: base, tool, then link by link (theta, d, a, alpha, beta).
ParameterIds candidate_parameters(const RobotModel& m) {
  const ParameterIds all = model::all_parameters(m);
  ParameterIds out;
  for (const auto& id : all)
    if (id.kind >= core::ParameterKind::base_x && id.kind <= core::ParameterKind::base_rz) out.push_back(id);
  for (const auto& id : all)
    if (id.kind >= core::ParameterKind::tool_x) out.push_back(id);
  for (const auto& id : all)
    if (id.kind <= core::ParameterKind::link_beta) out.push_back(id);
  return out;
}

RobotModel reparameterize_for_identification(const RobotModel& m, double tolerance, std::vector<std::string>* notes) {
  RobotModel out = m;
  const std::size_t n = m.joints.size();
  bool modified_parallel = false;
  std::vector<double> zero(n, 0.0);
  const std::vector<model::AxisLine> axes = model::joint_axes(m, zero);
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const double angle = std::acos(std::min(1.0, std::abs(axes[i].direction.dot(axes[i + 1].direction))));
    if (angle >= tolerance) continue;
    if (m.joints[i].convention == core::LinkConvention::standard_dh) {
      out.joints[i].convention = core::LinkConvention::doty;
      out.joints[i].parameters.beta_rad = 0.0;
      if (notes)
        notes->push_back("joint " + std::to_string(i + 1) + ": axes " + std::to_string(i + 1) + " and " +
                         std::to_string(i + 2) + " are nearly parallel; link " + std::to_string(i + 1) +
                         " identified in Doty's convention (beta), which is continuous there");
    }
    if (m.joints[i].convention == core::LinkConvention::modified_dh ||
        m.joints[i + 1].convention == core::LinkConvention::modified_dh)
      modified_parallel = true;
  }
  if (!modified_parallel) return out;
  const Transform tool = model::forward_kinematics(m, zero);
  RobotModel rewritten = model::chain_from_axes(m, axes, zero, tool, {tolerance});
  // Same kinematics: check a few configurations.
  for (int k = 0; k < 20; ++k) {
    std::vector<double> q(n);
    for (std::size_t i = 0; i < n; ++i) q[i] = std::sin(1.7 * (k + 1) * static_cast<double>(i + 1));
    const Transform a = model::forward_kinematics(m, q), b = model::forward_kinematics(rewritten, q);
    if ((a.translation - b.translation).norm() > 1e-9 || (a.rotation - b.rotation).norm() > 1e-9)
      throw std::logic_error("rewriting the modified-DH chain changed its kinematics");
  }
  if (notes)
    notes->push_back(
        "the modified-DH chain has nearly parallel consecutive axes; rewritten as DH/Doty from its axes "
        "(same kinematics) for identification");
  return rewritten;
}

IdentifyResult identify(const RobotModel& nominal, const model::Dataset& data, const IdentifyOptions& options) {
  check_data(nominal, data);
  IdentifyResult result;
  const int n = nominal.joint_count();

  // Noise levels: known from the data, given, or estimated.
  const bool all_covariance = std::all_of(data.rows.begin(), data.rows.end(),
                                          [](const model::Measurement& r) { return r.covariance.has_value(); });
  result.all_covariance = all_covariance;
  result.sigma_estimated = !all_covariance && !(options.sigma_m > 0.0);
  result.sigma_m = options.sigma_m > 0.0 ? options.sigma_m : 1e-3;
  result.orientation_used = data.has_orientation && nominal.tool == model::ToolKind::frame;
  const bool orientation_estimated = result.orientation_used && !(options.orientation_sigma_rad > 0.0);
  result.orientation_estimated = orientation_estimated;
  result.orientation_sigma_rad = options.orientation_sigma_rad > 0.0 ? options.orientation_sigma_rad : 1e-3;
  if (data.has_orientation && nominal.tool == model::ToolKind::point)
    result.notes.push_back("the data has orientations but the model's tool is a point: positions only");

  if (options.method == Method::cpa || options.start == Start::cpa) {
    CpaOptions cpa_options;
    cpa_options.sigma_m = options.sigma_m;
    cpa_options.parallel_tolerance_rad = options.parallel_tolerance_rad;
    const CpaResult cpa = circle_point_analysis(nominal, data, cpa_options);
    for (const SweepFit& f : cpa.fits) {
      std::ostringstream line;
      line << "joint " << f.joint + 1 << ": " << (f.curved ? "circle" : "line") << " (p(straight) = " << f.p_value
           << "), " << f.used << " points";
      if (f.curved) line << ", radius " << f.radius_m * 1e3 << " mm";
      line << ", fit rms " << f.rms_m * 1e3 << " mm";
      if (!f.rejected_lines.empty()) {
        line << ", rejected lines";
        for (int l : f.rejected_lines) line << ' ' << l;
      }
      result.cpa_sweeps.push_back(line.str());
    }
    result.notes.insert(result.notes.end(), cpa.notes.begin(), cpa.notes.end());
    if (options.method == Method::cpa) {
      result.model = cpa.model;
      result.start = nominal;
      result.residuals = accuracy(result.model, data);
      result.termination = "circle-point analysis";
      model::CalibrationRecord record;
      record.method = "cpa";
      record.data = data.source;
      record.measurements = static_cast<int>(data.rows.size());
      record.rms_residual_m = result.residuals.rms_m;
      result.model.calibration = record;
      return result;
    }
    result.start = reparameterize_for_identification(cpa.model, options.parallel_tolerance_rad, &result.notes);
  } else {
    result.start = reparameterize_for_identification(nominal, options.parallel_tolerance_rad, &result.notes);
  }

  Weights weights = make_weights(data, result.sigma_m, result.orientation_used ? result.orientation_sigma_rad : 0.0);
  const int size = residual_size(weights);

  // Candidates and identifiability at the start.
  const ParameterIds fixed = parse_names(options.fixed, result.start);
  const ParameterIds requested = parse_names(options.requested, result.start);
  ParameterIds candidates;
  if (!requested.empty()) {
    candidates = requested;
  } else {
    for (const auto& id : candidate_parameters(result.start))
      if (!contains(fixed, id)) candidates.push_back(id);
  }
  for (const auto& id : candidates)
    if (id.kind >= core::ParameterKind::tool_rx && result.start.tool == model::ToolKind::point)
      throw InputError(model::parameter_name(id) + ": the model's tool is a point, which has no orientation");
  std::vector<int> rows = all_rows(data);
  // What the robot's structure allows at all: the same analysis over random configurations.
  const Identifiability structural = structural_identifiability(result.start, candidates, result.orientation_used);
  {
    Parameterization all(result.start, candidates);
    Eigen::VectorXd r;
    Eigen::MatrixXd j;
    stacked(all, data, weights, rows, r, &j);
    result.identifiability = analyze_identifiability(j, candidates);
  }
  if (!requested.empty() && !result.identifiability.held_fixed.empty()) {
    std::string what;
    for (const HeldFixed& h : result.identifiability.held_fixed)
      what += "\n  " + model::parameter_name(h.id) + ": " + h.reason;
    throw InputError(data.source + ": the data cannot identify the requested parameters:" + what);
  }
  for (const auto& id : fixed) result.identifiability.held_fixed.push_back({id, "fixed on request"});
  const ParameterIds& ids = result.identifiability.identified;
  const int p = static_cast<int>(ids.size());
  const int p_structural = static_cast<int>(structural.identified.size());
  const int equations = static_cast<int>(data.rows.size()) * (result.orientation_used ? 6 : 3);
  const int needed = p_structural + (result.sigma_estimated ? 1 : 0) + (orientation_estimated ? 1 : 0);
  if (equations < needed) {
    throw InputError(data.source + ": too few measurements: " + std::to_string(data.rows.size()) + " give " +
                     std::to_string(equations) + " equations for " + std::to_string(p_structural) +
                     " identifiable parameters" + (needed > p ? " and the noise level" : "") + "; need at least " +
                     std::to_string((needed + size - 1) / size) + " measurements");
  }
  if (p == 0) throw InputError(data.source + ": no parameter is identifiable from this data");
  if (p < p_structural) {
    std::string names;
    for (const HeldFixed& h : result.identifiability.held_fixed)
      if (contains(structural.identified, h.id)) names += " " + model::parameter_name(h.id);
    result.notes.push_back("this data identifies " + std::to_string(p) + " of the " + std::to_string(p_structural) +
                           " parameters the robot's structure allows; not excited by these configurations:" + names +
                           " (see `kincal plan`)");
  }

  Parameterization param(result.start, ids);
  std::vector<double> delta(static_cast<std::size_t>(p), 0.0);
  const double orientation_scale = result.orientation_used ? 1.0 : 0.0;

  if (options.method == Method::first_order) {
    // Doty's eps = E psi, one weighted least-squares step at the nominal model.
    Eigen::VectorXd r;
    Eigen::MatrixXd j;
    stacked(param, data, weights, rows, r, &j);
    const Eigen::VectorXd step = j.colPivHouseholderQr().solve(-r);
    for (int k = 0; k < p; ++k) delta[static_cast<std::size_t>(k)] = step(k);
    param.set(delta);
    result.iterations = 1;
    result.termination = "one linear step (first-order model)";
    if (result.sigma_estimated || orientation_estimated) {
      // Noise from the residuals of the linear fit.
      std::vector<double> pos, ori;
      row_norms(param, data, weights, pos, ori);
      double sp = 0, so = 0;
      for (std::size_t i = 0; i < pos.size(); ++i) {
        sp += pos[i];
        so += ori[i];
      }
      const double dof_each = std::max(1.0, (equations - p) / (result.orientation_used ? 2.0 : 1.0));
      if (result.sigma_estimated) result.sigma_m *= std::sqrt(sp / dof_each);
      if (orientation_estimated) result.orientation_sigma_rad *= std::sqrt(so / dof_each);
      weights = make_weights(data, result.sigma_m, result.orientation_sigma_rad * orientation_scale);
    }
  } else {
    // Full nonlinear: estimate unknown noise, reject outliers, solve again.
    bool robust = options.robust && !(result.sigma_estimated || orientation_estimated);
    std::vector<int> previous_outliers{-1};
    for (int pass = 0; pass < 6; ++pass) {
      const SolveSummary s = solve_ceres(param, data, weights, rows, robust, options.max_iterations, delta);
      result.iterations += s.iterations;
      result.termination = s.termination;
      std::vector<double> pos, ori;
      row_norms(param, data, weights, pos, ori);
      bool rescaled = false;
      if (result.sigma_estimated || orientation_estimated) {
        // Median-based while outliers may be in; sum of squares over the inliers once settled.
        std::vector<double> pin, oin;
        for (int r : rows) {
          pin.push_back(pos[static_cast<std::size_t>(r)]);
          oin.push_back(ori[static_cast<std::size_t>(r)]);
        }
        double fp = 1.0, fo = 1.0;
        if (pass == 0) {
          fp = median(pin) / chi_square_quantile(0.5, 3);
          fo = median(oin) / chi_square_quantile(0.5, 3);
        } else {
          const double dof_each =
              std::max(1.0, (static_cast<double>(rows.size()) * size - p) / (result.orientation_used ? 2.0 : 1.0));
          double sp = 0, so = 0;
          for (std::size_t i = 0; i < pin.size(); ++i) {
            sp += pin[i];
            so += oin[i];
          }
          fp = sp / dof_each;
          fo = so / dof_each;
        }
        if (result.sigma_estimated && fp > 0 && std::abs(std::sqrt(fp) - 1.0) > 1e-3) {
          result.sigma_m *= std::sqrt(fp);
          rescaled = true;
        }
        if (orientation_estimated && fo > 0 && std::abs(std::sqrt(fo) - 1.0) > 1e-3) {
          result.orientation_sigma_rad *= std::sqrt(fo);
          rescaled = true;
        }
        weights = make_weights(data, result.sigma_m, result.orientation_sigma_rad * orientation_scale);
        row_norms(param, data, weights, pos, ori);
        robust = options.robust;
      }
      // Outliers: the whole row's whitened squared residual against its chi-square quantile.
      std::vector<int> outliers;
      rows.clear();
      const double threshold = chi_square_quantile(1.0 - options.outlier_probability, size);
      for (std::size_t i = 0; i < pos.size(); ++i) {
        if (pos[i] + ori[i] > threshold) {
          outliers.push_back(static_cast<int>(i));
        } else {
          rows.push_back(static_cast<int>(i));
        }
      }
      if (static_cast<int>(rows.size()) * size < needed) {
        throw InputError(data.source + ": after rejecting " + std::to_string(outliers.size()) +
                         " outliers too few measurements remain; the model is probably far from the robot, or the "
                         "noise level too small (the dataset's sigma or covariance columns, or identify --sigma)");
      }
      if (outliers == previous_outliers && !rescaled && pass > 0) break;
      previous_outliers = outliers;
      if (pass == 5) result.notes.push_back("outlier rejection did not settle in 6 passes");
    }
    for (int i : previous_outliers)
      if (i >= 0) result.outlier_lines.push_back(data.rows[static_cast<std::size_t>(i)].line);
  }

  // Standard deviations and the chi-square of the fit.
  Eigen::VectorXd r;
  Eigen::MatrixXd j;
  stacked(param, data, weights, rows, r, &j);
  result.stddev = standard_deviations(j);
  result.change = Eigen::Map<Eigen::VectorXd>(delta.data(), p);
  const double dof = static_cast<double>(r.size()) - p;
  result.chi_square_per_dof = dof > 0 ? r.squaredNorm() / dof : 0.0;
  result.model = param.model();
  result.model.name = nominal.name;
  result.residuals = accuracy(result.model, data, rows);

  model::CalibrationRecord record;
  record.method = options.method == Method::first_order ? "first-order" : "full";
  if (options.start == Start::cpa && options.method == Method::full) record.method = "full (from cpa)";
  record.data = data.source;
  record.measurements = static_cast<int>(rows.size());
  record.rms_residual_m = result.residuals.rms_m;
  for (int k = 0; k < p; ++k)
    record.parameters.push_back(
        {model::parameter_name(ids[static_cast<std::size_t>(k)]), result.change(k), result.stddev(k)});
  for (const HeldFixed& h : result.identifiability.held_fixed) record.held_fixed.push_back(model::parameter_name(h.id));
  result.model.calibration = record;
  (void)n;
  return result;
}

std::string format_report(const IdentifyResult& r) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  const model::CalibrationRecord* c = r.model.calibration ? &*r.model.calibration : nullptr;
  out << "method: " << (c ? c->method : "?") << ", " << r.residuals.count << " measurements used";
  if (!r.outlier_lines.empty()) {
    out << ", " << r.outlier_lines.size() << " rejected as outliers (lines";
    for (int l : r.outlier_lines) out << ' ' << l;
    out << ')';
  }
  out << "\nsolver: " << r.termination;
  if (r.iterations > 0) out << ", " << r.iterations << " iterations";
  out << '\n';
  for (const std::string& s : r.cpa_sweeps) out << "sweep: " << s << '\n';
  for (const std::string& note : r.notes) out << "note: " << note << '\n';
  if (!r.identifiability.identified.empty()) {
    out.precision(3);
    out << "identifiability: rank " << r.identifiability.rank << " of " << r.identifiability.singular_values.size()
        << " candidate parameters; " << r.identifiability.identified.size()
        << " identified, condition number (unit-scaled columns) " << std::scientific << r.identifiability.condition
        << std::fixed << '\n';
    for (const HeldFixed& h : r.identifiability.held_fixed)
      out << "  held fixed: " << model::parameter_name(h.id) << " (" << h.reason << ")\n";
    out << "noise: position ";
    if (r.all_covariance) {
      out << "covariance of each measurement from the data";
    } else {
      out << "sigma " << std::setprecision(4) << r.sigma_m * 1e3 << " mm"
          << (r.sigma_estimated ? " (estimated from the residuals)" : " (given)");
    }
    if (r.orientation_used)
      out << ", orientation sigma " << r.orientation_sigma_rad * kDegPerRad << " deg"
          << (r.orientation_estimated ? " (estimated)" : " (given)");
    out << "; chi-square per degree of freedom " << r.chi_square_per_dof << '\n';
    out << "parameter        change          stddev\n";
    for (std::size_t k = 0; k < r.identifiability.identified.size(); ++k) {
      const core::ParameterId id = r.identifiability.identified[k];
      const bool angle = id.kind == core::ParameterKind::link_theta || id.kind == core::ParameterKind::link_alpha ||
                         id.kind == core::ParameterKind::link_beta ||
                         (id.kind >= core::ParameterKind::base_rx && id.kind <= core::ParameterKind::base_rz) ||
                         id.kind >= core::ParameterKind::tool_rx;
      const double s = angle ? kDegPerRad : 1e3;
      const auto i = static_cast<Eigen::Index>(k);
      char line[160];
      std::snprintf(line, sizeof line, "  %-10s %12.5f %-4s %10.5f %s\n", model::parameter_name(id).c_str(),
                    r.change(i) * s, angle ? "deg" : "mm", r.stddev(i) * s, angle ? "deg" : "mm");
      out << line;
    }
  }
  out.precision(4);
  out << "residuals (measurements used): mean " << r.residuals.mean_m * 1e3 << " mm, rms " << r.residuals.rms_m * 1e3
      << " mm, max " << r.residuals.max_m * 1e3 << " mm";
  if (r.residuals.has_orientation)
    out << "; orientation mean " << r.residuals.mean_rad * kDegPerRad << " deg, rms "
        << r.residuals.rms_rad * kDegPerRad << " deg, max " << r.residuals.max_rad * kDegPerRad << " deg";
  out << '\n';
  return out.str();
}

}  // namespace kincal::identify

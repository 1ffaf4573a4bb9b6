#include "host/identify/identify.hpp"

#include <ceres/ceres.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <memory>
#include <numbers>
#include <random>
#include <sstream>

#include "host/identify/cpa.hpp"
#include "host/identify/measured_point.hpp"
#include "host/identify/model_selection.hpp"
#include "host/identify/sag.hpp"
#include "host/identify/statistics.hpp"
#include "host/model/axes.hpp"
#include "host/model/isometry.hpp"
#include "host/model/reading_coverage.hpp"

namespace kincal::identify {

namespace {

using model::InputError;

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

class RowCost final : public ceres::CostFunction {
 public:
  RowCost(Parameterization& p, const model::Measurement& m, const Matrix6& l, int size)
      : p_(p), m_(m), l_(l), size_(size) {
    set_num_residuals(size);
    mutable_parameter_block_sizes()->push_back(p.size());
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    p_.set(std::span<const double>(parameters[0], static_cast<std::size_t>(p_.size())));
    const bool want = jacobians != nullptr && jacobians[0] != nullptr;
    Eigen::MatrixXd j;
    row_residual(p_, m_, l_, size_, residuals, want ? &j : nullptr);
    if (want) {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(jacobians[0], size_,
                                                                                         p_.size()) = j;
    }
    return true;
  }

 private:
  Parameterization& p_;
  const model::Measurement& m_;
  Matrix6 l_;
  int size_;
};

// The priors' whitened residuals w_k (delta_k - c_k) (w = 1 / sigma, 0 for none; c the prior's
// centre: the nominal in the start's parameters).
class PriorCost final : public ceres::CostFunction {
 public:
  PriorCost(const Eigen::VectorXd& w, const Eigen::VectorXd& centre) : w_(w), centre_(centre) {
    set_num_residuals(static_cast<int>(w.size()));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(w.size()));
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Index p = w_.size();
    Eigen::Map<Eigen::VectorXd>(residuals, p) =
        w_.cwiseProduct(Eigen::Map<const Eigen::VectorXd>(parameters[0], p) - centre_);
    if (jacobians != nullptr && jacobians[0] != nullptr)
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(jacobians[0], p, p) =
          w_.asDiagonal();
    return true;
  }

 private:
  Eigen::VectorXd w_, centre_;
};

// Appends the prior rows (already whitened: w_k (delta_k - c_k), d/d(delta) = w_k e_k) of the
// parameters with a prior below the rows of a linearization e + J d.
void append_prior(const Eigen::VectorXd& w, const Eigen::VectorXd& centre, std::span<const double> delta,
                  Eigen::VectorXd& e, Eigen::MatrixXd& j) {
  std::vector<Eigen::Index> with;
  for (Eigen::Index k = 0; k < w.size(); ++k)
    if (w(k) > 0.0) with.push_back(k);
  const Eigen::Index at = e.size(), count = static_cast<Eigen::Index>(with.size());
  e.conservativeResize(at + count);
  j.conservativeResize(at + count, Eigen::NoChange);
  j.bottomRows(count).setZero();
  for (Eigen::Index m = 0; m < count; ++m) {
    const Eigen::Index k = with[static_cast<std::size_t>(m)];
    e(at + m) = w(k) * (delta[static_cast<std::size_t>(k)] - centre(k));
    j(at + m, k) = w(k);
  }
}

std::vector<int> all_rows(const model::Dataset& data) {
  std::vector<int> rows(data.rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) rows[i] = static_cast<int>(i);
  return rows;
}

// The model-error variance components s_p^2 (m^2) and s_o^2 (rad^2).
struct Components {
  double position2 = 0.0;
  double orientation2 = 0.0;
};

// The smallest variance a component takes (it stays positive so the weights stay finite).
constexpr double kVarianceFloor = 1e-20;

// Weights of the noise model V_i = instrument_i + diag(s_p^2 I, s_o^2 I) (instrument_i the row's
// 6 x 6, problem.hpp: full where the row has a pose covariance).
Weights noise_weights(const std::vector<Matrix6>& instrument, const Components& c, bool orientation_used) {
  return covariance_weights(instrument, orientation_used ? 6 : 3, c.position2, c.orientation2);
}

// Unwhitened residuals e and Jacobian J of the rows at the current point (r(d) ~ e + J d).
void linearize(const Parameterization& p, const model::Dataset& data, const std::vector<int>& rows,
               bool orientation_used, Eigen::VectorXd& e, Eigen::MatrixXd& j) {
  stacked(p, data, unit_weights(data.rows.size(), orientation_used ? 6 : 3), rows, e, &j);
}

// The weighted linear fit of e + J d at weights w: whitened residuals after the step, the thin Q
// and R of the whitened Jacobian (the hat matrix is Q Q^T).
struct WhitenedFit {
  Eigen::VectorXd residual;
  Eigen::MatrixXd q;
  Eigen::MatrixXd r;
};

WhitenedFit whitened_fit(const Eigen::VectorXd& e, const Eigen::MatrixXd& j, const Weights& w,
                         const std::vector<int>& rows, int size) {
  Eigen::VectorXd ew = e;
  Eigen::MatrixXd jw = j;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const auto at = static_cast<Eigen::Index>(k) * size;
    const auto l = w.factor[static_cast<std::size_t>(rows[k])].topLeftCorner(size, size).triangularView<Eigen::Lower>();
    ew.segment(at, size) = l * e.segment(at, size);
    jw.middleRows(at, size) = l * j.middleRows(at, size);
  }
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(jw);
  WhitenedFit f;
  f.r = qr.matrixQR().topRows(jw.cols()).triangularView<Eigen::Upper>();
  // Q = J_w R^-1 (a blocked triangular solve, cheaper than accumulating the Householder
  // reflections), unless R is too near singular for that to be accurate.
  const Eigen::VectorXd diagonal = f.r.diagonal().cwiseAbs();
  if (diagonal.size() == 0 || diagonal.minCoeff() > 1e-8 * diagonal.maxCoeff()) {
    f.q = std::move(jw);
    f.r.triangularView<Eigen::Upper>().solveInPlace<Eigen::OnTheRight>(f.q);
  } else {
    f.q = qr.householderQ() * Eigen::MatrixXd::Identity(jw.rows(), jw.cols());
  }
  f.residual = ew - f.q * (f.q.transpose() * ew);
  return f;
}

// REML for the model-error components at a fixed linearization (see identify.hpp), by Fisher
// scoring: g_k = (r^T V^-1 V_k V^-1 r - tr(V_k P)) / 2, F_kl = tr(V_k P V_l P) / 2, evaluated per
// row block with whitened residuals and the thin Q of the whitened Jacobian (H = Q Q^T; with
// M_k = L V_k L^T block-diagonal, tr(V_k P V_l P) = tr(M_k M_l) - 2 tr(Q^T M_k M_l Q) +
// tr(Q^T M_k Q Q^T M_l Q)). V_p = diag(I, 0) and V_o = diag(0, I) per row; L mixes them where a
// row's covariance ties its position to its rotation.
// Rows of e and j below the data's are the prior's (append_prior: whitened, of known variance, no
// component loads them): part of the fit, so the hat-matrix correction counts the degrees of
// freedom the prior lets the parameters take, not all of them (identify passes them from its
// second noise pass on, see there).
// A step is cut at a hundredth of the current value, so the boundary at zero is approached
// geometrically; a component below negligible2 (1e-6 of the instrument's variance) has reached
// zero for every practical purpose and stays there.
Components reml(const Eigen::VectorXd& e, const Eigen::MatrixXd& j, const std::vector<int>& rows,
                const std::vector<Matrix6>& instrument, double orientation_given2, Components c, bool estimate_position,
                bool estimate_orientation, int size, double negligible_position2) {
  const bool orientation_used = size == 6;
  const Eigen::Index p = j.cols();
  const double negligible_orientation2 = 1e-6 * orientation_given2;
  for (int iteration = 0; iteration < 100; ++iteration) {
    const Weights w = noise_weights(instrument, c, orientation_used);
    const WhitenedFit f = whitened_fit(e, j, w, rows, size);
    const int components = orientation_used ? 2 : 1;
    Eigen::Vector2d num = Eigen::Vector2d::Zero(), trace = Eigen::Vector2d::Zero();
    Eigen::Matrix2d trace_mm = Eigen::Matrix2d::Zero(), trace_qmmq = Eigen::Matrix2d::Zero();
    std::array<Eigen::MatrixXd, 2> qmq{Eigen::MatrixXd::Zero(p, p), Eigen::MatrixXd::Zero(p, p)};
    std::array<Eigen::MatrixXd, 2> mk, mkq;  // a row block of M_k and M_k Q
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const auto at = static_cast<Eigen::Index>(k) * size;
      const Eigen::MatrixXd l = w.factor[static_cast<std::size_t>(rows[k])].topLeftCorner(size, size);
      const auto q = f.q.middleRows(at, size);
      const auto r = f.residual.segment(at, size);
      for (int a = 0; a < components; ++a) {
        const auto s = static_cast<std::size_t>(a);
        mk[s] = l.middleCols(3 * a, 3) * l.middleCols(3 * a, 3).transpose();
        mkq[s] = mk[s] * q;
        num(a) += r.dot(mk[s] * r);
        trace(a) += mk[s].trace() - mkq[s].cwiseProduct(q).sum();
        qmq[s] += q.transpose() * mkq[s];
      }
      for (int a = 0; a < components; ++a)
        for (int b = 0; b < components; ++b) {
          const auto sa = static_cast<std::size_t>(a), sb = static_cast<std::size_t>(b);
          trace_mm(a, b) += mk[sa].cwiseProduct(mk[sb]).sum();
          trace_qmmq(a, b) += mkq[sa].cwiseProduct(mkq[sb]).sum();
        }
    }
    const std::array<bool, 2> active{estimate_position && c.position2 > negligible_position2,
                                     estimate_orientation && c.orientation2 > negligible_orientation2};
    Eigen::Vector2d g = 0.5 * (num - trace);
    Eigen::Matrix2d fisher;
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b)
        fisher(a, b) = 0.5 * (trace_mm(a, b) - 2.0 * trace_qmmq(a, b) +
                              qmq[static_cast<std::size_t>(a)].cwiseProduct(qmq[static_cast<std::size_t>(b)]).sum());
    for (int m = 0; m < 2; ++m) {
      if (active[static_cast<std::size_t>(m)]) continue;
      g(m) = 0.0;
      fisher.row(m).setZero();
      fisher.col(m).setZero();
      fisher(m, m) = 1.0;
    }
    const Eigen::Vector2d step = fisher.ldlt().solve(g);
    const Eigen::Vector2d now(c.position2, c.orientation2);
    Eigen::Vector2d next = now;
    for (int m = 0; m < 2; ++m)
      if (active[static_cast<std::size_t>(m)]) next(m) = std::max({now(m) + step(m), 0.01 * now(m), kVarianceFloor});
    c = {next(0), next(1)};
    if (((next - now).array().abs() <= 1e-6 * now.array()).all()) break;
  }
  return c;
}

struct SolveSummary {
  int iterations = 0;
  std::string termination;
};

// Plain least squares: outliers are handled by the leverage-aware rejection (a robust loss
// would bias the variance components the noise model estimates from the same residuals). Within
// the physical bounds `bounds` (problem.hpp), which `delta` must meet on entry.
SolveSummary solve_ceres(Parameterization& p, const model::Dataset& data, const Weights& w,
                         const std::vector<int>& rows, const Eigen::VectorXd& prior_weight,
                         const Eigen::VectorXd& prior_centre, const PhysicalBounds& bounds, int max_iterations,
                         std::vector<double>& delta) {
  ceres::Problem problem;
  for (int r : rows) {
    const auto k = static_cast<std::size_t>(r);
    problem.AddResidualBlock(new RowCost(p, data.rows[k], w.factor[k], w.size), nullptr, delta.data());
  }
  if ((prior_weight.array() > 0.0).any())
    problem.AddResidualBlock(new PriorCost(prior_weight, prior_centre), nullptr, delta.data());
  for (Eigen::Index k = 0; k < bounds.lower.size(); ++k) {
    if (std::isfinite(bounds.lower(k)))
      problem.SetParameterLowerBound(delta.data(), static_cast<int>(k), bounds.lower(k));
    if (std::isfinite(bounds.upper(k)))
      problem.SetParameterUpperBound(delta.data(), static_cast<int>(k), bounds.upper(k));
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

// Parses --fix / --params entries (parameter_entry_ids).
ParameterIds parse_names(const std::vector<std::string>& names, const RobotModel& m) {
  ParameterIds ids;
  for (const std::string& name : names) {
    const ParameterIds entry = parameter_entry_ids(name, m.joint_count());
    ids.insert(ids.end(), entry.begin(), entry.end());
  }
  return ids;
}

bool same_id(core::ParameterId a, core::ParameterId b) {
  return a.kind == b.kind &&
         ((a.kind > core::ParameterKind::link_beta && !model::is_joint_map_parameter(a.kind)) || a.link == b.link);
}

bool contains(const ParameterIds& ids, core::ParameterId id) {
  return std::any_of(ids.begin(), ids.end(), [&](core::ParameterId x) { return same_id(x, id); });
}

// Refuses data that cannot calibrate the model; notes each joint that never moved.
void check_data(const RobotModel& m, const model::Dataset& data, std::vector<std::string>& notes) {
  model::check_joint_count(m, data.joint_count, data.source);
  if (data.rows.empty()) throw InputError(data.source + ": no measurements");
  for (const int j : still_joints(data)) {
    std::ostringstream msg;
    msg << data.source << ": joint " << j + 1 << " (" << m.joints[static_cast<std::size_t>(j)].name
        << ") never moved: every row has q" << j + 1 << " = " << data.rows[0].q[static_cast<std::size_t>(j)]
        << "; what only its motion shows is held at the nominal, and the model is calibrated for that reading of "
           "it alone (move it in the data to calibrate its axis)";
    notes.push_back(msg.str());
  }
}

// Identifiability over random configurations within the limits (revolute joints without
// limits: [-pi, pi]; prismatic: [-1, 1] m): what no choice of configurations can improve on.
// Three equations per candidate and at least 20 configurations reach the generic rank with a
// wide margin (the structural rank needs only as many equations as parameters).
Identifiability structural_identifiability(const RobotModel& m, const ParameterIds& candidates, bool orientation) {
  std::mt19937_64 rng(12345);
  const int rows = orientation ? 6 : 3;
  const int count = std::max(20, (3 * static_cast<int>(candidates.size()) + rows - 1) / rows);
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

// A model whose base is far from the data (metres: a placeholder for the device-to-robot
// registration, as in a laser tracker's frame) starts the solver far from the answer. The rigid
// motion that best maps the model's tool points onto the measured ones (Umeyama, no scale) is
// composed into the base first; the solve then refines it with everything else.
void register_base(RobotModel& start, const model::Dataset& data, std::vector<std::string>& notes) {
  const auto n = static_cast<Eigen::Index>(data.rows.size());
  Eigen::Matrix3Xd model_points(3, n), measured(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const model::Measurement& row = data.rows[static_cast<std::size_t>(i)];
    model_points.col(i) = model::forward_kinematics(start, row.q).translation;
    measured.col(i) = row.position;
  }
  const auto rms = [&](const Eigen::Matrix3Xd& points) {
    return std::sqrt((points - measured).colwise().squaredNorm().mean());
  };
  const double before = rms(model_points);
  if (n < 3 || before < 0.05) return;
  const Eigen::Matrix4d t = Eigen::umeyama(model_points, measured, false);
  const Eigen::Matrix3Xd moved = (t.topLeftCorner<3, 3>() * model_points).colwise() + t.topRightCorner<3, 1>();
  const double after = rms(moved);
  if (!(after < 0.5 * before)) return;
  model::Transform device_T_device;
  device_T_device.rotation = t.topLeftCorner<3, 3>();
  device_T_device.translation = t.topRightCorner<3, 1>();
  start.base_T_frame0 = device_T_device * start.base_T_frame0;
  std::ostringstream note;
  note.setf(std::ios::fixed);
  note.precision(1);
  note << "the model's base was " << before * 1e3 << " mm RMS from the data; registered first (rigid fit of the "
       << "tool points: " << after * 1e3 << " mm RMS), the base changes below are from there";
  notes.push_back(note.str());
}

// A frame tool whose orientation is far from the data's (a 6-DoF probe or a board mounted any way
// round: tens of degrees, where the solver can settle with orientation and position pulling
// apart): the turn of the tool that best maps the model's tool orientations onto the measured
// ones at the registered base (the chordal mean of R_model^T R_measured, projected on the
// rotations) is composed into the tool first. The tool's origin stays, so the base's registration
// holds.
void register_tool_turn(RobotModel& start, const model::Dataset& data, std::vector<std::string>& notes) {
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  std::vector<std::pair<Eigen::Matrix3d, Eigen::Matrix3d>> pairs;  // model's, measured
  for (const model::Measurement& row : data.rows)
    if (row.orientation) {
      pairs.emplace_back(model::forward_kinematics(start, row.q).rotation, row.orientation->toRotationMatrix());
      sum += pairs.back().first.transpose() * pairs.back().second;
    }
  const auto rms_deg = [&](const Eigen::Matrix3d& turn) {
    double sum2 = 0.0;
    for (const auto& [model_r, measured] : pairs) {
      const double a = Eigen::AngleAxisd(model_r * turn * measured.transpose()).angle();
      sum2 += a * a;
    }
    return std::sqrt(sum2 / static_cast<double>(pairs.size())) * kDegPerRad;
  };
  if (pairs.size() < 2) return;
  const double before = rms_deg(Eigen::Matrix3d::Identity());
  if (before < 5.0) return;
  const Eigen::Matrix3d turn = model::nearest_rotation(sum);
  const double after = rms_deg(turn);
  if (!(after < 0.5 * before)) return;
  start.flange_T_tool.rotation = start.flange_T_tool.rotation * turn;
  std::ostringstream note;
  note.setf(std::ios::fixed);
  note.precision(1);
  note << "the model's tool frame was " << before << " deg RMS from the data's orientations; turned first by "
       << Eigen::AngleAxisd(turn).angle() * kDegPerRad << " deg (" << after
       << " deg RMS), the tool changes below are from there";
  notes.push_back(note.str());
}

// Both registrations above, the tool's turn when the solve uses orientations and may turn the tool.
void register_start(RobotModel& start, const model::Dataset& data, bool turn_tool, std::vector<std::string>& notes) {
  register_base(start, data, notes);
  if (turn_tool) register_tool_turn(start, data, notes);
}

// Whether the tool's orientation is the solve's to change: the data's orientations are used and
// no --fixed entry holds a tool turn.
bool tool_turn_free(const IdentifyOptions& options, bool orientation_used, int joint_count) {
  if (!orientation_used) return false;
  for (const std::string& entry : options.fixed)
    for (const core::ParameterId& id : parameter_entry_ids(entry, joint_count))
      if (id.kind >= core::ParameterKind::tool_rx && id.kind <= core::ParameterKind::tool_rz) return false;
  return true;
}

// The nominal in the start's parameters, for a start that is not the nominal (cpa's fit): the
// change of the start that best reproduces the nominal's tool poses (reparameterized and
// registered as a nominal start would be) at the data's configurations, by the same solver. The
// priors are centred there: the maker's tolerance is about the nominal, whatever the solve starts
// from (a prior centred on cpa's fit would count the data twice).
Eigen::VectorXd nominal_in_start(const RobotModel& nominal, const model::Dataset& data, const IdentifyOptions& options,
                                 const Parameterization& param, bool registered, bool orientation_used,
                                 std::vector<std::string>& notes) {
  RobotModel reference = reparameterize_for_identification(nominal, options.parallel_tolerance_rad, nullptr);
  std::vector<std::string> unused;
  if (registered)
    register_start(reference, data, tool_turn_free(options, orientation_used, nominal.joint_count()), unused);
  model::Dataset poses = data;
  for (model::Measurement& row : poses.rows) {
    const Transform pose = model::forward_kinematics(reference, row.q);
    row.position = pose.translation;
    row.orientation.reset();
    if (orientation_used) row.orientation = Eigen::Quaterniond(pose.rotation);
  }
  // Metres, and radians as metres (a 1 m lever).
  const Weights unit = unit_weights(poses.rows.size(), orientation_used ? 6 : 3);
  Parameterization fit(param.start(), param.ids());
  std::vector<double> delta(static_cast<std::size_t>(fit.size()), 0.0);
  const Eigen::VectorXd none = Eigen::VectorXd::Zero(fit.size());
  solve_ceres(fit, poses, unit, all_rows(poses), none, none, physical_bounds(fit, options.negative_masses),
              options.max_iterations, delta);
  std::ostringstream note;
  note.precision(3);
  note << "priors centred on the nominal: the start is not the nominal; the nominal in the start's parameters "
          "reproduces its tool points to "
       << std::fixed << accuracy(fit.model(), poses).rms_m * 1e3 << " mm RMS over the data's configurations";
  notes.push_back(note.str());
  return Eigen::Map<const Eigen::VectorXd>(delta.data(), fit.size());
}

}  // namespace

AccuracyStats accuracy(const RobotModel& m, const model::Dataset& data, const std::vector<int>& rows_in) {
  const std::vector<int> rows = rows_in.empty() ? all_rows(data) : rows_in;
  const bool orientation = data.has_orientation && m.tool == model::ToolKind::frame;
  std::vector<double> positions_m, angles_rad;
  for (int r : rows) {
    const model::Measurement& row = data.rows[static_cast<std::size_t>(r)];
    const Transform pose = model::forward_kinematics(m, row.q);
    positions_m.push_back((pose.translation - row.position).norm());
    if (orientation)
      angles_rad.push_back(
          row.orientation ? so3_log(row.orientation->toRotationMatrix() * pose.rotation.transpose()).norm() : 0.0);
  }
  AccuracyStats s = error_stats(positions_m, angles_rad);
  s.has_orientation = orientation;
  return s;
}

AccuracyStats error_stats(std::span<const double> positions_m, std::span<const double> angles_rad) {
  AccuracyStats s;
  s.count = static_cast<int>(positions_m.size());
  if (s.count == 0) return s;
  const auto summarize = [count = s.count](std::span<const double> e, double& mean, double& rms, double& max) {
    double sum = 0, sum2 = 0;
    for (const double v : e) {
      sum += v;
      sum2 += v * v;
      max = std::max(max, v);
    }
    mean = sum / count;
    rms = std::sqrt(sum2 / count);
  };
  summarize(positions_m, s.mean_m, s.rms_m, s.max_m);
  s.has_orientation = !angles_rad.empty();
  if (s.has_orientation) summarize(angles_rad, s.mean_rad, s.rms_rad, s.max_rad);
  return s;
}

Eigen::Matrix3d prediction_covariance(const IdentifyResult& r, std::span<const double> q) {
  Parameterization p(r.start, r.identifiability.identified);
  p.set(std::span<const double>(r.change.data(), static_cast<std::size_t>(r.change.size())));
  Eigen::MatrixXd j;
  (void)p.pose(q, &j);
  const Eigen::MatrixXd jp = j.topRows(3);
  return jp * r.covariance * jp.transpose() +
         Eigen::Matrix3d::Identity() * r.model_error_position_m * r.model_error_position_m;
}

// Candidates in order of preference: base, tool, then link by link (theta, d, a, alpha, beta).
ParameterIds parameter_entry_ids(const std::string& name, int joint_count) {
  if (name != "base" && name != "tool") return {model::parse_parameter_name(name, joint_count)};
  const int first = static_cast<int>(name == "base" ? core::ParameterKind::base_x : core::ParameterKind::tool_x);
  ParameterIds ids;
  for (int k = 0; k < 6; ++k) ids.push_back({static_cast<core::ParameterKind>(first + k), 0});
  return ids;
}

ParameterIds candidate_parameters(const RobotModel& m) {
  const ParameterIds all = model::all_parameters(m);
  ParameterIds out;
  for (const auto& id : all)
    if (model::is_base_parameter(id.kind)) out.push_back(id);
  for (const auto& id : all)
    if (id.kind >= core::ParameterKind::tool_x && !model::is_joint_map_parameter(id.kind)) out.push_back(id);
  for (const auto& id : all)
    if (id.kind <= core::ParameterKind::link_beta) out.push_back(id);
  for (const auto& id : all)
    if (model::is_joint_map_parameter(id.kind)) out.push_back(id);
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
  // Frame n moved on the last body: the flange (robot_model.hpp) keeps its place on that body.
  const Transform frame_n = tool * m.flange_T_tool.inverse();
  const Transform frame_n_rewritten = model::forward_kinematics(rewritten, zero) * rewritten.flange_T_tool.inverse();
  rewritten.frame_n_T_flange = frame_n_rewritten.inverse() * frame_n * m.frame_n_T_flange;
  return rewritten;
}

namespace {

// identify() without the rejection gate. When the test rejected rows and `unrejected` is given, it
// receives the fit before the first rejection round finished as the result: what options.robust =
// false gives (the same solves, so the gate need not solve it again).
IdentifyResult identify_ungated(const RobotModel& nominal, const model::Dataset& data, const IdentifyOptions& options,
                                IdentifyResult* unrejected = nullptr) {
  IdentifyResult result;
  check_data(nominal, data, result.notes);
  const int n = nominal.joint_count();

  // Noise: the instrument's (from the data, or given) plus the model error (estimated).
  const bool all_covariance = std::all_of(data.rows.begin(), data.rows.end(),
                                          [](const model::Measurement& r) { return r.covariance.has_value(); });
  const bool all_pose_covariance = std::all_of(
      data.rows.begin(), data.rows.end(), [](const model::Measurement& r) { return r.pose_covariance.has_value(); });
  result.all_covariance = all_covariance;
  result.sigma_m = options.sigma_m > 0.0 ? options.sigma_m : 0.0;
  result.orientation_used = data.has_orientation && nominal.tool == model::ToolKind::frame;
  result.orientation_sigma_rad = options.orientation_sigma_rad > 0.0 ? options.orientation_sigma_rad : 0.0;
  const bool estimate_position = options.model_error || !(all_covariance || result.sigma_m > 0.0);
  const bool estimate_orientation =
      result.orientation_used && (options.model_error || !(result.orientation_sigma_rad > 0.0));
  result.model_error_estimated = estimate_position || estimate_orientation;
  const std::vector<Matrix6> instrument = instrument_covariances(data, result.sigma_m, result.orientation_sigma_rad);
  {
    std::vector<double> sigmas;
    for (const Matrix6& c : instrument) sigmas.push_back(std::sqrt(c.topLeftCorner<3, 3>().trace() / 3.0));
    result.median_instrument_sigma_m = median(sigmas);
  }
  if (data.has_orientation && nominal.tool == model::ToolKind::point)
    result.notes.push_back("the data has orientations but the model's tool is a point: positions only");

  if (options.method == Method::cpa || options.start == Start::cpa) {
    CpaOptions cpa_options;
    cpa_options.sigma_m = options.sigma_m;
    cpa_options.parallel_tolerance_rad = options.parallel_tolerance_rad;
    const CpaResult cpa = circle_point_analysis(nominal, data, cpa_options);
    for (const SweepFit& f : cpa.fits) result.cpa_sweeps.push_back(describe(f));
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
      record.reading_ranges = model::reading_ranges(data);
      result.model.calibration = record;
      return result;
    }
    result.start = reparameterize_for_identification(cpa.model, options.parallel_tolerance_rad, &result.notes);
  } else {
    result.start = reparameterize_for_identification(nominal, options.parallel_tolerance_rad, &result.notes);
  }
  const bool base_free = std::none_of(options.fixed.begin(), options.fixed.end(),
                                      [](const std::string& f) { return f.starts_with("base"); });
  if (base_free && options.requested.empty())
    register_start(result.start, data, tool_turn_free(options, result.orientation_used, n), result.notes);
  const Transform tool_before_estimate = result.start.flange_T_tool;  // the record's tool changes are from here
  result.start = with_estimated_measured_point(result.start, data, options, result.orientation_used, result.notes);

  const double orientation_given2 = result.orientation_sigma_rad * result.orientation_sigma_rad;
  // Start: 1 mm and 1 mrad of model error (the scale of real arms), refined from the residuals.
  Components components{estimate_position ? 1e-6 : 0.0, estimate_orientation ? 1e-6 : 0.0};
  Weights weights = noise_weights(instrument, components, result.orientation_used);
  const int size = weights.size;

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
  const std::vector<HeldFixed> unloaded =
      requested.empty() ? unloaded_compliances(result.start, data, candidates) : std::vector<HeldFixed>{};
  for (const HeldFixed& h : unloaded)
    candidates.erase(
        std::find_if(candidates.begin(), candidates.end(), [&](core::ParameterId id) { return same_id(id, h.id); }));
  for (const auto& id : candidates)
    if (id.kind >= core::ParameterKind::tool_rx && !model::is_joint_map_parameter(id.kind) &&
        result.start.tool == model::ToolKind::point)
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
  result.identifiability.held_fixed.insert(result.identifiability.held_fixed.end(), unloaded.begin(), unloaded.end());
  if (!requested.empty() && !result.identifiability.held_fixed.empty()) {
    std::string what;
    for (const HeldFixed& h : result.identifiability.held_fixed)
      what += "\n  " + model::parameter_name(h.id) + ": " + h.reason;
    throw InputError(data.source + ": the data cannot identify the requested parameters:" + what);
  }
  for (const std::string& name : options.fixed) {
    const auto because = options.fixed_because.find(name);
    const std::string reason = because == options.fixed_because.end() ? "fixed on request" : because->second;
    for (const auto& id : parameter_entry_ids(name, result.start.joint_count()))
      result.identifiability.held_fixed.push_back({id, reason});
  }
  const ParameterIds& ids = result.identifiability.identified;
  const int p = static_cast<int>(ids.size());
  const int p_structural = static_cast<int>(structural.identified.size());
  const int equations = static_cast<int>(data.rows.size()) * (result.orientation_used ? 6 : 3);
  const int needed = p_structural + (estimate_position ? 1 : 0) + (estimate_orientation ? 1 : 0);
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
  const GravityLoads loads = compliance_prior_loads(result.start, data);
  const std::vector<bool> given = given_centres(result.start);
  const Eigen::VectorXd default_sigma = prior_sigmas(options.prior, ids, n, "prior", loads, given);
  result.prior_sigma = default_sigma;
  result.prior_scales = initial_prior_scales(options.prior, ids, n, loads, given);
  result.prior_centre = Eigen::VectorXd::Zero(p);
  if (options.start == Start::cpa && options.prior.strength > 0.0)
    result.prior_centre = nominal_in_start(nominal, data, options, param, base_free && options.requested.empty(),
                                           result.orientation_used, result.notes);
  // A compliance's prior is on the deflection itself, centred on a rigid joint whatever the start
  // (a model file's value, the sag's first stage: prior.hpp).
  for (int k = 0; k < p; ++k)
    if (ids[static_cast<std::size_t>(k)].kind == model::kJointCompliance)
      result.prior_centre(k) = -result.start.joints.at(ids[static_cast<std::size_t>(k)].link).compliance.value_or(0.0);
  Eigen::VectorXd prior_weight = prior_weights(options.prior, result.prior_sigma);
  const double negligible_position2 = 1e-6 * result.median_instrument_sigma_m * result.median_instrument_sigma_m;

  // Solve, estimate the model error from the residuals (REML) and the priors' widths
  // (prior_scale.hpp), re-weight, until both settle.
  const auto fit = [&] {
    PriorScales two_passes_ago;
    bool damped = false;  // the widths' estimates cycled: each update goes half way from then on
    for (int pass = 0; pass < 20; ++pass) {
      weights = noise_weights(instrument, components, result.orientation_used);
      if (options.method == Method::first_order) {
        // Doty's eps = E psi, one weighted least-squares step at the nominal model.
        std::fill(delta.begin(), delta.end(), 0.0);
        param.set(delta);
        Eigen::VectorXd r;
        Eigen::MatrixXd j;
        stacked(param, data, weights, rows, r, &j);
        append_prior(prior_weight, result.prior_centre, delta, r, j);
        const Eigen::VectorXd step = j.colPivHouseholderQr().solve(-r);
        const PhysicalBounds bounds = physical_bounds(param, options.negative_masses);  // the step clamped to them
        for (int k = 0; k < p; ++k)
          delta[static_cast<std::size_t>(k)] = std::clamp(step(k), bounds.lower(k), bounds.upper(k));
        param.set(delta);
        result.iterations = 1;
        result.termination = "one linear step (first-order model)";
      } else {
        const SolveSummary s =
            solve_ceres(param, data, weights, rows, prior_weight, result.prior_centre,
                        physical_bounds(param, options.negative_masses), options.max_iterations, delta);
        result.iterations += s.iterations;
        result.termination = s.termination;
      }
      ++result.noise_passes;
      if (!result.model_error_estimated && !result.prior_scales.estimated) return;
      Components next = components;
      if (result.model_error_estimated) {
        Eigen::VectorXd e;
        Eigen::MatrixXd j;
        linearize(param, data, rows, result.orientation_used, e, j);
        // The prior's rows count once the data have chosen their widths (pass 0 has the defaults).
        // Without them a near-saturated fit left a component no degree of freedom: on a 10-row fold
        // of the zoo's SIA10F (60 equations, 52 parameters) the orientation's 0.3 set its model
        // error to 0, its rows outweighed the positions, and the solve ended 57 mm off on its own
        // training rows. At the default widths, a prior far narrower than the arm's deviations
        // passed its misfit to the model error: on 8 rows of a KR 210 with millimetres of error,
        // 4.7 mm of it, and the evidence then saw the lengths too little to widen their prior.
        if (pass > 0) append_prior(prior_weight, result.prior_centre, delta, e, j);
        next = reml(e, j, rows, instrument, orientation_given2, components, estimate_position, estimate_orientation,
                    size, negligible_position2);
      }
      PriorScales scales =
          update_prior_scales(param, delta, data, noise_weights(instrument, next, result.orientation_used), rows,
                              result.prior_centre, default_sigma, options.prior, result.prior_scales);
      damped = damped || (pass >= 2 && scales_moved(scales, result.prior_scales, 1e-3) &&
                          !scales_moved(scales, two_passes_ago, 1e-3));
      if (damped) scales = halfway_scales(result.prior_scales, scales);
      const auto moved = [](double a2, double b2) {
        return std::abs(std::sqrt(a2) - std::sqrt(b2)) > 1e-3 * std::sqrt(std::max(a2, b2));
      };
      const bool settled = !moved(next.position2, components.position2) &&
                           !moved(next.orientation2, components.orientation2) &&
                           !scales_moved(scales, result.prior_scales, 1e-3);
      components = next;
      two_passes_ago = result.prior_scales;
      result.prior_scales = scales;
      result.prior_sigma = scaled_sigmas(default_sigma, scales);
      prior_weight = prior_weights(options.prior, result.prior_sigma);
      if (settled) break;
      if (pass == 19) result.notes.push_back("the model-error and prior-width estimates did not settle in 20 passes");
    }
    weights = noise_weights(instrument, components, result.orientation_used);
  };
  fit();
  result.model_error_before_rejection_m = std::sqrt(components.position2);
  const IdentifyResult before_rejection = result;
  const std::vector<double> delta_before_rejection = delta;
  const Components components_before_rejection = components;

  // Outliers: studentized residuals against a robust scale, capped (see identify.hpp).
  const int total = static_cast<int>(data.rows.size());
  int cap = std::min(static_cast<int>(options.max_rejected_fraction * total), total - (needed + size - 1) / size);
  // Small sets: with fewer than 5 equations per parameter a row's residual cannot tell a blunder
  // from the model error the fit leaves where few rows see a direction (a sweep's ends); on the
  // simulated sagging sweep set (36 rows) rejection there cost held out.
  if (options.method == Method::full && options.robust && cap > 0 && equations < 5 * p) {
    cap = 0;
    result.notes.push_back("no outlier rejection: " + std::to_string(equations) + " equations for " +
                           std::to_string(p) +
                           " parameters (fewer than 5 per parameter cannot tell an outlier from the model error)");
  }
  for (int round = 0; options.method == Method::full && options.robust && round < 8; ++round) {
    const int room = cap - static_cast<int>(result.rejections.size());
    if (room <= 0) break;
    Eigen::VectorXd e;
    Eigen::MatrixXd j;
    // The test is against the data alone, without the prior rows: a row that carries the only
    // information on a direction (a sweep's end) would otherwise lose its leverage to the prior and
    // look like an outlier where the prior merely pulls (rejection then costs held out).
    linearize(param, data, rows, result.orientation_used, e, j);
    const WhitenedFit f = whitened_fit(e, j, weights, rows, size);
    std::vector<double> t(rows.size());
    std::vector<Eigen::VectorXd> scaled(rows.size());  // (I - H_ii)^-1 r_i
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const auto at = static_cast<Eigen::Index>(k) * size;
      const Eigen::MatrixXd q = f.q.middleRows(at, size);
      const Eigen::MatrixXd i_minus_h = Eigen::MatrixXd::Identity(size, size) - q * q.transpose();
      scaled[k] = i_minus_h.ldlt().solve(Eigen::VectorXd(f.residual.segment(at, size)));
      t[k] = f.residual.segment(at, size).dot(scaled[k]);
    }
    // At least a tenth of what V says: where a given instrument sigma overstates the noise
    // (noise-free data) the median goes to zero, and rounding must not become outliers.
    const double scale = std::max(0.1, median(t) / chi_square_quantile(0.5, size));
    const double threshold = chi_square_quantile(1.0 - options.outlier_probability / total, size);
    std::vector<std::size_t> over;
    for (std::size_t k = 0; k < rows.size(); ++k)
      if (t[k] > scale * threshold) over.push_back(k);
    if (over.empty()) break;
    std::sort(over.begin(), over.end(), [&](std::size_t a, std::size_t b) { return t[a] > t[b]; });
    // Only the clearly worst this round (within a factor 2 of the largest residual): a blunder
    // pulls the fit and inflates the scale, so its neighbours' residuals mean little until it is out.
    const double worst = t[over.front()];
    while (t[over.back()] < 0.25 * worst) over.pop_back();
    if (static_cast<int>(over.size()) > room) over.resize(static_cast<std::size_t>(room));
    std::vector<bool> drop(rows.size(), false);
    for (std::size_t k : over) {
      const auto at = static_cast<Eigen::Index>(k) * size;
      Rejection rejection;
      rejection.line = data.rows[static_cast<std::size_t>(rows[k])].line;
      rejection.id = model::id_suffix(data.rows[static_cast<std::size_t>(rows[k])]);
      rejection.residual_m = e.segment<3>(at).norm();
      rejection.statistic_ratio = t[k] / (scale * threshold);
      // Removing row k changes the parameters by R^-1 Q_k^T (I - H_kk)^-1 r_k (first order).
      const Eigen::VectorXd shift =
          f.r.triangularView<Eigen::Upper>().solve(Eigen::VectorXd(f.q.middleRows(at, size).transpose() * scaled[k]));
      for (std::size_t m = 0; m < rows.size(); ++m)
        rejection.tool_shift_max_m =
            std::max(rejection.tool_shift_max_m, (j.middleRows<3>(static_cast<Eigen::Index>(m) * size) * shift).norm());
      result.rejections.push_back(rejection);
      drop[k] = true;
    }
    std::vector<int> kept;
    for (std::size_t k = 0; k < rows.size(); ++k)
      if (!drop[k]) kept.push_back(rows[k]);
    rows = kept;
    fit();
  }
  // The statistics, the standard deviations and the calibration record of the fit at `at` with
  // the noise components `c` over the rows `used`.
  const auto finish = [&](IdentifyResult& out, const std::vector<double>& at, const Components& c,
                          const std::vector<int>& used) {
    for (const Rejection& x : out.rejections) out.outlier_lines.push_back(x.line);
    out.model_error_position_m = std::sqrt(c.position2);
    out.model_error_orientation_rad = std::sqrt(c.orientation2);
    param.set(at);

    // Standard deviations and the chi-square of the fit.
    Eigen::VectorXd r;
    Eigen::MatrixXd j;
    stacked(param, data, noise_weights(instrument, c, out.orientation_used), used, r, &j);
    {
      const Eigen::VectorXd w = prior_weights(options.prior, out.prior_sigma);  // the result's own widths
      const Eigen::MatrixXd info = j.transpose() * j + Eigen::MatrixXd(w.cwiseAbs2().asDiagonal());
      out.at_bound = on_bound(physical_bounds(param, options.negative_masses), at);
      std::vector<Eigen::Index> free;
      for (Eigen::Index k = 0; k < p; ++k)
        if (!out.at_bound[static_cast<std::size_t>(k)]) free.push_back(k);
      const Eigen::MatrixXd free_info = info(free, free);
      out.covariance = Eigen::MatrixXd::Zero(p, p);
      const Eigen::MatrixXd free_covariance =
          free_info.ldlt().solve(Eigen::MatrixXd::Identity(free_info.rows(), free_info.cols()));
      out.covariance(free, free) = free_covariance;
      out.stddev = out.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
      out.prior_share = out.covariance.diagonal().cwiseProduct(w.cwiseAbs2()).cwiseMin(1.0);
    }
    out.change = Eigen::Map<const Eigen::VectorXd>(at.data(), p);
    const double dof = static_cast<double>(r.size()) - p;
    out.chi_square_per_dof = dof > 0 ? r.squaredNorm() / dof : 0.0;
    out.model = param.model();
    out.model.name = nominal.name;
    out.residuals = accuracy(out.model, data, used);

    model::CalibrationRecord record;
    record.method = options.method == Method::first_order ? "first-order" : "full";
    if (options.start == Start::cpa && options.method == Method::full) record.method = "full (from cpa)";
    record.data = data.source;
    record.measurements = static_cast<int>(used.size());
    record.rms_residual_m = out.residuals.rms_m;
    record.reading_ranges = model::reading_ranges(data);
    const Eigen::Matrix<double, 6, 1> tool_change = small_motion(tool_before_estimate, out.model.flange_T_tool);
    for (int k = 0; k < p; ++k) {
      const core::ParameterId id = ids[static_cast<std::size_t>(k)];
      const bool tool = model::is_motion_parameter(id.kind) && id.kind >= core::ParameterKind::tool_x;
      const int t = static_cast<int>(id.kind) - static_cast<int>(core::ParameterKind::tool_x);
      record.parameters.push_back({model::parameter_name(id), tool ? tool_change(t) : out.change(k), out.stddev(k)});
    }
    for (int k = 1; k < p; ++k) {
      std::vector<double> row;
      for (int l = 0; l < k; ++l) {
        const double s = out.stddev(k) * out.stddev(l);
        row.push_back(s > 0.0 ? std::clamp(out.covariance(k, l) / s, -1.0, 1.0) : 0.0);
      }
      record.correlations.push_back(std::move(row));
    }
    // s_p and s_o are the model error only beside a known instrument noise; else they are the noise.
    if (out.all_covariance || out.sigma_m > 0.0) record.model_error_m = out.model_error_position_m;
    if (out.orientation_used && (out.orientation_sigma_rad > 0.0 || all_pose_covariance))
      record.model_error_rad = out.model_error_orientation_rad;
    for (const HeldFixed& h : out.identifiability.held_fixed) record.held_fixed.push_back(model::parameter_name(h.id));
    out.model.calibration = record;
  };
  finish(result, delta, components, rows);
  if (unrejected != nullptr && !result.rejections.empty()) {
    *unrejected = before_rejection;
    finish(*unrejected, delta_before_rejection, components_before_rejection, all_rows(data));
  }
  (void)n;
  return result;
}

// How many standard errors rejection must lower the K-fold errors by (see identify.hpp).
constexpr double kGateT = 2.0;

// identify() with the rejection gate; `with_rule`: its cross-validation with the rule when the
// caller has it (model selection's), else computed here.
IdentifyResult gated(const RobotModel& nominal, const model::Dataset& data, const IdentifyOptions& options,
                     const CrossValidation* with_rule) {
  if (needs_sag_start(nominal, options)) {
    // Masses to identify and no compliance yet (sag.hpp): stage 1, then the rest from its compliances
    // (and stage 3 when a mass went below 0; again from the gravity found when it loads a compliance
    // the start held as unloaded, and stage 3 after it when needed).
    const SagStage second = second_sag_stage(
        nominal, options, identify_ungated(nominal, data, first_sag_stage(nominal, options)).model, data);
    SagStage stage = second;
    IdentifyResult r = gated(stage.model, data, stage.options, with_rule);
    std::string note = stage.note;
    const auto next = [&](const std::optional<SagStage>& then) {
      if (!then) return false;
      stage = *then;
      r = gated(stage.model, data, stage.options, with_rule);
      note += "; " + stage.note;
      return true;
    };
    next(third_sag_stage(stage, r));
    if (next(tilted_sag_stage(stage, r, data))) next(third_sag_stage(stage, r));
    finish_sag_result(r, nominal);
    r.notes.push_back(note);
    return r;
  }
  IdentifyResult unrejected;
  IdentifyResult result = identify_ungated(nominal, data, options, options.rejection_gate ? &unrejected : nullptr);
  if (!options.rejection_gate || result.rejections.empty()) return result;
  IdentifyOptions without = options;
  without.robust = false;
  // Both cross-validations side by side when the caller has neither.
  std::vector<Candidate> to_validate{Candidate{"without", "", nominal, without}};
  if (with_rule == nullptr) to_validate.push_back(Candidate{"with", "", nominal, options});
  std::vector<CrossValidation> validated = cross_validate(to_validate, data);
  const CrossValidation without_cv = std::move(validated.front());
  const CrossValidation with_cv = with_rule != nullptr ? *with_rule : std::move(validated.back());
  if (with_cv.kfold_rms_m < 0.0 || without_cv.kfold_rms_m < 0.0) {
    result.notes.push_back("rejection gate: cross-validation cannot judge the rejections (" +
                           (with_cv.why.empty() ? without_cv.why : with_cv.why) + "); they stand");
    return result;
  }
  RejectionGate gate;
  gate.judged = true;
  gate.kfold_with_m = with_cv.kfold_rms_m;
  gate.kfold_without_m = without_cv.kfold_rms_m;
  gate.kfold_t = paired_t(with_cv.kfold_error2, without_cv.kfold_error2);
  if (with_cv.out_of_range_rms_m >= 0.0 && without_cv.out_of_range_rms_m >= 0.0) {
    gate.out_of_range_with_m = with_cv.out_of_range_rms_m;
    gate.out_of_range_without_m = without_cv.out_of_range_rms_m;
  }
  gate.kept = gate.kfold_t <= -kGateT && gate.out_of_range_with_m <= gate.out_of_range_without_m;
  if (!gate.kept) {
    gate.undone = std::move(result.rejections);
    result = std::move(unrejected);
  }
  result.rejection_gate = std::move(gate);
  return result;
}

}  // namespace

IdentifyResult identify(const RobotModel& nominal, const model::Dataset& data, const IdentifyOptions& options) {
  return gated(nominal, data, options, nullptr);
}

std::vector<int> still_joints(const model::Dataset& data) {
  std::vector<int> out;
  const std::vector<std::array<double, 2>> ranges = model::reading_ranges(data);
  for (std::size_t j = 0; j < ranges.size(); ++j)
    if (ranges[j][0] == ranges[j][1]) out.push_back(static_cast<int>(j));
  return out;
}

IdentifyResult identify(const RobotModel& nominal, const model::Dataset& data, const IdentifyOptions& options,
                        const CrossValidation& with_rule) {
  return gated(nominal, data, options, &with_rule);
}

std::string format_noise(const IdentifyResult& r) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(3);
  out << "noise: position: instrument ";
  if (r.all_covariance) {
    out << "covariance of each row (median sigma " << std::setprecision(4) << r.median_instrument_sigma_m * 1e3
        << " mm)";
  } else if (r.sigma_m > 0.0) {
    out << "sigma " << std::setprecision(4) << r.sigma_m * 1e3 << " mm (given)";
  } else {
    out << "unknown";
  }
  if (r.model_error_position_m > 0.0)
    out << " + model error " << std::setprecision(4) << r.model_error_position_m * 1e3 << " mm per axis (REML)";
  if (r.orientation_used) {
    out << "; orientation: instrument ";
    if (r.orientation_sigma_rad > 0.0) {
      out << "sigma " << r.orientation_sigma_rad * kDegPerRad << " deg (given)";
    } else {
      out << "unknown";
    }
    if (r.model_error_orientation_rad > 0.0)
      out << " + model error " << r.model_error_orientation_rad * kDegPerRad << " deg per axis (REML)";
  }
  out << "; chi-square per degree of freedom " << r.chi_square_per_dof
      << "; the parameters' standard deviations include "
      << (r.model_error_estimated ? "the model error" : "the instrument noise only") << '\n';
  for (const Rejection& x : r.rejections)
    out << "  rejected line " << x.line << x.id << ": residual " << x.residual_m * 1e3 << " mm, studentized statistic "
        << x.statistic_ratio << " x the threshold; removing it moves the predicted tool by up to "
        << x.tool_shift_max_m * 1e3 << " mm over the data\n";
  const RejectionGate& g = r.rejection_gate;
  if (g.judged) {
    out << "  rejection gate: 5-fold cross-validated RMS with rejection " << std::setprecision(4)
        << g.kfold_with_m * 1e3 << " mm, without " << g.kfold_without_m * 1e3 << " mm (paired t "
        << std::setprecision(2) << g.kfold_t << std::setprecision(4) << ")";
    if (g.out_of_range_with_m >= 0.0)
      out << "; out-of-range fold " << g.out_of_range_with_m * 1e3 << " mm, without " << g.out_of_range_without_m * 1e3
          << " mm";
    out << ": "
        << (g.kept ? "the rejections stand" : "no rejection (it does not clearly lower the held-out error); undone:");
    for (const Rejection& x : g.undone) out << " line " << x.line << x.id;
    out << '\n';
  }
  if (!r.rejections.empty())
    out << "  model error before rejection " << r.model_error_before_rejection_m * 1e3 << " mm, after "
        << r.model_error_position_m * 1e3 << " mm\n";
  return out.str();
}

IdentifyResult identify_registration(const RobotModel& nominal, const model::Dataset& data,
                                     const IdentifyOptions& options, const IdentifyResult& calibrated) {
  IdentifyOptions o = options;
  o.method = Method::full;
  o.start = Start::nominal;
  o.fixed.clear();
  o.requested.clear();
  for (const core::ParameterId& id : calibrated.identifiability.identified)
    if (model::is_motion_parameter(id.kind)) o.requested.push_back(model::parameter_name(id));
  RobotModel start = nominal;
  std::vector<std::string> notes;
  const bool turn_tool =
      calibrated.orientation_used && std::any_of(o.requested.begin(), o.requested.end(),
                                                 [](const std::string& name) { return name.starts_with("tool_r"); });
  register_start(start, data, turn_tool, notes);
  if (o.requested.empty()) {  // nothing of the registration free: the nominal as it is
    IdentifyResult r;
    r.model = r.start = start;
    r.residuals = accuracy(start, data);
    return r;
  }
  return identify(start, data, o);
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
    out << format_noise(r);
    out << format_prior_scales(r.prior_scales);
    if (std::any_of(r.identifiability.identified.begin(), r.identifiability.identified.end(),
                    [](const core::ParameterId& id) { return model::is_motion_parameter(id.kind); }))
      out << "frames: base_* move frame 0 along and about its own axes (base_T_frame0 * [exp(r), t]); tool_* move "
             "the tool along and about the tool's own axes (flange_T_tool * [exp(r), t])\n";
    const bool priors = r.prior_sigma.size() == r.change.size();
    out << "parameter        change          stddev" << (priors ? "           prior sigma  from data" : "") << '\n';
    std::string beyond;
    bool any_bound = false;
    for (std::size_t k = 0; k < r.identifiability.identified.size(); ++k) {
      const core::ParameterId id = r.identifiability.identified[k];
      const model::DisplayUnit u = model::display_unit(r.model, id);
      const auto i = static_cast<Eigen::Index>(k);
      char line[200];
      const bool bound = k < r.at_bound.size() && r.at_bound[k];
      int at =
          bound ? std::snprintf(line, sizeof line, "  %-10s %12.5f %-4s %15s", model::parameter_name(id).c_str(),
                                r.change(i) * u.per_si, u.name, "at its bound")
                : std::snprintf(line, sizeof line, "  %-10s %12.5f %-4s %10.5f %-4s", model::parameter_name(id).c_str(),
                                r.change(i) * u.per_si, u.name, r.stddev(i) * u.per_si, u.name);
      any_bound = any_bound || bound;
      if (priors && !bound && std::isfinite(r.prior_sigma(i))) {
        std::snprintf(line + at, sizeof line - static_cast<std::size_t>(at), " %10.5f %-4s %5.1f %%",
                      r.prior_sigma(i) * u.per_si, u.name, 100.0 * (1.0 - r.prior_share(i)));
        const double sigmas = std::abs(r.change(i) - r.prior_centre(i)) / r.prior_sigma(i);
        if (sigmas > 3.0) {
          char warn[200];
          std::snprintf(warn, sizeof warn,
                        "warning: %s is %.1f prior sigmas from its nominal (%.5f %s, prior %.5f %s)\n",
                        model::parameter_name(id).c_str(), sigmas, (r.change(i) - r.prior_centre(i)) * u.per_si, u.name,
                        r.prior_sigma(i) * u.per_si, u.name);
          beyond += warn;
        }
      } else if (priors && !bound) {
        std::snprintf(line + at, sizeof line - static_cast<std::size_t>(at), " %10s      %5.1f %%", "none", 100.0);
      }
      out << line << '\n';
    }
    if (any_bound)
      out << "(at its bound: the solve ended on the parameter's physical bound -- a compliance or a mass at 0, a "
             "model file's limit -- which holds it; the other stddevs are given it)\n";
    if (priors)
      out << "(from data: the share of a parameter's posterior information that the measurements give, the rest is "
             "its prior's)\n"
          << beyond;
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

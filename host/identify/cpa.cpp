#include "host/identify/cpa.hpp"

#include <ceres/ceres.h>
#include <ceres/manifold.h>
#include <ceres/rotation.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include <Eigen/QR>

#include "host/identify/statistics.hpp"
#include "host/model/isometry.hpp"

namespace kincal::identify {

namespace {

using model::InputError;
using model::Vector3;

// The single joint whose reading changes by more than tol between a and b, or -1.
int moving_joint(const std::vector<double>& a, const std::vector<double>& b, double tol) {
  int joint = -1;
  for (std::size_t j = 0; j < a.size(); ++j) {
    if (std::abs(a[j] - b[j]) <= tol) continue;
    if (joint >= 0) return -1;
    joint = static_cast<int>(j);
  }
  return joint;
}

bool still_except(const std::vector<double>& a, const std::vector<double>& b, int joint, double tol) {
  for (std::size_t j = 0; j < a.size(); ++j)
    if (static_cast<int>(j) != joint && std::abs(a[j] - b[j]) > tol) return false;
  return true;
}

struct Point {
  Vector3 p;
  Eigen::Matrix3d w;  // whitening (w^T w = covariance^-1, up to the common scale)
  double q;
  int row;
};

// The general model's regressors: 1, q, cos q, sin q (first `terms` of them).
double regressor(int i, double q) {
  switch (i) {
    case 0:
      return 1.0;
    case 1:
      return q;
    case 2:
      return std::cos(q);
    default:
      return std::sin(q);
  }
}

// Weighted linear least squares of p = sum_i f_i(q) v_i.
struct LinearFit {
  double rss = 0.0;  // whitened
  int rank = 0;      // parameters
  Eigen::VectorXd residual;
  Eigen::MatrixXd q1;  // orthonormal basis of the fitted space (3m x rank), only when asked
};

LinearFit linear_fit(const std::vector<Point>& pts, int terms, bool with_basis) {
  const auto m = static_cast<Eigen::Index>(pts.size());
  Eigen::MatrixXd x(3 * m, 3 * terms);
  Eigen::VectorXd y(3 * m);
  for (Eigen::Index k = 0; k < m; ++k) {
    const Point& pt = pts[static_cast<std::size_t>(k)];
    for (int i = 0; i < terms; ++i) x.block(3 * k, 3 * i, 3, 3) = pt.w * regressor(i, pt.q);
    y.segment<3>(3 * k) = pt.w * pt.p;
  }
  // Columns scaled to unit norm so the rank decision does not depend on units.
  const Eigen::VectorXd norms = x.colwise().norm().cwiseMax(1e-300);
  x = x * norms.cwiseInverse().asDiagonal();
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(x);
  qr.setThreshold(1e-10);
  LinearFit f;
  f.rank = static_cast<int>(qr.rank());
  f.residual = y - x * qr.solve(y);
  f.rss = f.residual.squaredNorm();
  if (with_basis) {
    f.q1 = qr.householderQ() * Eigen::MatrixXd::Identity(x.rows(), f.rank);
  }
  return f;
}

struct CircleResidual {
  explicit CircleResidual(const Point& pt) : pt_(pt) {}
  template <class T>
  bool operator()(const T* c, const T* aa, const T* r, T* residual) const {
    const T local[3] = {r[0] * T(std::cos(pt_.q)), r[0] * T(std::sin(pt_.q)), T(0)};
    T world[3];
    ceres::AngleAxisRotatePoint(aa, local, world);
    T e[3];
    for (int i = 0; i < 3; ++i) e[i] = T(pt_.p(i)) - world[i] - c[i];
    for (int i = 0; i < 3; ++i) residual[i] = T(pt_.w(i, 0)) * e[0] + T(pt_.w(i, 1)) * e[1] + T(pt_.w(i, 2)) * e[2];
    return true;
  }
  Point pt_;
};

struct LineResidual {
  explicit LineResidual(const Point& pt) : pt_(pt) {}
  template <class T>
  bool operator()(const T* c, const T* u, T* residual) const {
    T e[3];
    for (int i = 0; i < 3; ++i) e[i] = T(pt_.p(i)) - c[i] - u[i] * T(pt_.q);
    for (int i = 0; i < 3; ++i) residual[i] = T(pt_.w(i, 0)) * e[0] + T(pt_.w(i, 1)) * e[1] + T(pt_.w(i, 2)) * e[2];
    return true;
  }
  Point pt_;
};

struct Fit {
  Vector3 centre = Vector3::Zero();
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // revolute: columns e1, e2, axis
  double radius = 0.0;
  Vector3 direction = Vector3::UnitZ();  // prismatic
  double rss = 0.0;                      // whitened
};

ceres::Solver::Options small_options() {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::DENSE_QR;
  o.max_num_iterations = 100;
  o.num_threads = 1;
  o.function_tolerance = 1e-14;
  o.parameter_tolerance = 1e-14;
  o.gradient_tolerance = 1e-16;
  o.logging_type = ceres::SILENT;
  return o;
}

Vector3 model_point(const Fit& f, double q, bool revolute) {
  return revolute ? Vector3(f.centre + f.radius * (std::cos(q) * f.rotation.col(0) + std::sin(q) * f.rotation.col(1)))
                  : Vector3(f.centre + f.direction * q);
}

double whitened_rss(const Fit& f, const std::vector<Point>& pts, bool revolute) {
  double sum = 0.0;
  for (const Point& pt : pts) sum += (pt.w * (pt.p - model_point(f, pt.q, revolute))).squaredNorm();
  return sum;
}

// Linear start p = c + a cos q + b sin q, then the constrained circle.
Fit fit_circle(const std::vector<Point>& pts) {
  const auto m = static_cast<Eigen::Index>(pts.size());
  Eigen::MatrixXd x(3 * m, 9);
  Eigen::VectorXd y(3 * m);
  for (Eigen::Index k = 0; k < m; ++k) {
    const Point& pt = pts[static_cast<std::size_t>(k)];
    x.block(3 * k, 0, 3, 3) = pt.w;
    x.block(3 * k, 3, 3, 3) = pt.w * std::cos(pt.q);
    x.block(3 * k, 6, 3, 3) = pt.w * std::sin(pt.q);
    y.segment<3>(3 * k) = pt.w * pt.p;
  }
  const Eigen::VectorXd beta = x.colPivHouseholderQr().solve(y);
  const Vector3 a = beta.segment<3>(3), b = beta.segment<3>(6);
  const Vector3 e1 = a.norm() > 0 ? Vector3(a.normalized()) : Vector3::UnitX();
  Vector3 e2 = b - b.dot(e1) * e1;
  e2 = e2.norm() > 0 ? Vector3(e2.normalized()) : Vector3(e1.unitOrthogonal());
  Eigen::Matrix3d r;
  r.col(0) = e1;
  r.col(1) = e2;
  r.col(2) = e1.cross(e2);
  double c[3] = {beta(0), beta(1), beta(2)}, aa[3], radius = 0.5 * (a.norm() + b.norm());
  ceres::RotationMatrixToAngleAxis(r.data(), aa);
  ceres::Problem problem;
  for (const Point& pt : pts)
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<CircleResidual, 3, 3, 3, 1>(new CircleResidual(pt)),
                             nullptr, c, aa, &radius);
  ceres::Solver::Summary summary;
  ceres::Solve(small_options(), &problem, &summary);
  Fit f;
  double rm[9];
  ceres::AngleAxisToRotationMatrix(aa, rm);
  f.rotation = Eigen::Map<Eigen::Matrix3d>(rm);
  f.centre = Vector3(c[0], c[1], c[2]);
  f.radius = radius;
  if (f.radius < 0) {  // r -> -r with e1, e2 -> -e1, -e2: same circle, same axis
    f.radius = -f.radius;
    f.rotation.col(0) *= -1.0;
    f.rotation.col(1) *= -1.0;
  }
  f.rss = whitened_rss(f, pts, true);
  return f;
}

Fit fit_line(const std::vector<Point>& pts) {
  const auto m = static_cast<Eigen::Index>(pts.size());
  Eigen::MatrixXd x(3 * m, 6);
  Eigen::VectorXd y(3 * m);
  for (Eigen::Index k = 0; k < m; ++k) {
    const Point& pt = pts[static_cast<std::size_t>(k)];
    x.block(3 * k, 0, 3, 3) = pt.w;
    x.block(3 * k, 3, 3, 3) = pt.w * pt.q;
    y.segment<3>(3 * k) = pt.w * pt.p;
  }
  const Eigen::VectorXd beta = x.colPivHouseholderQr().solve(y);
  double c[3] = {beta(0), beta(1), beta(2)};
  const Vector3 v = beta.segment<3>(3).norm() > 0 ? Vector3(beta.segment<3>(3).normalized()) : Vector3::UnitZ();
  double u[3] = {v(0), v(1), v(2)};
  ceres::Problem problem;
  for (const Point& pt : pts)
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<LineResidual, 3, 3, 3>(new LineResidual(pt)), nullptr, c,
                             u);
  problem.SetManifold(u, new ceres::SphereManifold<3>());
  ceres::Solver::Summary summary;
  ceres::Solve(small_options(), &problem, &summary);
  Fit f;
  f.centre = Vector3(c[0], c[1], c[2]);
  f.direction = Vector3(u[0], u[1], u[2]).normalized();
  f.rss = whitened_rss(f, pts, false);
  return f;
}

Eigen::Matrix3d cross_matrix(const Vector3& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// Gauss-Newton covariance of the fit (unit whitened noise), mapped to the axis (position and
// direction along the normal basis) and the radius. Fills the spreads of `out`.
void axis_spread(const Fit& f, const std::vector<Point>& pts, bool revolute, double variance, SweepFit& out) {
  const Vector3 n = revolute ? Vector3(f.rotation.col(2)) : f.direction;
  Eigen::Matrix<double, 3, 2> basis;
  basis.col(0) = n.unitOrthogonal();
  basis.col(1) = n.cross(basis.col(0));
  const int params = revolute ? 7 : 5;
  Eigen::MatrixXd info = Eigen::MatrixXd::Zero(params, params);
  double q_mean = 0.0;
  for (const Point& pt : pts) q_mean += pt.q / static_cast<double>(pts.size());
  for (const Point& pt : pts) {
    Eigen::MatrixXd j(3, params);
    j.leftCols<3>() = -Eigen::Matrix3d::Identity();
    if (revolute) {
      const Vector3 radial = f.radius * (std::cos(pt.q) * f.rotation.col(0) + std::sin(pt.q) * f.rotation.col(1));
      j.block<3, 3>(0, 3) = cross_matrix(radial);  // small rotation dphi: de = radial x dphi
      j.col(6) = -radial / std::max(f.radius, 1e-300);
    } else {
      j.col(3) = -basis.col(0) * pt.q;
      j.col(4) = -basis.col(1) * pt.q;
    }
    const Eigen::MatrixXd wj = pt.w * j;
    info += wj.transpose() * wj;
  }
  const Eigen::MatrixXd cov = variance * info.completeOrthogonalDecomposition().pseudoInverse();
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(4, params);
  a.block<1, 3>(0, 0) = basis.col(0).transpose();
  a.block<1, 3>(1, 0) = basis.col(1).transpose();
  if (revolute) {
    // dn = dphi x n; its component along b_i is (n x b_i) . dphi.
    a.block<1, 3>(2, 3) = n.cross(basis.col(0)).transpose();
    a.block<1, 3>(3, 3) = n.cross(basis.col(1)).transpose();
    out.radius_stddev_m = std::sqrt(std::max(0.0, cov(6, 6)));
  } else {
    // The line's point at the mean reading: c + u q_mean.
    a(0, 3) = q_mean;
    a(1, 4) = q_mean;
    a(2, 3) = 1.0;
    a(3, 4) = 1.0;
  }
  out.axis_covariance = a * cov * a.transpose();
  out.normal_basis = basis;
  out.position_stddev_m = std::sqrt(std::max(0.0, out.axis_covariance.topLeftCorner<2, 2>().trace() / 2.0));
  out.direction_stddev_rad = std::sqrt(std::max(0.0, out.axis_covariance.bottomRightCorner<2, 2>().trace() / 2.0));
}

// Drops outliers of the general model (studentized deleted residuals, Bonferroni, capped).
std::vector<Point> screen(std::vector<Point> pts, const model::Dataset& data, const CpaOptions& options,
                          std::vector<int>& rejected_lines) {
  const auto cap = static_cast<std::size_t>(options.max_rejected_fraction * static_cast<double>(pts.size()));
  std::size_t dropped = 0;
  while (dropped < cap) {
    const LinearFit f = linear_fit(pts, 4, true);
    const double dof = 3.0 * static_cast<double>(pts.size()) - f.rank;
    if (dof - 3.0 < 1.0 || f.rss <= 0.0) break;
    double worst_p = 1.0;
    std::size_t worst = 0;
    for (std::size_t k = 0; k < pts.size(); ++k) {
      const auto i = static_cast<Eigen::Index>(3 * k);
      const Eigen::Matrix3d m = Eigen::Matrix3d::Identity() - f.q1.middleRows<3>(i) * f.q1.middleRows<3>(i).transpose();
      const Eigen::LDLT<Eigen::Matrix3d> ldlt(m);
      if (ldlt.info() != Eigen::Success || m.determinant() < 1e-9) continue;  // leverage ~1: cannot be judged
      const Eigen::Vector3d e = f.residual.segment<3>(i);
      const double d = e.dot(ldlt.solve(e));
      const double rest = (f.rss - d) / (dof - 3.0);
      if (!(rest > 0.0)) continue;
      const double p = 1.0 - fisher_cdf((d / 3.0) / rest, 3.0, dof - 3.0);
      if (p < worst_p) {
        worst_p = p;
        worst = k;
      }
    }
    if (worst_p * static_cast<double>(pts.size()) >= options.outlier_probability) break;
    rejected_lines.push_back(data.rows[static_cast<std::size_t>(pts[worst].row)].line);
    pts.erase(pts.begin() + static_cast<std::ptrdiff_t>(worst));
    ++dropped;
  }
  return pts;
}

TypeTest type_test(const std::vector<Point>& pts, double unit_line_rss, double circle_rss, bool known_noise,
                   double significance) {
  TypeTest t;
  const LinearFit general = linear_fit(pts, 4, false);
  const LinearFit line = linear_fit(pts, 2, false);
  const double m3 = 3.0 * static_cast<double>(pts.size());
  const double dof = m3 - general.rank;
  t.residual_dof = static_cast<int>(dof);
  const double df_line = general.rank - line.rank, df_circle = general.rank - 7.0;
  // p-value of a drop in residual of df1 parameters against the general model's residual.
  const auto p_of = [&](double rss0, double df1) {
    if (df1 < 1.0) return 1.0;
    const double drop = std::max(0.0, rss0 - general.rss);
    if (dof >= 1.0) {
      if (general.rss <= 0.0) return drop > 0.0 ? 0.0 : 1.0;
      return 1.0 - fisher_cdf((drop / df1) / (general.rss / dof), df1, dof);
    }
    return 1.0 - chi_square_cdf(drop, df1);
  };
  t.tested = dof >= 1.0 || known_noise;
  // The line test uses the linear fit (affine in q, v free): the F test is then exact.
  t.p_line = t.tested ? p_of(line.rss, df_line) : 1.0;
  t.p_circle = t.tested ? p_of(circle_rss, df_circle) : 1.0;
  const bool line_rejected = t.tested && t.p_line < significance;
  const bool circle_rejected = t.tested && t.p_circle < significance;
  t.conclusive = line_rejected != circle_rejected;
  t.p_unit_speed = t.tested ? p_of(unit_line_rss, general.rank - 5.0) : 1.0;
  if (t.conclusive) {
    t.verdict = line_rejected ? core::JointType::revolute : core::JointType::prismatic;
  } else if (t.tested && !line_rejected) {
    // Both fit (a short sweep): a prismatic joint moves 1 m per metre of reading, a revolute one
    // r per radian, so the unit-speed line tells them apart unless r is near 1 m.
    t.verdict = t.p_unit_speed < significance ? core::JointType::revolute : core::JointType::prismatic;
  } else {
    // Neither fits, or untested: Akaike on the joint models (circle 7 parameters, unit line 5).
    const double s2 = dof >= 1.0 && general.rss > 0.0 ? general.rss / dof : 1.0;
    t.verdict =
        circle_rss / s2 + 14.0 < unit_line_rss / s2 + 10.0 ? core::JointType::revolute : core::JointType::prismatic;
  }
  return t;
}

// The motion of joint i by q about/along its axis: a transform in the device frame.
model::Transform joint_motion(const model::AxisLine& axis, double q) {
  model::Transform t;
  if (axis.type == core::JointType::revolute) {
    t.rotation = Eigen::AngleAxisd(q, axis.direction).toRotationMatrix();
    t.translation = axis.point - t.rotation * axis.point;
  } else {
    t.translation = axis.direction * q;
  }
  return t;
}

model::AxisLine transformed(const model::Transform& t, const model::AxisLine& a) {
  return {t * a.point, t.rotation * a.direction, a.type};
}

// Carry something measured at readings q back to all-zero readings of joints [0, count).
model::Transform back_to_zero(std::span<const model::AxisLine> zero_axes, const std::vector<double>& q, int count) {
  model::Transform t;  // applied as t * x
  for (int j = 0; j < count; ++j) {
    const auto k = static_cast<std::size_t>(j);
    t = joint_motion(zero_axes[k], -q[k]) * t;
  }
  return t;
}

const char* type_name(core::JointType t) { return t == core::JointType::revolute ? "revolute" : "prismatic"; }

SweepFit fit_sweep(const model::Dataset& data, const Sweep& s, std::optional<core::JointType> declared,
                   const CpaOptions& options) {
  const auto j = static_cast<std::size_t>(s.joint);
  std::vector<Point> pts;
  bool known_noise = options.sigma_m > 0.0;
  for (int r : s.rows) {
    const model::Measurement& m = data.rows[static_cast<std::size_t>(r)];
    Eigen::Matrix3d w = Eigen::Matrix3d::Identity();
    if (m.covariance) {
      w = Eigen::Matrix3d(Eigen::LLT<Eigen::Matrix3d>(*m.covariance).matrixL()).inverse();
    } else if (options.sigma_m > 0.0) {
      w /= options.sigma_m;
    }
    known_noise = known_noise || m.covariance.has_value();
    pts.push_back({m.position, w, m.q[j], r});
  }
  SweepFit fit;
  fit.joint = s.joint;
  fit.first_line = data.rows[static_cast<std::size_t>(s.rows.front())].line;
  fit.last_line = data.rows[static_cast<std::size_t>(s.rows.back())].line;
  fit.q_min = fit.q_max = pts.front().q;
  for (const Point& pt : pts) {
    fit.q_min = std::min(fit.q_min, pt.q);
    fit.q_max = std::max(fit.q_max, pt.q);
  }
  const std::vector<Point> kept = screen(pts, data, options, fit.rejected_lines);
  const Fit circle = fit_circle(kept);
  const Fit line = fit_line(kept);
  fit.test = type_test(kept, line.rss, circle.rss, known_noise, options.significance);
  fit.p_value = fit.test.p_line;
  fit.type = declared.value_or(fit.test.verdict);
  const bool revolute = fit.type == core::JointType::revolute;
  fit.curved = revolute;
  if (declared) {
    fit.contradicts_model =
        revolute ? fit.test.p_circle < options.significance : fit.test.p_line < options.significance;
  }
  const Fit& f = revolute ? circle : line;
  fit.used = static_cast<int>(kept.size());
  const double dof = 3.0 * static_cast<double>(kept.size()) - (revolute ? 7.0 : 5.0);
  const double variance = dof >= 1.0 ? f.rss / dof : 1.0;
  fit.noise_scale = std::sqrt(variance);
  double sum2 = 0;
  for (const Point& pt : kept) sum2 += (pt.p - model_point(f, pt.q, revolute)).squaredNorm();
  fit.rms_m = std::sqrt(sum2 / static_cast<double>(kept.size()));
  fit.axis.type = fit.type;
  if (revolute) {
    fit.axis.point = f.centre;
    fit.axis.direction = f.rotation.col(2);
    fit.radius_m = f.radius;
  } else {
    double q_mean = 0.0;
    for (const Point& pt : kept) q_mean += pt.q / static_cast<double>(kept.size());
    fit.axis.point = f.centre + f.direction * q_mean;
    fit.axis.direction = f.direction;
  }
  axis_spread(f, kept, revolute, variance, fit);
  return fit;
}

}  // namespace

std::vector<Sweep> find_sweeps(const model::Dataset& data, double still_tolerance) {
  std::vector<Sweep> sweeps;
  const std::size_t n = data.rows.size();
  std::size_t i = 0;
  while (i + 1 < n) {
    const int joint = moving_joint(data.rows[i].q, data.rows[i + 1].q, still_tolerance);
    if (joint < 0) {
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    while (j + 1 < n && still_except(data.rows[i].q, data.rows[j + 1].q, joint, still_tolerance)) ++j;
    if (j - i + 1 >= 4) {
      Sweep s;
      s.joint = joint;
      for (std::size_t k = i; k <= j; ++k) s.rows.push_back(static_cast<int>(k));
      sweeps.push_back(std::move(s));
    }
    i = j;
  }
  return sweeps;
}

std::vector<model::AxisLine> axes_at_zero(std::span<const model::AxisLine> measured,
                                          std::span<const std::vector<double>> sweep_readings) {
  std::vector<model::AxisLine> zero;
  for (std::size_t j = 0; j < measured.size(); ++j)
    zero.push_back(transformed(back_to_zero(zero, sweep_readings[j], static_cast<int>(j)), measured[j]));
  return zero;
}

namespace {

// A sweep whose measured points (and orientations, when used) do not move shows no axis: a fit
// to it returns a radius of roundoff (found: "beacon radius 7.5e-14 mm" from a constant column).
// 1 um and 1 urad are far below any instrument's noise and far above the arithmetic's.
void require_motion(const model::Dataset& data, const Sweep& s, bool use_orientation, const std::string& lines) {
  constexpr double kStillM = 1e-6, kStillRad = 1e-6;
  const model::Measurement& first = data.rows[static_cast<std::size_t>(s.rows.front())];
  double moved_m = 0.0, turned_rad = 0.0;
  for (int r : s.rows) {
    const model::Measurement& m = data.rows[static_cast<std::size_t>(r)];
    moved_m = std::max(moved_m, (m.position - first.position).norm());
    if (use_orientation && m.orientation && first.orientation)
      turned_rad = std::max(turned_rad, m.orientation->angularDistance(*first.orientation));
  }
  if (moved_m >= kStillM || turned_rad >= kStillRad) return;
  const double reading_span =
      std::abs(data.rows[static_cast<std::size_t>(s.rows.back())].q[static_cast<std::size_t>(s.joint)] -
               first.q[static_cast<std::size_t>(s.joint)]);
  std::ostringstream msg;
  msg << data.source << ": joint " << s.joint + 1 << " (" << lines << "): its reading changes by " << reading_span
      << " but the measured points do not move (all within " << moved_m * 1e6
      << " um of the first): the sweep shows no axis; are the position columns the right ones?";
  throw InputError(msg.str());
}

// A still tolerance at or above every step of a joint's reading leaves the joint still in every
// row: said as such, rather than as the sweep that then cannot be found.
void check_still_tolerance(const model::Dataset& data, double tolerance) {
  if (!(tolerance > 0.0)) return;
  for (std::size_t j = 0; j < static_cast<std::size_t>(data.joint_count); ++j) {
    double largest = 0.0;
    for (std::size_t i = 0; i + 1 < data.rows.size(); ++i)
      largest = std::max(largest, std::abs(data.rows[i + 1].q[j] - data.rows[i].q[j]));
    if (largest > 0.0 && largest <= tolerance) {
      std::ostringstream msg;
      msg << data.source << ": --still-tolerance " << tolerance << " leaves joint " << j + 1
          << " still in every row: its reading changes by at most " << largest
          << " (rad or m) from one row to the next; give a tolerance below its steps";
      throw InputError(msg.str());
    }
  }
}

}  // namespace

SweepAnalysis analyse_sweeps(const model::Dataset& data, std::span<const std::optional<core::JointType>> declared,
                             bool use_orientation, const CpaOptions& options) {
  const int n = data.joint_count;
  check_still_tolerance(data, options.still_tolerance);
  const std::vector<Sweep> sweeps = find_sweeps(data, options.still_tolerance);
  SweepAnalysis result;
  std::vector<const Sweep*> chosen(static_cast<std::size_t>(n), nullptr);
  const auto lines = [&](const Sweep& s) {
    return "lines " + std::to_string(data.rows[static_cast<std::size_t>(s.rows.front())].line) + "-" +
           std::to_string(data.rows[static_cast<std::size_t>(s.rows.back())].line);
  };
  for (const Sweep& s : sweeps) {
    const Sweep*& c = chosen[static_cast<std::size_t>(s.joint)];
    if (c && c->rows.size() >= s.rows.size()) {
      result.notes.push_back("a shorter sweep of joint " + std::to_string(s.joint + 1) + " (" + lines(s) +
                             ") not used");
      continue;
    }
    if (c)
      result.notes.push_back("a shorter sweep of joint " + std::to_string(s.joint + 1) + " (" + lines(*c) +
                             ") not used");
    c = &s;
  }
  for (int j = 0; j < n; ++j)
    if (!chosen[static_cast<std::size_t>(j)])
      throw InputError(data.source +
                       ": cpa needs a single-joint sweep of every joint (4 or more consecutive "
                       "rows in which only that joint moves); joint " +
                       std::to_string(j + 1) + " has none");

  std::vector<model::AxisLine> measured;
  for (int j = 0; j < n; ++j) {
    const Sweep& s = *chosen[static_cast<std::size_t>(j)];
    const std::optional<core::JointType> d = declared.empty() ? std::nullopt : declared[static_cast<std::size_t>(j)];
    require_motion(data, s, use_orientation, lines(s));
    SweepFit fit = fit_sweep(data, s, d, options);
    if (fit.contradicts_model) {
      std::ostringstream msg;
      msg << "joint " << j + 1 << " (" << lines(s) << "): the model says " << type_name(fit.type)
          << " but the sweep does not fit a " << (fit.curved ? "circle at angle q" : "line affine in q")
          << " (p(line) = " << fit.test.p_line << ", p(circle) = " << fit.test.p_circle << "); fitted as "
          << type_name(fit.type) << " all the same";
      result.notes.push_back(msg.str());
    }
    if (!fit.rejected_lines.empty()) {
      std::ostringstream msg;
      msg << "joint " << j + 1 << ": " << fit.rejected_lines.size() << " of " << s.rows.size()
          << " points rejected as outliers of the sweep (lines";
      for (int l : fit.rejected_lines) msg << ' ' << l;
      msg << ")";
      result.notes.push_back(msg.str());
    }
    if (s.rows.size() < 6) {
      result.notes.push_back("joint " + std::to_string(j + 1) + ": " + std::to_string(s.rows.size()) +
                             " points: too few to screen for outliers");
    }
    measured.push_back(fit.axis);
    result.sweep_readings.push_back(data.rows[static_cast<std::size_t>(s.rows.front())].q);
    result.fits.push_back(std::move(fit));
  }
  result.zero_axes = axes_at_zero(measured, result.sweep_readings);

  // The tool at zero readings: mean of every used point carried back.
  Vector3 sum = Vector3::Zero();
  Eigen::Matrix3d rotation_sum = Eigen::Matrix3d::Zero();
  int count = 0;
  for (int j = 0; j < n; ++j) {
    const SweepFit& fit = result.fits[static_cast<std::size_t>(j)];
    for (int r : chosen[static_cast<std::size_t>(j)]->rows) {
      const model::Measurement& m = data.rows[static_cast<std::size_t>(r)];
      if (std::find(fit.rejected_lines.begin(), fit.rejected_lines.end(), m.line) != fit.rejected_lines.end()) continue;
      const model::Transform back = back_to_zero(result.zero_axes, m.q, n);
      sum += back * m.position;
      if (use_orientation && m.orientation) rotation_sum += back.rotation * m.orientation->toRotationMatrix();
      ++count;
    }
  }
  result.tool_home.translation = sum / static_cast<double>(count);
  if (use_orientation) result.tool_home.rotation = model::nearest_rotation(rotation_sum);
  return result;
}

CpaResult circle_point_analysis(const RobotModel& nominal, const model::Dataset& data, const CpaOptions& options) {
  model::check_joint_count(nominal, data.joint_count, data.source);
  std::vector<std::optional<core::JointType>> declared;
  for (const model::Joint& j : nominal.joints) declared.push_back(j.type);
  SweepAnalysis a =
      analyse_sweeps(data, declared, data.has_orientation && nominal.tool == model::ToolKind::frame, options);
  CpaResult result;
  const std::vector<double> zero(static_cast<std::size_t>(nominal.joint_count()), 0.0);
  model::AxesToChainOptions axes_options;
  axes_options.parallel_tolerance_rad = options.parallel_tolerance_rad;
  result.model = model::chain_from_axes(nominal, a.zero_axes, zero, a.tool_home, axes_options);
  result.fits = std::move(a.fits);
  for (std::string& note : a.notes) result.notes.push_back("cpa: " + note);
  return result;
}

std::string describe(const SweepFit& f) {
  std::ostringstream out;
  out.precision(3);
  const bool revolute = f.type == core::JointType::revolute;
  const double deg = 180.0 / std::numbers::pi;
  out << "joint " << f.joint + 1 << ": " << (revolute ? "circle" : "line") << " (p(line) = " << f.test.p_line
      << ", p(circle) = " << f.test.p_circle << ", p(unit-speed line) = " << f.test.p_unit_speed
      << (f.test.conclusive ? "" : ", inconclusive") << (f.test.tested ? "" : ", untested: too few points") << "), "
      << f.used << " points, lines " << f.first_line << "-" << f.last_line;
  if (revolute) {
    out << ", swept " << f.q_min * deg << ".." << f.q_max * deg << " deg, radius " << f.radius_m * 1e3 << " +- "
        << f.radius_stddev_m * 1e3 << " mm";
  } else {
    out << ", stroke " << f.q_min * 1e3 << ".." << f.q_max * 1e3 << " mm";
  }
  out << ", axis direction +- " << f.direction_stddev_rad * 1e3 << " mrad, position +- " << f.position_stddev_m * 1e3
      << " mm, fit rms " << f.rms_m * 1e3 << " mm";
  if (!f.rejected_lines.empty()) {
    out << ", rejected lines";
    for (int l : f.rejected_lines) out << ' ' << l;
  }
  return out.str();
}

}  // namespace kincal::identify

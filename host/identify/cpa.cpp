#include "host/identify/cpa.hpp"

#include <ceres/ceres.h>
#include <ceres/manifold.h>
#include <ceres/rotation.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include <Eigen/QR>
#include <Eigen/SVD>

#include "host/identify/statistics.hpp"

namespace kincal::identify {

namespace {

using model::InputError;
using model::Vector3;

bool equal_except(const std::vector<double>& a, const std::vector<double>& b, int joint) {
  for (std::size_t j = 0; j < a.size(); ++j)
    if (static_cast<int>(j) != joint && a[j] != b[j]) return false;
  return true;
}

// The single joint in which rows a and b differ, or -1.
int moving_joint(const std::vector<double>& a, const std::vector<double>& b) {
  int joint = -1;
  for (std::size_t j = 0; j < a.size(); ++j) {
    if (a[j] == b[j]) continue;
    if (joint >= 0) return -1;
    joint = static_cast<int>(j);
  }
  return joint;
}

struct Point {
  Vector3 p;
  Eigen::Matrix3d w;  // whitening (L^T L = covariance^-1); identity/sigma when unknown
  double q;
  int row;
};

// Weighted linear least squares of p = c + sum_k f_k(q) v_k; returns RSS (whitened).
double polynomial_rss(const std::vector<Point>& pts, int terms, double q_mean, double q_scale) {
  const auto m = static_cast<Eigen::Index>(pts.size());
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(3 * m, 3 * terms);
  Eigen::VectorXd y(3 * m);
  for (Eigen::Index k = 0; k < m; ++k) {
    const Point& pt = pts[static_cast<std::size_t>(k)];
    const double t = (pt.q - q_mean) / q_scale;
    double f = 1.0;
    for (int i = 0; i < terms; ++i) {
      x.block(3 * k, 3 * i, 3, 3) = pt.w * f;
      f *= t;
    }
    y.segment<3>(3 * k) = pt.w * pt.p;
  }
  const Eigen::VectorXd beta = x.colPivHouseholderQr().solve(y);
  return (y - x * beta).squaredNorm();
}

struct CircleResidual {
  CircleResidual(const Point& pt) : pt_(pt) {}
  template <class T>
  bool operator()(const T* c, const T* aa, const T* r, T* residual) const {
    using std::cos;
    using std::sin;
    const T local[3] = {r[0] * T(cos(pt_.q)), r[0] * T(sin(pt_.q)), T(0)};
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
  LineResidual(const Point& pt) : pt_(pt) {}
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

// Linear start + constrained refinement (Huber loss at the 99.9 % chi-square(3) radius).
Fit fit_circle(const std::vector<Point>& pts, bool robust) {
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
  Fit f;
  const Vector3 e1 = a.normalized();
  const Vector3 e2 = (b - b.dot(e1) * e1).normalized();
  Eigen::Matrix3d r;
  r.col(0) = e1;
  r.col(1) = e2;
  r.col(2) = e1.cross(e2);
  double c[3] = {beta(0), beta(1), beta(2)}, aa[3], radius = 0.5 * (a.norm() + b.norm());
  ceres::RotationMatrixToAngleAxis(r.data(), aa);
  ceres::Problem problem;
  const double huber = std::sqrt(chi_square_quantile(0.999, 3));
  for (const Point& pt : pts)
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<CircleResidual, 3, 3, 3, 1>(new CircleResidual(pt)),
                             robust ? new ceres::HuberLoss(huber) : nullptr, c, aa, &radius);
  ceres::Solver::Summary summary;
  ceres::Solve(small_options(), &problem, &summary);
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
  return f;
}

Fit fit_line(const std::vector<Point>& pts, bool robust) {
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
  const Vector3 v = beta.segment<3>(3).normalized();
  double u[3] = {v(0), v(1), v(2)};
  ceres::Problem problem;
  const double huber = std::sqrt(chi_square_quantile(0.999, 3));
  for (const Point& pt : pts)
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<LineResidual, 3, 3, 3>(new LineResidual(pt)),
                             robust ? new ceres::HuberLoss(huber) : nullptr, c, u);
  problem.SetManifold(u, new ceres::SphereManifold<3>());
  ceres::Solver::Summary summary;
  ceres::Solve(small_options(), &problem, &summary);
  Fit f;
  f.centre = Vector3(c[0], c[1], c[2]);
  f.direction = Vector3(u[0], u[1], u[2]).normalized();
  return f;
}

Vector3 fit_error(const Fit& f, const Point& pt, bool revolute) {
  const Vector3 model =
      revolute
          ? Vector3(f.centre + f.radius * (std::cos(pt.q) * f.rotation.col(0) + std::sin(pt.q) * f.rotation.col(1)))
          : Vector3(f.centre + f.direction * pt.q);
  return pt.p - model;
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
model::Transform back_to_zero(const std::vector<model::AxisLine>& zero_axes, const std::vector<double>& q, int count) {
  model::Transform t;  // applied as t * x
  for (int j = 0; j < count; ++j) {
    const auto k = static_cast<std::size_t>(j);
    t = joint_motion(zero_axes[k], -q[k]) * t;
  }
  return t;
}

}  // namespace

std::vector<Sweep> find_sweeps(const model::Dataset& data) {
  std::vector<Sweep> sweeps;
  const std::size_t n = data.rows.size();
  std::size_t i = 0;
  while (i + 1 < n) {
    const int joint = moving_joint(data.rows[i].q, data.rows[i + 1].q);
    if (joint < 0) {
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    while (j + 1 < n && equal_except(data.rows[i].q, data.rows[j + 1].q, joint)) ++j;
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

CpaResult circle_point_analysis(const RobotModel& nominal, const model::Dataset& data, const CpaOptions& options) {
  model::check_joint_count(nominal, data.joint_count, data.source);
  const int n = nominal.joint_count();
  const std::vector<Sweep> sweeps = find_sweeps(data);
  CpaResult result;
  std::vector<const Sweep*> chosen(static_cast<std::size_t>(n), nullptr);
  for (const Sweep& s : sweeps) {
    const Sweep*& c = chosen[static_cast<std::size_t>(s.joint)];
    if (c && c->rows.size() >= s.rows.size()) {
      result.notes.push_back("cpa: a shorter sweep of joint " + std::to_string(s.joint + 1) + " (lines " +
                             std::to_string(data.rows[static_cast<std::size_t>(s.rows.front())].line) + "-" +
                             std::to_string(data.rows[static_cast<std::size_t>(s.rows.back())].line) + ") not used");
      continue;
    }
    c = &s;
  }
  for (int j = 0; j < n; ++j)
    if (!chosen[static_cast<std::size_t>(j)])
      throw InputError(data.source +
                       ": cpa needs a single-joint sweep of every joint (4 or more consecutive rows in "
                       "which only that joint moves); joint " +
                       std::to_string(j + 1) + " (" + nominal.joints[static_cast<std::size_t>(j)].name + ") has none");

  const bool known_noise = std::all_of(data.rows.begin(), data.rows.end(),
                                       [](const model::Measurement& r) { return r.covariance.has_value(); }) ||
                           options.sigma_m > 0.0;
  std::vector<model::AxisLine> zero_axes;
  std::vector<Point> all_points;  // every used point, for the tool
  for (int j = 0; j < n; ++j) {
    const Sweep& s = *chosen[static_cast<std::size_t>(j)];
    const model::Joint& joint = nominal.joints[static_cast<std::size_t>(j)];
    const bool revolute = joint.type == core::JointType::revolute;
    std::vector<Point> pts;
    for (int r : s.rows) {
      const model::Measurement& m = data.rows[static_cast<std::size_t>(r)];
      Eigen::Matrix3d w = Eigen::Matrix3d::Identity();
      if (m.covariance) {
        w = Eigen::Matrix3d(Eigen::LLT<Eigen::Matrix3d>(*m.covariance).matrixL()).inverse();
      } else if (options.sigma_m > 0.0) {
        w /= options.sigma_m;
      }
      pts.push_back({m.position, w, m.q[static_cast<std::size_t>(j)], r});
    }
    // Classification: is the path curved? (Uses all points; a gross outlier could only make a
    // line look curved, which the joint-type check below reports.)
    double q_mean = 0, q_lo = pts[0].q, q_hi = pts[0].q;
    for (const Point& pt : pts) {
      q_mean += pt.q;
      q_lo = std::min(q_lo, pt.q);
      q_hi = std::max(q_hi, pt.q);
    }
    q_mean /= static_cast<double>(pts.size());
    const double q_scale = std::max(1e-12, 0.5 * (q_hi - q_lo));
    const double rss_line = polynomial_rss(pts, 2, q_mean, q_scale);
    const double rss_quadratic = polynomial_rss(pts, 3, q_mean, q_scale);
    const double dof = 3.0 * static_cast<double>(pts.size()) - 9.0;
    SweepFit fit;
    fit.joint = j;
    if (known_noise) {
      fit.p_value = 1.0 - chi_square_cdf(std::max(0.0, rss_line - rss_quadratic), 3.0);
    } else if (rss_line < 1e-20) {
      fit.p_value = 1.0;  // noise-free straight line
    } else {
      const double f = ((rss_line - rss_quadratic) / 3.0) / std::max(rss_quadratic / dof, 1e-300);
      fit.p_value = 1.0 - fisher_cdf(f, 3.0, dof);
    }
    fit.curved = fit.p_value < options.significance;
    if (fit.curved != revolute) {
      std::ostringstream msg;
      msg << data.source << ": cpa: the sweep of joint " << j + 1 << " (" << joint.name << ", lines "
          << data.rows[static_cast<std::size_t>(s.rows.front())].line << "-"
          << data.rows[static_cast<std::size_t>(s.rows.back())].line << ") is "
          << (fit.curved ? "curved" : "not significantly curved") << " (p-value of a straight path " << fit.p_value
          << ") but the model says the joint is " << (revolute ? "revolute" : "prismatic")
          << (revolute ? ": too short an arc for the noise, or a prismatic joint" : "");
      throw InputError(msg.str());
    }
    // Fit with outlier rejection.
    std::vector<Point> active = pts;
    double scale = 1.0;  // whitened residual scale (noise unknown: estimated)
    if (!known_noise) {
      const double s2 = rss_quadratic / std::max(1.0, dof);
      scale = std::sqrt(std::max(s2, 1e-300));
      for (Point& pt : active) pt.w /= scale;
    }
    Fit f;
    for (int round = 0; round < 6; ++round) {
      f = revolute ? fit_circle(active, true) : fit_line(active, true);
      double raw = 0.0;  // metres: below rounding there is nothing to reject
      for (const Point& pt : active) raw = std::max(raw, fit_error(f, pt, revolute).norm());
      if (raw < 1e-12) break;
      std::vector<double> s2;
      for (const Point& pt : active) s2.push_back((pt.w * fit_error(f, pt, revolute)).squaredNorm());
      if (!known_noise) {
        // Rescale to unit variance: median while rejecting, then the residual sum over its dof.
        const double factor = round == 0 ? median(s2) / chi_square_quantile(0.5, 3) : [&] {
          double sum = 0;
          for (double v : s2) sum += v;
          return sum / std::max(1.0, 3.0 * static_cast<double>(active.size()) - (revolute ? 7.0 : 5.0));
        }();
        if (factor > 0) {
          for (Point& pt : active) pt.w /= std::sqrt(factor);
          for (double& v : s2) v /= factor;
        }
      }
      const double threshold = chi_square_quantile(1.0 - options.outlier_probability, 3);
      std::vector<Point> kept;
      for (std::size_t k = 0; k < active.size(); ++k) {
        if (s2[k] > threshold) {
          fit.rejected_lines.push_back(data.rows[static_cast<std::size_t>(active[k].row)].line);
        } else {
          kept.push_back(active[k]);
        }
      }
      if (kept.size() == active.size() || kept.size() < 4) break;
      active = kept;
    }
    if (!fit.rejected_lines.empty() && fit.rejected_lines.size() + 4 > pts.size()) fit.rejected_lines.clear();
    fit.used = static_cast<int>(active.size());
    double sum2 = 0;
    for (const Point& pt : active) sum2 += fit_error(f, pt, revolute).squaredNorm();
    fit.rms_m = std::sqrt(sum2 / static_cast<double>(active.size()));
    fit.axis.type = joint.type;
    if (revolute) {
      fit.axis.point = f.centre;
      fit.axis.direction = f.rotation.col(2);
      fit.radius_m = f.radius;
    } else {
      fit.axis.point = f.centre;
      fit.axis.direction = f.direction;
    }
    // Carry the axis back to zero readings of the joints before it.
    const std::vector<double>& q_sweep = data.rows[static_cast<std::size_t>(s.rows.front())].q;
    zero_axes.push_back(transformed(back_to_zero(zero_axes, q_sweep, j), fit.axis));
    for (const Point& pt : active) all_points.push_back(pt);
    result.fits.push_back(fit);
  }
  // The tool at zero readings: mean of every used point carried back.
  Vector3 sum = Vector3::Zero();
  Eigen::Matrix3d rotation_sum = Eigen::Matrix3d::Zero();
  bool orientation = data.has_orientation && nominal.tool == model::ToolKind::frame;
  for (const Point& pt : all_points) {
    const model::Measurement& m = data.rows[static_cast<std::size_t>(pt.row)];
    const model::Transform back = back_to_zero(zero_axes, m.q, n);
    sum += back * m.position;
    if (orientation && m.orientation) rotation_sum += back.rotation * m.orientation->toRotationMatrix();
  }
  model::Transform tool_home;
  tool_home.translation = sum / static_cast<double>(all_points.size());
  if (orientation) {
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(rotation_sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d r = svd.matrixU() * svd.matrixV().transpose();
    if (r.determinant() < 0) {
      Eigen::Matrix3d u = svd.matrixU();
      u.col(2) *= -1.0;
      r = u * svd.matrixV().transpose();
    }
    tool_home.rotation = r;
  }
  const std::vector<double> zero(static_cast<std::size_t>(n), 0.0);
  model::AxesToChainOptions axes_options;
  axes_options.parallel_tolerance_rad = options.parallel_tolerance_rad;
  result.model = model::chain_from_axes(nominal, zero_axes, zero, tool_home, axes_options);
  return result;
}

}  // namespace kincal::identify

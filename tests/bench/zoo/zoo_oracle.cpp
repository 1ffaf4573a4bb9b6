#include "zoo_oracle.hpp"

#include <memory>

#include <ceres/ceres.h>
#include <Eigen/Geometry>

namespace zoo {

namespace {

// Which parameters the oracle frees, and the truth they are laid over.
struct Layout {
  Truth start;
  bool pose = false;
  std::vector<std::size_t> scaled, compliant;  // joints with a reading scale / a compliance
  bool coupled = false;
  std::size_t joints = 0;
  int size() const {
    return 6 + (pose ? 6 : 3) + 7 * static_cast<int>(joints) + static_cast<int>(scaled.size() + compliant.size()) +
           (coupled ? 1 : 0);
  }
};

constexpr double kComplianceUnit = 1e-6;  // rad/(N m) per unit of the parameter: steps of 1e-6 stay small

Truth decode(const Layout& l, const double* x) {
  Truth t = l.start;
  t.device_T_root = l.start.device_T_root * small_motion(Eigen::Map<const Vector6>(x));
  Vector6 m = Vector6::Zero();
  for (int k = 0; k < (l.pose ? 6 : 3); ++k) m(k) = x[6 + k];
  t.flange_T_marker = l.start.flange_T_marker * small_motion(m);
  const double* p = x + 6 + (l.pose ? 6 : 3);
  for (std::size_t j = 0; j < l.joints; ++j, p += 7) {
    t.errors.origin[j] = Eigen::Map<const Vector6>(p);
    t.errors.zero[j] = p[6];
  }
  for (std::size_t j : l.scaled) t.errors.scale[j] = *p++;
  for (std::size_t j : l.compliant) t.errors.compliance_rad_per_nm[j] = kComplianceUnit * *p++;
  if (l.coupled) t.errors.coupling = *p;
  return t;
}

struct RowResidual {
  const Chain* chain;
  const Layout* layout;
  const Row* row;
  bool operator()(double const* const* x, double* residual) const {
    const Truth t = decode(*layout, x[0]);
    const Pose predicted = measured_truth(*chain, t, row->q);
    const Eigen::Vector3d d = predicted.translation() - row->measured.translation();
    for (int k = 0; k < 3; ++k) residual[k] = d(k) / t.position_sigma_m(k);
    if (layout->pose) {
      const Eigen::AngleAxisd turn(Eigen::Matrix3d(row->measured.linear().transpose() * predicted.linear()));
      const Eigen::Vector3d r = turn.angle() * turn.axis() / t.rotation_sigma_rad;
      for (int k = 0; k < 3; ++k) residual[3 + k] = r(k);
    }
    return true;
  }
};

Layout layout_of(const Chain& chain, const Truth& truth, std::mt19937& rng, bool geometry_only) {
  Layout l{Truth(chain.joints.size()),
           measures_pose(truth.instrument),
           {},
           {},
           truth.errors.coupled_to >= 0 && !geometry_only,
           chain.joints.size()};
  for (std::size_t j = 0; j < l.joints && !geometry_only; ++j) {
    if (truth.errors.scale[j] != 0.0) l.scaled.push_back(j);
    if (truth.compliance_known[j])
      l.start.errors.compliance_rad_per_nm[j] = truth.errors.compliance_rad_per_nm[j];
    else if (truth.errors.compliance_rad_per_nm[j] != 0.0)
      l.compliant.push_back(j);
  }
  l.start.instrument = truth.instrument;
  l.start.position_sigma_m = truth.position_sigma_m;
  l.start.rotation_sigma_rad = truth.rotation_sigma_rad;
  if (l.coupled) {
    l.start.errors.coupled_from = truth.errors.coupled_from;
    l.start.errors.coupled_to = truth.errors.coupled_to;
  }
  std::normal_distribution<double> n;
  Vector6 known = Vector6::Zero();
  known.head<3>() = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized() * 5e-3;
  if (l.pose) known.tail<3>() = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized() * (M_PI / 180.0);
  l.start.flange_T_marker = truth.flange_T_marker * small_motion(known);
  return l;
}

// device_T_root by the rigid fit (Umeyama) of the nominal points to the measured ones.
Pose register_points(const Chain& chain, const Truth& start, const std::vector<Row>& rows) {
  Eigen::Matrix3Xd from(3, static_cast<Eigen::Index>(rows.size())), to(3, static_cast<Eigen::Index>(rows.size()));
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const auto c = static_cast<Eigen::Index>(r);
    from.col(c) = (forward(chain, start.errors, rows[r].q) * start.flange_T_marker).translation();
    to.col(c) = rows[r].measured.translation();
  }
  return Pose(Eigen::umeyama(from, to, false));
}

}  // namespace

OracleFit fit_oracle(const Chain& chain, const Truth& truth, const std::vector<Row>& train, std::mt19937& rng,
                     bool geometry_only) {
  Layout layout = layout_of(chain, truth, rng, geometry_only);
  layout.start.device_T_root = register_points(chain, layout.start, train);
  std::vector<double> x(static_cast<std::size_t>(layout.size()), 0.0);
  ceres::Problem problem;
  for (const Row& row : train) {
    auto* cost =
        new ceres::DynamicNumericDiffCostFunction<RowResidual, ceres::CENTRAL>(new RowResidual{&chain, &layout, &row});
    cost->AddParameterBlock(layout.size());
    cost->SetNumResiduals(layout.pose ? 6 : 3);
    problem.AddResidualBlock(cost, nullptr, x.data());
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  // Run to convergence (Ceres' default cost tolerance): capped at 200 iterations with tolerances
  // of 1e-12, every service fit stopped at the cap, and where 20-40 rows leave the cost flat the
  // capped fit's held-out error was wherever it stopped (draw 1's mh5/tracker-point/service/40:
  // 0.0205 mm at 200 iterations, 0.0237 converged at 1291; on the same rows 10 um apart, 0.0292).
  options.max_num_iterations = 5000;
  options.function_tolerance = 1e-6;
  options.parameter_tolerance = 1e-10;
  options.num_threads = 2;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  OracleFit fit{decode(layout, x.data()), static_cast<int>(summary.iterations.size()),
                summary.termination_type == ceres::CONVERGENCE};
  return fit;
}

}  // namespace zoo

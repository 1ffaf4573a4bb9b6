#include "host/camera/hand_eye_refinement.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <Eigen/Cholesky>
#include <Eigen/SparseCore>

namespace kincal::camera {

namespace {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr double kRotationFloor_rad = 1e-6, kTranslationFloor_m = 1e-6, kCornerFloor_px = 1e-6;
constexpr int kMaxRounds = 20;
constexpr double kConverged = 0.01;  // relative change of every sigma

// 1 / sigma of each residual group, read by the costs at every evaluation (set between solves).
struct Weights {
  double corner = 1, rotation = 1, translation = 1;
};

// One board corner seen in one view: its residual (px, times weights->corner) at the projection of
// camera_T_target = X^-1 D^-1 H^-1 W (see the header), D = [exp(rho) | tau] from `correction`.
struct CornerCost {
  Matrix3d gripper_R_base;
  Vector3d base_t_gripper;
  Vector3d corner_m;
  double u_px, v_px;
  const CameraModel* camera;
  const Weights* weights;

  template <typename T>
  bool operator()(const T* gripper_T_camera, const T* base_T_target, const T* correction, T* residual) const {
    const T corner[3] = {T(corner_m.x()), T(corner_m.y()), T(corner_m.z())};
    T in_base[3];
    ceres::AngleAxisRotatePoint(base_T_target, corner, in_base);
    T offset[3];
    for (int k = 0; k < 3; ++k) offset[k] = in_base[k] + base_T_target[3 + k] - T(base_t_gripper[k]);
    T in_gripper[3];
    for (int r = 0; r < 3; ++r) {
      in_gripper[r] = T(gripper_R_base(r, 0)) * offset[0] + T(gripper_R_base(r, 1)) * offset[1] +
                      T(gripper_R_base(r, 2)) * offset[2] - correction[3 + r];
    }
    const T undo_correction[3] = {-correction[0], -correction[1], -correction[2]};
    T corrected[3];
    ceres::AngleAxisRotatePoint(undo_correction, in_gripper, corrected);
    for (int k = 0; k < 3; ++k) corrected[k] -= gripper_T_camera[3 + k];
    const T inverse_rotation[3] = {-gripper_T_camera[0], -gripper_T_camera[1], -gripper_T_camera[2]};
    T p[3];
    ceres::AngleAxisRotatePoint(inverse_rotation, corrected, p);
    const T x = p[0] / p[2], y = p[1] / p[2];
    const std::array<double, 5>& d = camera->distortion;
    const T r2 = x * x + y * y;
    const T radial = T(1) + T(d[0]) * r2 + T(d[1]) * r2 * r2 + T(d[4]) * r2 * r2 * r2;
    const T xd = x * radial + T(2 * d[2]) * x * y + T(d[3]) * (r2 + T(2) * x * x);
    const T yd = y * radial + T(d[2]) * (r2 + T(2) * y * y) + T(2 * d[3]) * x * y;
    const cv::Matx33d& k = camera->camera_matrix;
    residual[0] = (T(k(0, 0)) * xd + T(k(0, 2)) - T(u_px)) * T(weights->corner);
    residual[1] = (T(k(1, 1)) * yd + T(k(1, 2)) - T(v_px)) * T(weights->corner);
    return true;
  }
};

// The prior of one pose's correction: rho / sigma_rotation, tau / sigma_translation.
struct CorrectionPrior {
  const Weights* weights;

  template <typename T>
  bool operator()(const T* correction, T* residual) const {
    for (int k = 0; k < 3; ++k) {
      residual[k] = correction[k] * T(weights->rotation);
      residual[3 + k] = correction[3 + k] * T(weights->translation);
    }
    return true;
  }
};

std::array<double, 6> to_parameters(const Isometry3d& m) {
  const Eigen::AngleAxisd aa(m.rotation());
  const Vector3d r = aa.angle() * aa.axis();
  return {r.x(), r.y(), r.z(), m.translation().x(), m.translation().y(), m.translation().z()};
}

Isometry3d from_parameters(const std::array<double, 6>& p) {
  const Vector3d r(p[0], p[1], p[2]);
  Isometry3d m = Isometry3d::Identity();
  if (r.norm() > 0) m.linear() = Eigen::AngleAxisd(r.norm(), r.normalized()).toRotationMatrix();
  m.translation() = Vector3d(p[3], p[4], p[5]);
  return m;
}

// The inverse of the normal matrix of the weighted problem and its residuals, parameters in the
// order X, W, corrections (rotation then translation of each), residuals corners then priors.
struct Normal {
  Eigen::MatrixXd inverse;
  std::vector<double> residuals;
};

// The chain's least-squares problem; the parameter blocks live here, the costs read `weights`.
class ChainProblem {
 public:
  ChainProblem(const std::vector<const BoardDetection*>& detections, const std::vector<Isometry3d>& base_T_gripper,
               const CameraModel& camera, const Isometry3d& gripper_T_camera, const Isometry3d& base_T_target,
               bool correct_poses)
      : x_(to_parameters(gripper_T_camera)),
        w_(to_parameters(base_T_target)),
        corrections_(correct_poses ? detections.size() : 1, std::array<double, 6>{}),
        correct_poses_(correct_poses) {
    for (std::size_t i = 0; i < detections.size(); ++i) {
      const Isometry3d gripper_T_base = base_T_gripper[i].inverse();
      double* correction = corrections_[correct_poses ? i : 0].data();
      for (std::size_t c = 0; c < detections[i]->board_m.size(); ++c) {
        const cv::Point3f& corner = detections[i]->board_m[c];
        const cv::Point2f& px = detections[i]->image_px[c];
        auto* cost = new ceres::AutoDiffCostFunction<CornerCost, 2, 6, 6, 6>(
            new CornerCost{gripper_T_base.rotation(), base_T_gripper[i].translation(),
                           Vector3d(corner.x, corner.y, corner.z), px.x, px.y, &camera, &weights_});
        residual_blocks_.push_back(problem_.AddResidualBlock(cost, nullptr, x_.data(), w_.data(), correction));
      }
    }
    corner_rows_ = 2 * residual_blocks_.size();
    if (correct_poses) {
      for (std::array<double, 6>& c : corrections_) {
        residual_blocks_.push_back(problem_.AddResidualBlock(
            new ceres::AutoDiffCostFunction<CorrectionPrior, 6, 6>(new CorrectionPrior{&weights_}), nullptr, c.data()));
      }
    } else {
      problem_.SetParameterBlockConstant(corrections_.front().data());
    }
  }

  void set_noise(const ChainNoise& sigma) {
    weights_.corner = 1 / sigma.corner_px;
    weights_.rotation = correct_poses_ ? 1 / sigma.pose_rotation_rad : 0;
    weights_.translation = correct_poses_ ? 1 / sigma.pose_translation_m : 0;
  }

  void solve() {
    ceres::Solver::Options options;
    options.linear_solver_type = correct_poses_ ? ceres::DENSE_SCHUR : ceres::DENSE_QR;
    options.max_num_iterations = 200;
    options.function_tolerance = 1e-12;
    options.parameter_tolerance = 1e-12;
    options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem_, &summary);
    if (!summary.IsSolutionUsable()) {
      throw CalibrationError("hand-eye calibration: the refinement failed: " + summary.message);
    }
  }

  Normal normal() {
    ceres::Problem::EvaluateOptions options;
    options.parameter_blocks = {x_.data(), w_.data()};
    if (correct_poses_)
      for (std::array<double, 6>& c : corrections_) options.parameter_blocks.push_back(c.data());
    options.residual_blocks = residual_blocks_;
    Normal out;
    ceres::CRSMatrix crs;
    problem_.Evaluate(options, nullptr, &out.residuals, nullptr, &crs);
    const Eigen::Map<const Eigen::SparseMatrix<double, Eigen::RowMajor>> j(
        crs.num_rows, crs.num_cols, static_cast<Eigen::Index>(crs.values.size()), crs.rows.data(), crs.cols.data(),
        crs.values.data());
    const Eigen::MatrixXd n = Eigen::MatrixXd(Eigen::SparseMatrix<double>(j.transpose() * j));
    out.inverse = n.ldlt().solve(Eigen::MatrixXd::Identity(n.rows(), n.cols()));
    return out;
  }

  // Förstner's estimate of each group's sigma from the solution at the current weights (header).
  ChainNoise variance_components(const ChainNoise& current) {
    const Normal n = normal();
    if (!n.inverse.allFinite()) return current;  // a singular normal matrix: no estimate
    double trace_rotation = 0, trace_translation = 0, ss_rotation = 0, ss_translation = 0;
    if (correct_poses_) {
      for (std::size_t i = 0; i < corrections_.size(); ++i) {
        for (std::size_t k = 0; k < 3; ++k) {
          const auto at = static_cast<Eigen::Index>(12 + 6 * i + k);
          trace_rotation += n.inverse(at, at) * weights_.rotation * weights_.rotation;
          trace_translation += n.inverse(at + 3, at + 3) * weights_.translation * weights_.translation;
          ss_rotation += corrections_[i][k] * corrections_[i][k];
          ss_translation += corrections_[i][3 + k] * corrections_[i][3 + k];
        }
      }
    }
    double ss_corner = 0;
    for (std::size_t r = 0; r < corner_rows_; ++r) ss_corner += n.residuals[r] * n.residuals[r];
    ss_corner /= weights_.corner * weights_.corner;
    const double unknowns = static_cast<double>(n.inverse.rows());
    const double pose_rows = 3.0 * static_cast<double>(corrections_.size());
    const auto component = [](double ss, double redundancy, double before, double floor) {
      return redundancy > 0.5 ? std::max(floor, std::sqrt(ss / redundancy)) : before;
    };
    ChainNoise next;
    next.corner_px =
        component(ss_corner, static_cast<double>(corner_rows_) - (unknowns - trace_rotation - trace_translation),
                  current.corner_px, kCornerFloor_px);
    if (correct_poses_) {
      next.pose_rotation_rad =
          component(ss_rotation, pose_rows - trace_rotation, current.pose_rotation_rad, kRotationFloor_rad);
      next.pose_translation_m =
          component(ss_translation, pose_rows - trace_translation, current.pose_translation_m, kTranslationFloor_m);
    }
    return next;
  }

  // X's standard deviations at the current weights: the inverse normal matrix's first block; left
  // zero when the normal matrix is singular.
  void gripper_T_camera_sigma(ChainRefinement& out) {
    const Normal n = normal();
    if (!n.inverse.allFinite()) return;
    for (std::size_t k = 0; k < 3; ++k) {
      const auto at = static_cast<Eigen::Index>(k);
      out.rotation_sigma_rad[k] = std::sqrt(std::max(0.0, n.inverse(at, at)));
      out.translation_sigma_m[k] = std::sqrt(std::max(0.0, n.inverse(at + 3, at + 3)));
    }
  }

  Isometry3d gripper_T_camera() const { return from_parameters(x_); }
  Isometry3d base_T_target() const { return from_parameters(w_); }

 private:
  ceres::Problem problem_;
  Weights weights_;
  std::array<double, 6> x_, w_;
  std::vector<std::array<double, 6>> corrections_;  // one per view; a single constant zero when exact
  bool correct_poses_;
  std::vector<ceres::ResidualBlockId> residual_blocks_;  // corners, then the priors
  std::size_t corner_rows_ = 0;
};

bool close(double next, double before) { return std::abs(next - before) <= kConverged * before; }

}  // namespace

ChainRefinement refine_chain(const std::vector<const BoardDetection*>& detections,
                             const std::vector<Isometry3d>& base_T_gripper, const CameraModel& camera,
                             const Isometry3d& gripper_T_camera, const Isometry3d& base_T_target,
                             const ChainNoise& start, bool correct_poses) {
  ChainProblem problem(detections, base_T_gripper, camera, gripper_T_camera, base_T_target, correct_poses);
  ChainRefinement out;
  out.sigma = {std::max(kCornerFloor_px, start.corner_px),
               correct_poses ? std::max(kRotationFloor_rad, start.pose_rotation_rad) : 0.0,
               correct_poses ? std::max(kTranslationFloor_m, start.pose_translation_m) : 0.0};
  while (out.rounds < kMaxRounds) {
    problem.set_noise(out.sigma);
    problem.solve();
    ++out.rounds;
    const ChainNoise next = problem.variance_components(out.sigma);
    // Poses held exact leave one group, whose scale moves no estimate: its first estimate is final.
    const bool converged = !correct_poses || (close(next.corner_px, out.sigma.corner_px) &&
                                              close(next.pose_rotation_rad, out.sigma.pose_rotation_rad) &&
                                              close(next.pose_translation_m, out.sigma.pose_translation_m));
    out.sigma = next;
    if (converged) break;
  }
  problem.set_noise(out.sigma);
  problem.gripper_T_camera_sigma(out);
  out.gripper_T_camera = problem.gripper_T_camera();
  out.base_T_target = problem.base_T_target();
  return out;
}

}  // namespace kincal::camera

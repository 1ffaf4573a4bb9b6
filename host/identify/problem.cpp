#include "host/identify/problem.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include <Eigen/Geometry>

#include "host/model/model_file.hpp"

namespace kincal::identify {

namespace {

bool is_link(core::ParameterKind kind) { return kind <= core::ParameterKind::link_beta; }
int motion_index(core::ParameterKind kind) {
  return static_cast<int>(kind) - static_cast<int>(core::ParameterKind::base_x);
}

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

}  // namespace

Eigen::Matrix3d so3_right_jacobian(const Eigen::Vector3d& r) {
  const double t2 = r.squaredNorm();
  const Eigen::Matrix3d k = skew(r);
  if (t2 < 1e-10) return Eigen::Matrix3d::Identity() - 0.5 * k + k * k / 6.0;
  const double t = std::sqrt(t2);
  return Eigen::Matrix3d::Identity() - (1.0 - std::cos(t)) / t2 * k + (t - std::sin(t)) / (t2 * t) * k * k;
}

Eigen::Matrix3d so3_right_jacobian_inverse(const Eigen::Vector3d& r) {
  const double t2 = r.squaredNorm();
  const Eigen::Matrix3d k = skew(r);
  if (t2 < 1e-10) return Eigen::Matrix3d::Identity() + 0.5 * k + k * k / 12.0;
  const double t = std::sqrt(t2);
  return Eigen::Matrix3d::Identity() + 0.5 * k + (1.0 / t2 - (1.0 + std::cos(t)) / (2.0 * t * std::sin(t))) * k * k;
}

Eigen::Matrix<double, 6, 1> small_motion(const Transform& a, const Transform& b) {
  Eigen::Matrix<double, 6, 1> m;
  m.head<3>() = a.rotation.transpose() * (b.translation - a.translation);
  m.tail<3>() = so3_log(a.rotation.transpose() * b.rotation);
  return m;
}

Eigen::Vector3d so3_log(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.angle() * aa.axis();
}

Parameterization::Parameterization(const RobotModel& start, ParameterIds ids)
    : start_(start), start_chain_(model::to_chain(start)), ids_(std::move(ids)), current_(start) {
  if (ids_.size() > static_cast<std::size_t>(core::kMaxErrorParameters) + 7 * core::kMaxJoints)
    throw std::invalid_argument("too many parameters");
  for (const core::ParameterId& id : ids_) {
    if (model::is_joint_map_parameter(id.kind)) {
      link_column_.push_back(-2 - static_cast<int>(joint_map_ids_.size()));  // resolved below
      joint_map_ids_.push_back(id);
      continue;
    }
    if (!is_link(id.kind)) {
      link_column_.push_back(-1);
      continue;
    }
    if (augmented_.count >= core::kMaxErrorParameters - 12) throw std::invalid_argument("too many parameters");
    link_column_.push_back(augmented_.count);
    augmented_.ids[static_cast<std::size_t>(augmented_.count++)] = id;
  }
  for (int k = 0; k < 12; ++k)
    augmented_.ids[static_cast<std::size_t>(augmented_.count++)] = {
        static_cast<core::ParameterKind>(static_cast<int>(core::ParameterKind::base_x) + k), 0};
  for (int& c : link_column_)
    if (c <= -2) c = augmented_.count + (-2 - c);
  plain_ = joint_map_ids_.empty() && !model::has_joint_map(start_) && !model::has_compliance(start_);
  delta_.assign(ids_.size(), 0.0);
  set(delta_);
}

void Parameterization::set(std::span<const double> delta) {
  if (delta.size() != ids_.size()) throw std::invalid_argument("Parameterization::set: wrong size");
  if (ready_ && std::equal(delta.begin(), delta.end(), delta_.begin())) return;
  std::copy(delta.begin(), delta.end(), delta_.begin());
  core::ParameterSet chosen;
  core::ErrorVector<double> errors = core::ErrorVector<double>::Zero();
  Eigen::Vector3d base_r = Eigen::Vector3d::Zero(), tool_r = Eigen::Vector3d::Zero();
  current_ = start_;
  for (std::size_t k = 0; k < ids_.size(); ++k) {
    if (model::is_joint_map_parameter(ids_[k].kind)) {
      model::add_joint_map_error(current_, ids_[k], delta_[k]);
      continue;
    }
    chosen.ids[static_cast<std::size_t>(chosen.count)] = ids_[k];
    errors(chosen.count++) = delta_[k];
    if (!is_link(ids_[k].kind)) {
      const int m = motion_index(ids_[k].kind);
      if (m == 3 || m == 4 || m == 5) base_r(m - 3) += delta_[k];
      if (m == 9 || m == 10 || m == 11) tool_r(m - 9) += delta_[k];
    }
  }
  core::ChainModel<double> current;
  if (core::apply_parameter_errors(start_chain_, chosen, errors, current) != core::ErrorModelStatus::ok)
    throw std::invalid_argument("Parameterization: a parameter names a joint the model does not have");
  model::carry_centres_of_mass(current_, start_chain_, current);
  core::prepare_chain(current, prepared_);
  current_chain_ = current;
  base_exp_t_ = Eigen::AngleAxisd(base_r.norm(), base_r.norm() > 0 ? base_r.normalized() : Eigen::Vector3d::UnitZ())
                    .toRotationMatrix()
                    .transpose();
  tool_exp_t_ = Eigen::AngleAxisd(tool_r.norm(), tool_r.norm() > 0 ? tool_r.normalized() : Eigen::Vector3d::UnitZ())
                    .toRotationMatrix()
                    .transpose();
  base_jr_ = so3_right_jacobian(base_r);
  tool_jr_ = so3_right_jacobian(tool_r);
  ready_ = true;
}

RobotModel Parameterization::model() const {
  Eigen::VectorXd d = Eigen::Map<const Eigen::VectorXd>(delta_.data(), static_cast<Eigen::Index>(delta_.size()));
  return model::apply_parameter_errors(start_, ids_, d);
}

template <class Columns>
void Parameterization::motion_corrected(const Columns& e, Eigen::MatrixXd& jacobian) const {
  const int motions = augmented_.count - 12;
  // Motion columns corrected to d/d(delta) at the current delta.
  Eigen::Matrix<double, 6, 12> m;
  m.leftCols<3>() = e.template middleCols<3>(motions) * base_exp_t_;
  m.middleCols<3>(3) = e.template middleCols<3>(motions + 3) * base_jr_;
  m.middleCols<3>(6) = e.template middleCols<3>(motions + 6) * tool_exp_t_;
  m.rightCols<3>() = e.template middleCols<3>(motions + 9) * tool_jr_;
  jacobian.resize(6, static_cast<Eigen::Index>(ids_.size()));
  for (std::size_t k = 0; k < ids_.size(); ++k) {
    const auto c = static_cast<Eigen::Index>(k);
    jacobian.col(c) = link_column_[k] >= 0 ? Eigen::Matrix<double, 6, 1>(e.col(link_column_[k]))
                                           : Eigen::Matrix<double, 6, 1>(m.col(motion_index(ids_[k].kind)));
  }
}

Transform Parameterization::pose(std::span<const double> q, Eigen::MatrixXd* jacobian) const {
  if (!plain_) {
    const model::ChainAtJoints at = model::evaluate_chain(current_, current_chain_, q);
    if (jacobian) {
      ParameterIds all(augmented_.ids.begin(), augmented_.ids.begin() + augmented_.count);
      all.insert(all.end(), joint_map_ids_.begin(), joint_map_ids_.end());
      motion_corrected(model::parameter_jacobian(current_, at, q, all), *jacobian);
    }
    return at.frames.base_T_tool;
  }
  const core::JointVector<double> qv = model::joint_vector(q);
  std::array<core::SinCos<double>, core::kMaxJoints> trig{};
  core::joint_trig(prepared_, qv, trig);
  core::ChainFrames<double> frames;
  core::forward_kinematics(prepared_, qv, trig, frames);
  if (jacobian) {
    core::ErrorMatrix<double> e;
    if (core::parameter_jacobian(prepared_, qv, trig, frames, augmented_, e) != core::ErrorModelStatus::ok)
      throw std::invalid_argument("Parameterization: bad parameter set");
    motion_corrected(e, *jacobian);
  }
  return frames.base_T_tool;
}

namespace {

// The sum of the distances between consecutive frames at zero readings, and the tool's from the
// last: no part of the arm is farther than this from any of its frames.
double arm_size_m(const model::RobotModel& m) {
  const model::ChainAtJoints at = model::chain_at_joints(m, std::vector<double>(m.joints.size(), 0.0));
  double size = 0.0;
  for (int i = 0; i < at.frames.joint_count; ++i)
    size += (at.frames.base_T_frame[static_cast<std::size_t>(i) + 1].translation -
             at.frames.base_T_frame[static_cast<std::size_t>(i)].translation)
                .norm();
  return size + (at.frames.base_T_tool.translation -
                 at.frames.base_T_frame[static_cast<std::size_t>(at.frames.joint_count)].translation)
                    .norm();
}

}  // namespace

PhysicalBounds physical_bounds(const Parameterization& p, bool negative_masses) {
  const auto n = static_cast<Eigen::Index>(p.size());
  PhysicalBounds b{Eigen::VectorXd::Constant(n, -std::numeric_limits<double>::infinity()),
                   Eigen::VectorXd::Constant(n, std::numeric_limits<double>::infinity())};
  std::optional<double> size;
  for (std::size_t k = 0; k < p.ids().size(); ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    const core::ParameterKind kind = p.ids()[k].kind;
    if (!model::is_joint_map_parameter(kind)) continue;
    const model::Joint& joint = p.start().joints.at(p.ids()[k].link);
    if (kind == model::kJointCompliance) {
      b.lower(i) = -joint.compliance.value_or(0.0);
      b.upper(i) = model::kMaxCompliance - joint.compliance.value_or(0.0);
    } else if (kind == model::kLinkMass) {
      b.lower(i) = (negative_masses ? -model::kMaxMass_kg : 0.0) - joint.mass_kg;
      b.upper(i) = model::kMaxMass_kg - joint.mass_kg;
    } else if (kind == model::kJointScale) {
      b.lower(i) = model::kMinScale - joint.scale.value_or(1.0);
      b.upper(i) = model::kMaxScale - joint.scale.value_or(1.0);
    } else if (kind == model::kJointCoupling) {
      const std::size_t from = p.ids()[k].link - 1U;
      const double at = from < joint.coupling.size() ? joint.coupling[from] : 0.0;
      b.lower(i) = -model::kMaxCoupling - at;
      b.upper(i) = model::kMaxCoupling - at;
    } else if (model::is_mass_parameter(kind)) {  // a centre of mass coordinate
      if (!size) size = arm_size_m(p.start());
      const double at =
          joint.centre_of_mass_m(static_cast<Eigen::Index>(kind) - static_cast<Eigen::Index>(model::kLinkCentreX));
      b.lower(i) = std::min(0.0, -*size - at);  // a start beyond it (a user's file) is kept
      b.upper(i) = std::max(0.0, *size - at);
    }
  }
  return b;
}

std::vector<bool> on_bound(const PhysicalBounds& b, std::span<const double> delta) {
  std::vector<bool> on(delta.size(), false);
  for (std::size_t k = 0; k < delta.size(); ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    for (const double bound : {b.lower(i), b.upper(i)})
      if (std::isfinite(bound) && std::abs(delta[k] - bound) <= 1e-9 * std::abs(bound)) on[k] = true;
  }
  return on;
}

std::vector<Matrix6> instrument_covariances(const model::Dataset& data, double sigma_m, double orientation_sigma_rad) {
  std::vector<Matrix6> c;
  for (const model::Measurement& m : data.rows) {
    if (m.pose_covariance) {
      c.push_back(*m.pose_covariance);
      continue;
    }
    Matrix6 v = Matrix6::Zero();
    v.topLeftCorner<3, 3>() =
        m.covariance ? *m.covariance : Eigen::Matrix3d(Eigen::Matrix3d::Identity() * sigma_m * sigma_m);
    v.bottomRightCorner<3, 3>().diagonal().setConstant(orientation_sigma_rad * orientation_sigma_rad);
    c.push_back(v);
  }
  return c;
}

Weights covariance_weights(const std::vector<Matrix6>& covariance, int size, double position2, double orientation2) {
  Weights w;
  w.size = size;
  for (const Matrix6& c : covariance) {
    Matrix6 v = c;
    v.topLeftCorner<3, 3>().diagonal().array() += position2;
    v.bottomRightCorner<3, 3>().diagonal().array() += orientation2;
    const Eigen::LLT<Eigen::MatrixXd> llt(v.topLeftCorner(size, size));
    if (llt.info() != Eigen::Success) throw std::invalid_argument("a row's covariance is not positive definite");
    Matrix6 l = Matrix6::Zero();
    l.topLeftCorner(size, size) = llt.matrixL().solve(Eigen::MatrixXd::Identity(size, size));
    w.factor.push_back(l);
  }
  return w;
}

Weights unit_weights(std::size_t rows, int size) {
  Weights w;
  w.size = size;
  w.factor.assign(rows, Matrix6::Identity());
  return w;
}

Weights make_weights(const model::Dataset& data, double sigma_m, double orientation_sigma_rad) {
  const bool orientation = data.has_orientation && orientation_sigma_rad > 0.0;
  return covariance_weights(instrument_covariances(data, sigma_m, orientation_sigma_rad), orientation ? 6 : 3);
}

void row_residual(const Parameterization& p, const model::Measurement& m, const Matrix6& factor, int size,
                  double* residual, Eigen::MatrixXd* jacobian) {
  Eigen::MatrixXd e;
  const Transform pose = p.pose(m.q, jacobian ? &e : nullptr);
  Eigen::Matrix<double, 6, 1> error = Eigen::Matrix<double, 6, 1>::Zero();
  error.head<3>() = m.position - pose.translation;
  const bool orientation = size == 6 && m.orientation;
  if (orientation) error.tail<3>() = so3_log(m.orientation->toRotationMatrix() * pose.rotation.transpose());
  const auto l = factor.topLeftCorner(size, size).triangularView<Eigen::Lower>();
  Eigen::Map<Eigen::VectorXd>(residual, size) = l * error.head(size);
  if (jacobian) {
    // d(error)/d(delta): the pose's twist e moves the model's point and rotation (on the left).
    Eigen::MatrixXd d = Eigen::MatrixXd::Zero(size, e.cols());
    d.topRows(3) = -e.topRows(3);
    if (orientation) d.bottomRows(3) = -so3_right_jacobian_inverse(error.tail<3>()) * e.bottomRows(3);
    *jacobian = l * d;
  }
}

void stacked(const Parameterization& p, const model::Dataset& data, const Weights& w, const std::vector<int>& rows,
             Eigen::VectorXd& residual, Eigen::MatrixXd* jacobian) {
  const int size = w.size;
  const auto n = static_cast<Eigen::Index>(rows.size()) * size;
  residual.resize(n);
  if (jacobian) jacobian->resize(n, p.size());
  Eigen::MatrixXd j;
  Eigen::Index at = 0;
  for (int r : rows) {
    const auto k = static_cast<std::size_t>(r);
    row_residual(p, data.rows[k], w.factor[k], size, residual.data() + at, jacobian ? &j : nullptr);
    if (jacobian) jacobian->middleRows(at, size) = j;
    at += size;
  }
}

}  // namespace kincal::identify

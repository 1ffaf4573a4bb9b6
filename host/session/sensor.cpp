#include "host/session/sensor.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/Eigenvalues>

#include "firmware/core/planar_pose.hpp"
#include "host/camera/calibration_file.hpp"
#include "host/target/doty_square.hpp"
#include "shared/measurement_report.hpp"

namespace kincal::session {

namespace {

std::string at_pose(int index) { return "pose " + std::to_string(index) + ": "; }

// turn * C * turn^T takes a covariance of (x, y, z, rx, ry, rz), its errors on the left in the
// square frame, into the strip frame.
model::Matrix6 turn_of(const model::Matrix3& strip_R_square) {
  model::Matrix6 turn = model::Matrix6::Zero();
  turn.topLeftCorner<3, 3>() = strip_R_square;
  turn.bottomRightCorner<3, 3>() = strip_R_square;
  return turn;
}

// The report's pose covariance in the dataset's convention and the strip frame (sensor.hpp), made
// positive definite. The report's errors are the truth's on the reported pose (true = exp([delta]x)
// reported, and t_true = t_reported + dt: firmware/app/platform_measurement.cpp), the dataset's the
// measurement's on the truth: both signs flip, so the covariance, cross block included, is the
// same. Both errors are in the square's frame, on the left: strip_R_square turns them into the
// strip's. The correlations' rounding can leave a nearly singular covariance slightly indefinite:
// the correlation matrix's eigenvalues below 1e-6 of its largest are raised to it (in
// correlations, not in m and rad, whose scales differ by orders).
model::Matrix6 strip_pose_covariance(const shared::MeasurementReport& report, const model::Matrix3& strip_R_square) {
  const std::array<double, 36> c = shared::pose_covariance(report);
  const model::Matrix6 square = Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(c.data());
  const Eigen::Matrix<double, 6, 1> sigma = square.diagonal().cwiseSqrt();
  const model::Matrix6 rho = sigma.cwiseInverse().asDiagonal() * square * sigma.cwiseInverse().asDiagonal();
  const Eigen::SelfAdjointEigenSolver<model::Matrix6> eigen(rho);
  const double floor = eigen.eigenvalues().maxCoeff() * 1e-6;
  const Eigen::Matrix<double, 6, 1> values = eigen.eigenvalues().cwiseMax(floor);
  const model::Matrix6 turn = turn_of(strip_R_square);
  const model::Matrix6 strip = turn * sigma.asDiagonal() * eigen.eigenvectors() * values.asDiagonal() *
                               eigen.eigenvectors().transpose() * sigma.asDiagonal() * turn.transpose();
  return (strip + strip.transpose()) / 2;  // exactly symmetric, as the journal checks
}

// The rotation vector (rad) of a rotation matrix.
model::Vector3 rotation_vector(const model::Matrix3& r) {
  const Eigen::AngleAxisd a(r);
  return a.angle() * a.axis();
}

// square_T_camera as the platform solves it from `points` with `camera`.
model::Transform solved_pose(const core::CameraIntrinsics& camera, std::span<const core::PlanarCorrespondence> points) {
  core::PlanarPoseOptions options;  // the platform's: 0.1 px (MeasurementPipeline::kPixelSigmaPx), one
  options.perspective_passes = 1;   // perspective pass (fiducials of a non-zero side)
  core::PlanarPoseWorkspace workspace;
  core::PlanarPose pose;
  if (const core::PlanarPoseStatus status = core::planar_pose(camera, points, nullptr, options, workspace, pose);
      status != core::PlanarPoseStatus::ok)
    throw SessionError(
        "the platform camera's share of the pose covariance: the pose under moved intrinsics failed (status " +
        std::to_string(static_cast<int>(status)) + " of core::PlanarPoseStatus, firmware/core/planar_pose.hpp)");
  const core::RigidTransform<float> square_T_camera = pose.camera_T_target.inverse();
  model::Transform out;
  out.rotation = square_T_camera.rotation.cast<double>();
  out.translation = square_T_camera.translation.cast<double>();
  return out;
}

// Rotation vector (rad) to a rotation matrix.
model::Matrix3 rotation_from_vector(const model::Vector3& phi) {
  const double angle = phi.norm();
  if (angle == 0.0) return model::Matrix3::Identity();
  return Eigen::AngleAxisd(angle, phi / angle).toRotationMatrix();
}

}  // namespace

core::CameraIntrinsics moved_intrinsics(const core::CameraIntrinsics& camera, const IntrinsicsVector& delta) {
  core::CameraIntrinsics c = camera;
  float* values[9] = {&c.fx_px,         &c.fy_px,         &c.cx_px,         &c.cy_px,        &c.distortion.k1,
                      &c.distortion.k2, &c.distortion.p1, &c.distortion.p2, &c.distortion.k3};
  for (int i = 0; i < 9; ++i) *values[i] = static_cast<float>(static_cast<double>(*values[i]) + delta(i));
  return c;
}

PlatformCamera load_platform_camera(const std::string& path) {
  const std::optional<camera::IntrinsicsCovariance> uncertainty = camera::load_camera_uncertainty(path);
  if (!uncertainty)
    throw camera::CalibrationError(
        path +
        ": key 'intrinsics_covariance' missing: the platform camera's share of the pose covariance "
        "needs the intrinsics' covariance (`kincal camera calibrate` writes it)");
  PlatformCamera out{core::camera_from_block(camera::to_platform(camera::load_camera(path))),
                     Eigen::Matrix<double, 9, 9>::Zero(), target::kDotyFiducialSideM};
  for (int i = 0; i < 9; ++i)
    for (int j = 0; j < 9; ++j) out.covariance(i, j) = uncertainty->covariance(i, j);
  return out;
}

model::Matrix6 camera_share(const PlatformCamera& c, const model::Transform& square_T_camera) {
  const model::Transform camera_T_square = square_T_camera.inverse();
  core::RigidTransform<float> pose;
  pose.rotation = camera_T_square.rotation.cast<float>();
  pose.translation = camera_T_square.translation.cast<float>();
  std::array<core::PlanarCorrespondence, 6> points;
  const std::array<target::FiducialRect, 6> fiducials = target::doty_square_fiducials(c.fiducial_side_m);
  for (std::size_t k = 0; k < fiducials.size(); ++k) {
    core::PlanarCorrespondence& p = points[k];
    p.target_m = fiducials[k].centre_m.cast<float>();
    p.fiducial_half_size_m = (fiducials[k].size_m / 2).cast<float>();
    const core::Vector3<float> centre =
        pose.rotation * core::Vector3<float>(p.target_m.x(), p.target_m.y(), 0.0f) + pose.translation;
    core::Vector2<float> bias;
    if (core::project_point(c.camera, centre, p.pixel_px) != core::CameraStatus::ok ||
        !core::fiducial_centroid_bias_px(c.camera, pose, p.target_m, p.fiducial_half_size_m, bias))
      throw SessionError("the platform camera's share of the pose covariance: fiducial p" +
                         std::to_string(fiducials[k].id) + " is not in the camera's view from the reported pose");
    p.pixel_px += bias;
  }
  model::Matrix6 share = model::Matrix6::Zero();
  for (const IntrinsicsVector& d : covariance_directions(c.covariance, "the platform camera's intrinsics covariance")) {
    const model::Transform plus = solved_pose(moved_intrinsics(c.camera, d), points);
    const model::Transform minus = solved_pose(moved_intrinsics(c.camera, -d), points);
    Eigen::Matrix<double, 6, 1> change;
    change << (plus.translation - minus.translation) / 2,
        rotation_vector(plus.rotation * minus.rotation.transpose()) / 2;
    share += change * change.transpose();
  }
  return share;
}

PlatformPoseSensor::PlatformPoseSensor(can::PlatformClient& client, std::vector<model::Transform> strip_T_square,
                                       std::optional<PlatformCamera> camera)
    : client_(client), strip_T_square_(std::move(strip_T_square)), camera_(std::move(camera)) {
  if (strip_T_square_.empty()) throw SessionError("platform sensor: the strip has no calibration squares");
  if (camera_) (void)covariance_directions(camera_->covariance, "the platform camera's intrinsics covariance");
  try {
    client_.set_mode(true, false, true);
  } catch (const can::PlatformError& e) {
    throw SessionError(std::string("the sensor platform does not answer: ") + e.what());
  }
}

int PlatformPoseSensor::measured_square(const model::Transform& square_T_camera,
                                        const model::Transform& predicted) const {
  int best = 0;
  double best_distance = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < strip_T_square_.size(); ++k) {
    const double distance = ((strip_T_square_[k] * square_T_camera).translation - predicted.translation).norm();
    if (distance < best_distance) {
      best_distance = distance;
      best = static_cast<int>(k);
    }
  }
  return best;
}

Observation PlatformPoseSensor::measure(int index, const model::Transform& predicted) {
  using namespace shared;
  const std::uint8_t sections = section::kRanges | section::kPlane | section::kFiducials | section::kPose;
  MeasurementReport report;
  try {
    report = client_.measure(sections);
  } catch (const can::PlatformError& e) {
    throw SessionError(at_pose(index) + "the sensor platform did not measure: " + e.what());
  }
  if (report.status != MeasureStatus::kOk || !(report.sections & section::kPose)) {
    std::string why = can::to_string(report.status);
    if (report.status == MeasureStatus::kNoTarget) {
      why += (report.sections & section::kFiducials)
                 ? " (" + std::to_string(report.fiducial_count) + " fiducials identified, 3 needed)"
                 : " (no calibration square in view)";
      if (!(report.sections & section::kPlane)) why += "; no flat surface under the rangers";
    }
    throw SessionError(at_pose(index) + "the platform's measurement failed: " + why);
  }
  model::Transform square_T_camera;
  model::Vector3 phi;
  for (int i = 0; i < 3; ++i) {
    square_T_camera.translation(i) = report.translation_raw[static_cast<std::size_t>(i)] * kTranslationLsbM;
    phi(i) = report.rotation_raw[static_cast<std::size_t>(i)] * kRotationLsbRad;
  }
  square_T_camera.rotation = rotation_from_vector(phi);
  const int square = measured_square(square_T_camera, predicted);
  const model::Transform strip_T_camera = strip_T_square_[static_cast<std::size_t>(square)] * square_T_camera;
  Observation o;
  o.position = strip_T_camera.translation;
  o.orientation = Eigen::Quaterniond(strip_T_camera.rotation);
  const model::Matrix3& strip_R_square = strip_T_square_[static_cast<std::size_t>(square)].rotation;
  model::Matrix6 covariance = strip_pose_covariance(report, strip_R_square);
  if (camera_) {
    try {
      const model::Matrix6 turn = turn_of(strip_R_square);
      covariance += turn * camera_share(*camera_, square_T_camera) * turn.transpose();
    } catch (const SessionError& e) {
      throw SessionError(at_pose(index) + e.what());
    }
    covariance = (covariance + covariance.transpose()) / 2;
  }
  o.pose_covariance = covariance;
  o.covariance = model::Matrix3(covariance.topLeftCorner<3, 3>());
  o.sequence = report.sequence;
  o.timestamp_s = report.timestamp_us * 1e-6;
  // The report's square is the pose's reference; the platform may have used its neighbours too.
  o.note = "square " + std::to_string(square + 1) +
           (report.pose_squares > 1 ? " (pose over " + std::to_string(report.pose_squares) + " squares)" : "") + ", " +
           std::to_string(report.fiducial_count) + " fiducials";
  return o;
}

}  // namespace kincal::session

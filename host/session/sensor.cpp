#include "host/session/sensor.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/Eigenvalues>

#include "shared/measurement_report.hpp"

namespace kincal::session {

namespace {

std::string at_pose(int index) { return "pose " + std::to_string(index) + ": "; }

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
  model::Matrix6 turn = model::Matrix6::Zero();
  turn.topLeftCorner<3, 3>() = strip_R_square;
  turn.bottomRightCorner<3, 3>() = strip_R_square;
  const model::Matrix6 strip = turn * sigma.asDiagonal() * eigen.eigenvectors() * values.asDiagonal() *
                               eigen.eigenvectors().transpose() * sigma.asDiagonal() * turn.transpose();
  return (strip + strip.transpose()) / 2;  // exactly symmetric, as the journal checks
}

// Rotation vector (rad) to a rotation matrix.
model::Matrix3 rotation_from_vector(const model::Vector3& phi) {
  const double angle = phi.norm();
  if (angle == 0.0) return model::Matrix3::Identity();
  return Eigen::AngleAxisd(angle, phi / angle).toRotationMatrix();
}

}  // namespace

PlatformPoseSensor::PlatformPoseSensor(can::PlatformClient& client, std::vector<model::Transform> strip_T_square)
    : client_(client), strip_T_square_(std::move(strip_T_square)) {
  if (strip_T_square_.empty()) throw SessionError("platform sensor: the strip has no calibration squares");
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
  const model::Matrix6 covariance =
      strip_pose_covariance(report, strip_T_square_[static_cast<std::size_t>(square)].rotation);
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

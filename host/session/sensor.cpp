#include "host/session/sensor.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include "host/vision/image_labeling.hpp"
#include "shared/measurement_report.hpp"

namespace kincal::session {

namespace {

std::string at_pose(int index) { return "pose " + std::to_string(index) + ": "; }

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
  o.sequence = report.sequence;
  o.timestamp_s = report.timestamp_us * 1e-6;
  o.note = "square " + std::to_string(square + 1) + ", " + std::to_string(report.fiducial_count) + " fiducials";
  return o;
}

StereoBeaconSensor::StereoBeaconSensor(std::function<StereoFrames()> grab, const core::ParallelStereoRig& rig,
                                       const model::Transform& device_T_right, double pixel_sigma_px)
    : grab_(std::move(grab)), rig_(rig), device_T_right_(device_T_right), pixel_sigma_px_(pixel_sigma_px) {
  if (!(pixel_sigma_px > 0)) throw SessionError("stereo sensor: the pixel sigma must be positive");
}

namespace {

// The beacon: the largest bright blob of the frame, thresholded halfway between the background
// (the median grey level) and the brightest pixel. Not Otsu: in a frame that is nearly all
// background, Otsu splits the background's own shading and the beacon drowns in half of it.
core::Vector2<float> find_beacon(const cv::Mat& grey, const char* which, int index) {
  if (grey.empty() || grey.type() != CV_8UC1)
    throw SessionError(at_pose(index) + "the " + which + " camera gave no 8-bit grey frame");
  std::array<int, 256> histogram{};
  for (int r = 0; r < grey.rows; ++r)
    for (int c = 0; c < grey.cols; ++c) ++histogram[grey.at<std::uint8_t>(r, c)];
  int median = 0, brightest = 0;
  for (int level = 0, seen = 0; level < 256; ++level) {
    seen += histogram[static_cast<std::size_t>(level)];
    if (seen * 2 < static_cast<int>(grey.total())) median = level + 1;
    if (histogram[static_cast<std::size_t>(level)] > 0) brightest = level;
  }
  constexpr int kMinContrastDn = 20;
  if (brightest - median < kMinContrastDn)
    throw SessionError(at_pose(index) + "no beacon in the " + which + " camera's frame (brightest pixel " +
                       std::to_string(brightest) + " DN, background " + std::to_string(median) + " DN)");
  vision::LabelOptions options;
  options.polarity = core::Polarity::kBright;
  options.threshold = static_cast<std::uint8_t>((median + brightest) / 2);
  options.min_area_px = 4;
  const vision::LabelResult result = vision::label_grey(grey, options);
  const core::Blob* best = nullptr;
  for (const core::Blob& b : result.blobs)
    if (!best || b.area_px > best->area_px) best = &b;
  if (!best) throw SessionError(at_pose(index) + "no beacon (no bright blob) in the " + which + " camera's frame");
  if (best->flags & core::kTouchesBorder)
    throw SessionError(at_pose(index) + "the beacon touches the border of the " + which + " camera's frame");
  return {best->x_px.to_float(), best->y_px.to_float()};
}

}  // namespace

Observation StereoBeaconSensor::measure(int index, const model::Transform&) {
  const StereoFrames frames = grab_();
  const core::Vector2<float> left = find_beacon(frames.left, "left", index);
  const core::Vector2<float> right = find_beacon(frames.right, "right", index);
  const auto sigma = static_cast<float>(pixel_sigma_px_);
  auto triangulate = [&](const core::Vector2<float>& l, const core::Vector2<float>& r) {
    core::StereoPoint point;
    const core::StereoStatus status = core::triangulate_parallel(rig_, l, r, sigma, point);
    if (status != core::StereoStatus::ok)
      throw SessionError(at_pose(index) + "stereo triangulation failed (status " +
                         std::to_string(static_cast<int>(status)) + ") at left (" + std::to_string(l.x()) + ", " +
                         std::to_string(l.y()) + ") px, right (" + std::to_string(r.x()) + ", " +
                         std::to_string(r.y()) + ") px");
    // The right camera sits one baseline along the left camera's x.
    const model::Vector3 in_right =
        point.point_left_m.cast<double>() - model::Vector3(static_cast<double>(rig_.baseline_m), 0, 0);
    return model::Vector3(device_T_right_ * in_right);
  };
  Observation o;
  o.position = triangulate(left, right);
  // First-order covariance: central differences over the four pixel coordinates (a quarter pixel
  // is far above float rounding and well inside the linear range).
  constexpr float kStep = 0.25f;
  constexpr double kStepPx = kStep;
  Eigen::Matrix<double, 3, 4> jacobian;
  for (int k = 0; k < 4; ++k) {
    core::Vector2<float> lp = left, lm = left, rp = right, rm = right;
    (k < 2 ? lp : rp)(k % 2) += kStep;
    (k < 2 ? lm : rm)(k % 2) -= kStep;
    jacobian.col(k) = (triangulate(lp, rp) - triangulate(lm, rm)) / (2.0 * kStepPx);
  }
  const model::Matrix3 covariance = pixel_sigma_px_ * pixel_sigma_px_ * jacobian * jacobian.transpose();
  o.covariance = (covariance + covariance.transpose()) / 2;  // exactly symmetric, as a covariance is
  o.timestamp_s = frames.timestamp_s;
  char note[96];
  std::snprintf(note, sizeof note, "beacon at (%.2f, %.2f) / (%.2f, %.2f) px", static_cast<double>(left.x()),
                static_cast<double>(left.y()), static_cast<double>(right.x()), static_cast<double>(right.y()));
  o.note = note;
  return o;
}

}  // namespace kincal::session

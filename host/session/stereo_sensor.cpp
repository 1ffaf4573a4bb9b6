#include "host/session/stereo_sensor.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>

#include <Eigen/Geometry>

#include "host/vision/image_labeling.hpp"

namespace kincal::session {

namespace {

struct Camera {
  const char* name;  // "left", "right"
  const cv::Mat& frame;
  const std::string& origin;
  cv::Size size_px;  // calibrated; empty: any
};

struct Beacon {
  core::Vector2<float> px;
  double area_px = 0;
};

std::string where(int index, const Camera& c) {
  return "pose " + std::to_string(index) + ", " + c.name + " camera" + (c.origin.empty() ? "" : " (" + c.origin + ")") +
         ": ";
}

std::string size_text(const cv::Size& s) { return std::to_string(s.width) + "x" + std::to_string(s.height); }

// The median and the brightest grey level of a frame.
std::pair<int, int> median_and_brightest(const cv::Mat& grey) {
  std::array<int, 256> histogram{};
  for (int r = 0; r < grey.rows; ++r)
    for (int c = 0; c < grey.cols; ++c) ++histogram[grey.at<std::uint8_t>(r, c)];
  int median = 0, brightest = 0;
  for (int level = 0, seen = 0; level < 256; ++level) {
    seen += histogram[static_cast<std::size_t>(level)];
    if (seen * 2 < static_cast<int>(grey.total())) median = level + 1;
    if (histogram[static_cast<std::size_t>(level)] > 0) brightest = level;
  }
  return {median, brightest};
}

// The beacon of one camera's frame (see the header for what fails).
Beacon find_beacon(const Camera& c, const std::optional<core::ColourClassTable>& colour, int index) {
  const cv::Mat& frame = c.frame;
  if (frame.empty()) throw SessionError(where(index, c) + "no frame");
  if (frame.depth() != CV_8U || (frame.channels() != 1 && frame.channels() != 3))
    throw SessionError(where(index, c) + "not an 8-bit grey or colour frame");
  if (!c.size_px.empty() && frame.size() != c.size_px)
    throw SessionError(where(index, c) + "the frame is " + size_text(frame.size()) + " px, the stereo calibration's " +
                       size_text(c.size_px) + " px");
  vision::LabelOptions options;
  options.polarity = core::Polarity::kBright;
  options.min_area_px = 4;
  vision::LabelResult result;
  if (colour) {
    if (frame.channels() != 3)
      throw SessionError(where(index, c) + "a grey frame, but the colour table classifies colour frames");
    options.colour = colour;
    result = vision::label_colour(frame, options);
  } else {
    cv::Mat grey = frame;
    if (frame.channels() == 3) cv::cvtColor(frame, grey, cv::COLOR_BGR2GRAY);
    // Not Otsu: in a frame that is nearly all background, Otsu splits the background's own
    // shading and the beacon drowns in half of it.
    const auto [median, brightest] = median_and_brightest(grey);
    constexpr int kMinContrastDn = 20;
    if (brightest - median < kMinContrastDn)
      throw SessionError(where(index, c) + "no beacon (brightest pixel " + std::to_string(brightest) +
                         " DN, background " + std::to_string(median) + " DN)");
    options.threshold = static_cast<std::uint8_t>((median + brightest) / 2);
    result = vision::label_grey(grey, options);
  }
  std::vector<const core::Blob*> blobs;
  for (const core::Blob& b : result.blobs) blobs.push_back(&b);
  std::sort(blobs.begin(), blobs.end(),
            [](const core::Blob* a, const core::Blob* b) { return a->area_px > b->area_px; });
  if (blobs.empty())
    throw SessionError(where(index, c) + "no beacon (no blob of " + std::to_string(options.min_area_px) +
                       " px or more" + (colour ? " in the colour class)" : ")"));
  const core::Blob& best = *blobs.front();
  auto centre = [](const core::Blob& b) {
    char text[48];
    std::snprintf(text, sizeof text, "(%.1f, %.1f) px", static_cast<double>(b.x_px.to_float()),
                  static_cast<double>(b.y_px.to_float()));
    return std::string(text);
  };
  if (blobs.size() > 1 && static_cast<double>(blobs[1]->area_px) >= kDoubledAreaRatio * best.area_px)
    throw SessionError(where(index, c) + "the beacon is doubled: blobs of " + std::to_string(best.area_px) + " px at " +
                       centre(best) + " and " + std::to_string(blobs[1]->area_px) + " px at " + centre(*blobs[1]) +
                       " (a reflection or a second light?)");
  if (best.flags & core::kTouchesBorder)
    throw SessionError(where(index, c) + "the beacon at " + centre(best) + " touches the frame's border");
  return {{best.x_px.to_float(), best.y_px.to_float()}, static_cast<double>(best.area_px)};
}

const char* to_text(core::StereoStatus s) {
  switch (s) {
    case core::StereoStatus::ok:
      return "ok";
    case core::StereoStatus::bad_rig:
      return "the stereo calibration is not usable (focal length, baseline or sigma)";
    case core::StereoStatus::behind_camera:
      return "the rays meet behind the cameras";
    case core::StereoStatus::zero_disparity:
      return "the rays are parallel (the beacon at infinity)";
    case core::StereoStatus::rows_mismatch:
      return "the rows differ (not the same beacon)";
    case core::StereoStatus::rays_miss:
      return "the rays miss each other (not the same beacon, or a calibration that does not fit these cameras)";
    case core::StereoStatus::undistortion_failed:
      return "a pixel the camera model cannot undistort";
  }
  return "unknown status";
}

// The point triangulated by `pair`, in the left camera's frame; `what` prefixes the error.
model::Vector3 triangulate(const core::StereoPair& pair, const core::Vector2<float>& l, const core::Vector2<float>& r,
                           float sigma_px, const std::string& what) {
  core::StereoPoint point;
  const core::StereoStatus status = core::triangulate_pair(pair, l, r, sigma_px, point);
  if (status != core::StereoStatus::ok) {
    char text[96];
    std::snprintf(text, sizeof text, " at left (%.2f, %.2f) px, right (%.2f, %.2f) px", static_cast<double>(l.x()),
                  static_cast<double>(l.y()), static_cast<double>(r.x()), static_cast<double>(r.y()));
    throw SessionError(what + to_text(status) + text);
  }
  return point.point_left_m.cast<double>();
}

}  // namespace

CalibrationDirections calibration_directions(const CalibrationCovariance& covariance) {
  return covariance_directions(covariance, "stereo sensor: the calibration covariance");
}

core::StereoPair perturbed(const core::StereoPair& pair, const Eigen::Matrix<double, 24, 1>& delta) {
  core::StereoPair out = pair;
  out.left = moved_intrinsics(pair.left, delta.segment<9>(0));
  out.right = moved_intrinsics(pair.right, delta.segment<9>(9));
  core::RigidTransform<double> left_T_right;
  left_T_right.rotation = pair.left_T_right.rotation.cast<double>();
  left_T_right.translation = pair.left_T_right.translation.cast<double>();
  const core::RigidTransform<double> right_T_left = left_T_right.inverse();
  const Eigen::AngleAxisd rotation(right_T_left.rotation);
  const Eigen::Vector3d r = rotation.angle() * rotation.axis() + delta.segment<3>(18);
  core::RigidTransform<double> moved;
  moved.rotation =
      r.norm() > 0 ? Eigen::AngleAxisd(r.norm(), r.normalized()).toRotationMatrix() : Eigen::Matrix3d::Identity();
  moved.translation = right_T_left.translation + delta.segment<3>(21);
  const core::RigidTransform<double> moved_left_T_right = moved.inverse();
  out.left_T_right.rotation = moved_left_T_right.rotation.cast<float>();
  out.left_T_right.translation = moved_left_T_right.translation.cast<float>();
  return out;
}

model::Matrix3 triangulation_covariance(const core::StereoPair& pair, const core::Vector2<float>& left_px,
                                        const core::Vector2<float>& right_px, double pixel_sigma_px,
                                        const CalibrationDirections& calibration_directions, const std::string& what) {
  const auto sigma = static_cast<float>(pixel_sigma_px);
  // A quarter pixel is far above float rounding and well inside the linear range.
  constexpr float kStep = 0.25f;
  Eigen::Matrix<double, 3, 4> jacobian;
  for (int k = 0; k < 4; ++k) {
    core::Vector2<float> lp = left_px, lm = left_px, rp = right_px, rm = right_px;
    (k < 2 ? lp : rp)(k % 2) += kStep;
    (k < 2 ? lm : rm)(k % 2) -= kStep;
    jacobian.col(k) =
        (triangulate(pair, lp, rp, sigma, what) - triangulate(pair, lm, rm, sigma, what)) / (2.0 * double{kStep});
  }
  model::Matrix3 covariance = pixel_sigma_px * pixel_sigma_px * jacobian * jacobian.transpose();
  for (const Eigen::Matrix<double, 24, 1>& d : calibration_directions) {
    const model::Vector3 change = (triangulate(perturbed(pair, d), left_px, right_px, sigma, what) -
                                   triangulate(perturbed(pair, -d), left_px, right_px, sigma, what)) /
                                  2.0;
    covariance += change * change.transpose();
  }
  return covariance;
}

StereoBeaconSensor::StereoBeaconSensor(std::function<StereoFrames(int)> grab, StereoSetup setup)
    : grab_(std::move(grab)), setup_(std::move(setup)) {
  if (!(setup_.pixel_sigma_px > 0)) throw SessionError("stereo sensor: the pixel sigma must be positive");
  if (setup_.calibration_covariance) calibration_directions_ = calibration_directions(*setup_.calibration_covariance);
}

Observation StereoBeaconSensor::measure(int index, const model::Transform&) {
  const StereoFrames frames = grab_(index);
  const Camera left_camera{"left", frames.left, frames.left_origin, setup_.left_size_px};
  const Camera right_camera{"right", frames.right, frames.right_origin, setup_.right_size_px};
  const Beacon left = find_beacon(left_camera, setup_.colour, index);
  const Beacon right = find_beacon(right_camera, setup_.colour, index);
  // The beacon stands at nearly the same depth for both cameras: its areas differ by the
  // cameras' pixel densities only, unless one camera sees part of it.
  const core::StereoPair& pair = setup_.pair;
  const double density_left = static_cast<double>(pair.left.fx_px) * static_cast<double>(pair.left.fy_px);
  const double density_right = static_cast<double>(pair.right.fx_px) * static_cast<double>(pair.right.fy_px);
  const double left_over_right = (left.area_px / density_left) / (right.area_px / density_right);
  if (left_over_right < kOccludedAreaRatio || left_over_right > 1 / kOccludedAreaRatio) {
    const bool left_smaller = left_over_right < 1;
    const Camera& hidden = left_smaller ? left_camera : right_camera;
    char text[160];
    std::snprintf(text, sizeof text,
                  "the beacon covers %.0f px here and %.0f px in the %s camera: partly hidden (occluded) in this one",
                  left_smaller ? left.area_px : right.area_px, left_smaller ? right.area_px : left.area_px,
                  left_smaller ? "right" : "left");
    throw SessionError(where(index, hidden) + text);
  }

  const std::string what = "pose " + std::to_string(index) + ": stereo triangulation failed: ";
  const model::Matrix3 covariance =
      triangulation_covariance(pair, left.px, right.px, setup_.pixel_sigma_px, calibration_directions_, what);
  const model::Matrix3& rotation = setup_.device_T_left.rotation;
  Observation o;
  o.position =
      setup_.device_T_left * triangulate(pair, left.px, right.px, static_cast<float>(setup_.pixel_sigma_px), what);
  const model::Matrix3 in_device = rotation * covariance * rotation.transpose();
  o.covariance = (in_device + in_device.transpose()) / 2;  // exactly symmetric, as a covariance is
  o.timestamp_s = frames.timestamp_s;
  char note[96];
  std::snprintf(note, sizeof note, "beacon at (%.2f, %.2f) / (%.2f, %.2f) px", static_cast<double>(left.px.x()),
                static_cast<double>(left.px.y()), static_cast<double>(right.px.x()), static_cast<double>(right.px.y()));
  o.note = note;
  return o;
}

}  // namespace kincal::session

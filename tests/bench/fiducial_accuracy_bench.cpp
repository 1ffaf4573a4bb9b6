// Fiducial image points on rendered calibration squares under perspective and blur: the
// streaming labeler + Doty's FID against the true projections of the fiducials' centres.
//
// Each view: a 4-inch calibration square (Doty Fig. 5.1: fiducial side s = 1/4 inch, centre
// fiducial 2s x s, perimeter fiducials at 7s, corner marker at (-7s, 7s)) seen by a pinhole
// camera (f = 800 px, 640x480) from 0.25-0.35 m, the square tilted 0-30 degrees about a random
// in-plane axis and rotated in-plane at random; 4x4 supersampled, Gaussian blur (sigma 1 px),
// noise 2 DN, 8-bit. The truth is the projection of each fiducial's centre. The area centroid
// of a projected square differs from its projected centre by a second-order perspective term;
// it is printed (fiducial_perspective_bias_max_px), and the error against the area centroid —
// what a centroid estimator can reach — beside the error against the projected centre.
//
// Figures: the fraction of views with all six fiducials identified with the right ids, and the
// RMS and worst image-point errors over all identified fiducials.
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <random>

#include "firmware/core/blob_labeler.hpp"
#include "firmware/core/fiducial_id.hpp"

using namespace kincal::core;

namespace {

constexpr int kWidth = 640, kHeight = 480;
constexpr double kFocal = 800, kSide = 0.00635;  // 1/4 inch in metres
constexpr double kFx[7] = {0, -7, 0, -7, 0, 7, 0}, kFy[7] = {0, 7, 7, 0, 0, 0, -7};

struct View {
  cv::Matx33d camera_R_square;
  cv::Vec3d camera_t_square;
  // Area centroid of the image quadrilateral of a fiducial (what a perfect centroid measures).
  cv::Point2d area_centroid(int id) const {
    const double hy = id == 4 ? 1.0 : 0.5;
    const double cx[4] = {-0.5, 0.5, 0.5, -0.5}, cy[4] = {-hy, -hy, hy, hy};
    cv::Point2d p[4];
    for (int i = 0; i < 4; ++i) p[i] = project((kFx[id] + cx[i]) * kSide, (kFy[id] + cy[i]) * kSide);
    double a = 0, x = 0, y = 0;
    for (int i = 0; i < 4; ++i) {
      const cv::Point2d& u = p[i];
      const cv::Point2d& w = p[(i + 1) % 4];
      const double c = u.x * w.y - w.x * u.y;
      a += c;
      x += (u.x + w.x) * c;
      y += (u.y + w.y) * c;
    }
    return {x / (3 * a), y / (3 * a)};
  }
  cv::Point2d project(double x_m, double y_m) const {
    const cv::Vec3d p = camera_R_square * cv::Vec3d(x_m, y_m, 0) + camera_t_square;
    return {kWidth / 2.0 - 0.5 + kFocal * p[0] / p[2], kHeight / 2.0 - 0.5 + kFocal * p[1] / p[2]};
  }
};

// Rotation by angle about axis (Rodrigues' formula).
cv::Matx33d axis_angle(cv::Vec3d axis, double angle) {
  const cv::Vec3d u = axis / cv::norm(axis);
  const cv::Matx33d cross(0, -u[2], u[1], u[2], 0, -u[0], -u[1], u[0], 0);
  return cv::Matx33d::eye() + std::sin(angle) * cross + (1 - std::cos(angle)) * cross * cross;
}

cv::Mat render(const View& v, std::mt19937_64& rng) {
  // Square plane -> image homography, inverted to map image samples back to the paper.
  const cv::Matx33d k(kFocal, 0, kWidth / 2.0 - 0.5, 0, kFocal, kHeight / 2.0 - 0.5, 0, 0, 1);
  const cv::Matx33d rt(v.camera_R_square(0, 0), v.camera_R_square(0, 1), v.camera_t_square[0], v.camera_R_square(1, 0),
                       v.camera_R_square(1, 1), v.camera_t_square[1], v.camera_R_square(2, 0), v.camera_R_square(2, 1),
                       v.camera_t_square[2]);
  const cv::Matx33d inverse = (k * rt).inv();
  cv::Mat img(kHeight, kWidth, CV_64FC1);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      int covered = 0;
      for (int sy = 0; sy < 4; ++sy)
        for (int sx = 0; sx < 4; ++sx) {
          const cv::Vec3d q = inverse * cv::Vec3d(x - 0.375 + 0.25 * sx, y - 0.375 + 0.25 * sy, 1);
          const double px = q[0] / q[2] / kSide, py = q[1] / q[2] / kSide;
          for (int id = 1; id <= 6; ++id) {
            const double ox = px - kFx[id], oy = py - kFy[id], hy = id == 4 ? 1.0 : 0.5;
            if (ox >= -0.5 && ox < 0.5 && oy >= -hy && oy < hy) ++covered;
          }
        }
      img.at<double>(y, x) = 200.0 - 160.0 * covered / 16.0;
    }
  cv::GaussianBlur(img, img, cv::Size(0, 0), 1.0);
  std::normal_distribution<double> noise(0.0, 2.0);
  cv::Mat out(kHeight, kWidth, CV_8UC1);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      out.at<std::uint8_t>(y, x) = cv::saturate_cast<std::uint8_t>(img.at<double>(y, x) + noise(rng));
  return out;
}

}  // namespace

int main() {
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto buffers = std::make_unique<VgaLabelerBuffers>();
  Blob blobs[128];
  FidVerdict verdicts[128];
  constexpr int kViews = 40;
  int complete = 0, points = 0;
  double sum_sq = 0, worst = 0, sum_sq_area = 0, worst_perspective = 0;
  for (int view = 0; view < kViews; ++view) {
    const double in_plane = 2 * M_PI * unit(rng), tilt = (30.0 * M_PI / 180) * unit(rng), axis = 2 * M_PI * unit(rng);
    View v;
    // The square faces the camera (its +z toward the camera: camera z = -square z), then tilts.
    const cv::Matx33d facing(1, 0, 0, 0, -1, 0, 0, 0, -1);
    v.camera_R_square =
        axis_angle({std::cos(axis), std::sin(axis), 0}, tilt) * facing * axis_angle({0, 0, 1}, in_plane);
    v.camera_t_square = {0.01 * (unit(rng) - 0.5), 0.01 * (unit(rng) - 0.5), 0.25 + 0.1 * unit(rng)};
    const cv::Mat img = render(v, rng);

    BlobLabeler labeler(buffers->memory());
    LabelerConfig config;
    config.polarity = Polarity::kDark;
    config.threshold = 120;
    config.min_area_px = 4;
    FrameSummary summary;
    bool ok = labeler.begin_frame(config, blobs) == LabelStatus::kOk;
    for (int y = 0; y < kHeight && ok; ++y)
      ok = labeler.push_row({img.ptr<std::uint8_t>(y), static_cast<std::size_t>(kWidth)}) == LabelStatus::kOk;
    ok = ok && labeler.end_frame(summary) == LabelStatus::kOk;
    FidResult result;
    if (!ok || identify_fiducials(FidModel{}, std::span<const Blob>(blobs, summary.blobs), verdicts, result) !=
                   FidStatus::kOk) {
      continue;
    }
    int right = 0;
    for (int i = 0; i < result.count; ++i) {
      const IdentifiedFiducial& f = result.fiducials[static_cast<std::size_t>(i)];
      const cv::Point2d truth = v.project(kFx[f.id] * kSide, kFy[f.id] * kSide);
      const double e = std::hypot(f.x_px.to_double() - truth.x, f.y_px.to_double() - truth.y);
      if (e < 3.0) ++right;  // the right id lands on its own fiducial
      sum_sq += e * e;
      worst = std::fmax(worst, e);
      const cv::Point2d area = v.area_centroid(f.id);
      const double ea = std::hypot(f.x_px.to_double() - area.x, f.y_px.to_double() - area.y);
      sum_sq_area += ea * ea;
      worst_perspective = std::fmax(worst_perspective, std::hypot(area.x - truth.x, area.y - truth.y));
      ++points;
    }
    if (result.count == 6 && right == 6) ++complete;
  }
  std::printf("views %d, all six identified %d, points %d\n", kViews, complete, points);
  std::printf("FIGURE fid_views_fully_identified %.3f fraction\n", static_cast<double>(complete) / kViews);
  std::printf("FIGURE fiducial_point_rms_error_px %.4f px\n", std::sqrt(sum_sq / points));
  std::printf("FIGURE fiducial_point_max_error_px %.4f px\n", worst);
  std::printf("FIGURE fiducial_point_rms_error_vs_area_centroid_px %.4f px\n", std::sqrt(sum_sq_area / points));
  std::printf("FIGURE fiducial_perspective_bias_max_px %.4f px\n", worst_perspective);
  return complete > 0 ? 0 : 1;
}

// host/sim/render.hpp: rendered images against OpenCV's projection and corner finder and
// against the firmware's own labeler; errors; determinism.
#include <doctest/doctest.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <numbers>
#include <vector>

#include "host/sim/render.hpp"
#include "host/vision/image_labeling.hpp"

namespace kincal::sim {
namespace {

constexpr std::array<double, 5> kDistortion{-0.25, 0.08, 0.0012, -0.0008, -0.01};

ImagingConditions noise_free() {
  ImagingConditions c;
  c.read_noise_dn = 0;
  c.shot_noise_gain = 0;
  return c;
}

cv::Point2d project(const CameraSpec& camera, const Eigen::Isometry3d& camera_T_target,
                    const Eigen::Vector3d& p_target) {
  return project_points(camera, camera_T_target, std::span(&p_target, 1))[0];
}

TEST_CASE("a noise-free disc's centroid (the firmware labeler) is its projected centre") {
  const double radius_m = 0.002;
  const PlanarTarget disc{[radius_m](double x, double y) { return x * x + y * y < radius_m * radius_m ? 1.0 : 0.1; }};
  for (const bool distorted : {false, true}) {
    CameraSpec camera;
    if (distorted) camera.distortion = kDistortion;
    // Frontal views at sub-pixel phases, in the centre and toward a corner (where distortion acts).
    for (const Eigen::Vector3d& centre_camera :
         {Eigen::Vector3d(0.0013, -0.0007, 0.4), Eigen::Vector3d(0.1512, -0.1049, 0.4),
          Eigen::Vector3d(-0.1637, 0.1121, 0.4)}) {
      const Eigen::Isometry3d camera_T_target = facing_camera(centre_camera, 0, 0);
      const cv::Point2d truth = project(camera, camera_T_target, Eigen::Vector3d::Zero());
      const cv::Mat image = render_plane(camera, camera_T_target, disc, noise_free());
      vision::LabelOptions options;
      options.polarity = core::Polarity::kBright;
      options.threshold = 120;  // between the dark ground (0.1) and the disc (1)
      const vision::LabelResult labels = vision::label_grey(image, options);
      CAPTURE(distorted);
      CAPTURE(truth);
      REQUIRE(labels.blobs.size() == 1);
      CHECK(std::abs(labels.blobs[0].x_px.to_double() - truth.x) < 0.05);
      CHECK(std::abs(labels.blobs[0].y_px.to_double() - truth.y) < 0.05);
    }
  }
}

TEST_CASE("cv::findChessboardCorners on a rendered chessboard finds the projected corners") {
  constexpr int kCols = 9, kRows = 6;
  constexpr double kSquare = 0.025;
  CameraSpec camera;
  camera.distortion = kDistortion;
  ImagingConditions conditions;  // default lighting, blur and noise
  const Eigen::Vector3d board_centre(4 * kSquare, 2.5 * kSquare, 0);
  int views = 0;
  for (const auto& [tilt_x, tilt_y] : {std::pair{0.0, 0.0}, std::pair{0.35, -0.2}, std::pair{-0.3, 0.4}}) {
    const Eigen::Isometry3d camera_T_target =
        facing_camera(Eigen::Vector3d(0.02, -0.01, 0.45), tilt_x, tilt_y, board_centre, Facing::kZAway);
    conditions.seed = static_cast<std::uint64_t>(++views);
    const cv::Mat image = render_plane(camera, camera_T_target, chessboard(kCols, kRows, kSquare), conditions);
    std::vector<cv::Point2f> found;
    REQUIRE(cv::findChessboardCorners(image, cv::Size(kCols, kRows), found));
    cv::cornerSubPix(image, found, cv::Size(5, 5), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-4));
    std::vector<Eigen::Vector3d> corners;
    for (int j = 0; j < kRows; ++j) {
      for (int i = 0; i < kCols; ++i) corners.emplace_back(i * kSquare, j * kSquare, 0);
    }
    const std::vector<cv::Point2d> truth = project_points(camera, camera_T_target, corners);
    REQUIRE(found.size() == truth.size());
    double worst_px = 0, sum_sq_px2 = 0;
    for (std::size_t k = 0; k < found.size(); ++k) {
      const double e_px =
          std::hypot(static_cast<double>(found[k].x) - truth[k].x, static_cast<double>(found[k].y) - truth[k].y);
      worst_px = std::max(worst_px, e_px);
      sum_sq_px2 += e_px * e_px;
    }
    CAPTURE(tilt_x);
    CAPTURE(tilt_y);
    // cornerSubPix itself is off by up to 0.07 px on noise-free frontal renders at 8x8 samples
    // (its phase-dependent error on sharp corners); with the default noise its RMS error here is
    // about 0.06 px. A misplaced projection (half a pixel, a wrong distortion sign) fails both.
    CHECK(std::sqrt(sum_sq_px2 / static_cast<double>(found.size())) < 0.1);
    CHECK(worst_px < 0.2);
  }
}

TEST_CASE("texture() places texel (0, 0) at the target origin, columns along x") {
  cv::Mat grey(3, 4, CV_8UC1, cv::Scalar(255));
  grey.at<std::uint8_t>(0, 0) = 0;
  grey.at<std::uint8_t>(2, 3) = 51;
  const PlanarTarget t = texture(grey, 0.01, 0.5);
  CHECK(t.reflectance(0.0, 0.0) == 0.0);
  CHECK(t.reflectance(0.0049, -0.0049) == 0.0);
  CHECK(t.reflectance(0.0051, 0.0) == 1.0);
  CHECK(t.reflectance(0.03, 0.02) == doctest::Approx(0.2));
  CHECK(t.reflectance(-0.0051, 0.0) == 0.5);
  CHECK(t.reflectance(0.0, 0.0251) == 0.5);
}

TEST_CASE("the same seed gives the same bits; another seed other noise") {
  CameraSpec camera;
  camera.distortion = kDistortion;
  const Eigen::Isometry3d camera_T_target = facing_camera(Eigen::Vector3d(0, 0, 0.4), 0.3, 0.1);
  ImagingConditions conditions;
  conditions.seed = 7;
  const cv::Mat a = render_plane(camera, camera_T_target, chessboard(5, 4, 0.02), conditions);
  const cv::Mat b = render_plane(camera, camera_T_target, chessboard(5, 4, 0.02), conditions);
  conditions.seed = 8;
  const cv::Mat c = render_plane(camera, camera_T_target, chessboard(5, 4, 0.02), conditions);
  CHECK(cv::norm(a, b, cv::NORM_INF) == 0);
  CHECK(cv::norm(a, c, cv::NORM_INF) > 0);
  // Noise is what differs: the mean difference is near zero, the spread about sqrt(2) x read noise.
  cv::Mat diff;
  cv::subtract(a, c, diff, cv::noArray(), CV_32F);
  cv::Scalar mean, stddev;
  cv::meanStdDev(diff, mean, stddev);
  CHECK(std::abs(mean[0]) < 0.1);
  CHECK(stddev[0] > 1.5);
  CHECK(stddev[0] < 4.0);
}

TEST_CASE("lighting: a white wall shows the gradient and the vignetting") {
  CameraSpec camera;
  ImagingConditions conditions = noise_free();
  conditions.exposure_dn = 200;
  conditions.black_level_dn = 10;
  conditions.gradient = 0.2;
  conditions.vignetting = 0.3;
  const cv::Mat image = render_plane(camera, facing_camera(Eigen::Vector3d(0, 0, 1), 0, 0),
                                     PlanarTarget{[](double, double) { return 1.0; }}, conditions);
  const double centre = image.at<std::uint8_t>(240, 320) - 10.0;
  CHECK(centre == doctest::Approx(200).epsilon(0.01));
  // Left and right edges at mid-height: the gradient, with the same vignetting on both sides.
  const double left = image.at<std::uint8_t>(240, 0) - 10.0, right = image.at<std::uint8_t>(240, 639) - 10.0;
  CHECK((right - left) / ((right + left) / 2) == doctest::Approx(0.2).epsilon(0.05));
  // The corner: (1 - vignetting) times the gradient there.
  const double corner = image.at<std::uint8_t>(0, 639) - 10.0;
  CHECK(corner == doctest::Approx(200 * 0.7 * (1 + 0.2 * 319.5 / 640)).epsilon(0.02));
}

TEST_CASE("bad arguments throw, naming the field") {
  const PlanarTarget white{[](double, double) { return 1.0; }};
  const Eigen::Isometry3d pose = facing_camera(Eigen::Vector3d(0, 0, 1), 0, 0);
  struct Case {
    const char* field;
    void (*spoil)(CameraSpec&, ImagingConditions&);
  };
  const Case cases[] = {
      {"width_px", [](CameraSpec& c, ImagingConditions&) { c.width_px = 0; }},
      {"height_px", [](CameraSpec& c, ImagingConditions&) { c.height_px = 9000; }},
      {"fx_px", [](CameraSpec& c, ImagingConditions&) { c.fx_px = -1; }},
      {"fy_px", [](CameraSpec& c, ImagingConditions&) { c.fy_px = std::nan(""); }},
      {"distortion", [](CameraSpec& c, ImagingConditions&) { c.distortion[0] = -5.0; }},  // folds in the image
      {"supersampling", [](CameraSpec&, ImagingConditions& i) { i.supersampling = 9; }},
      {"read_noise_dn", [](CameraSpec&, ImagingConditions& i) { i.read_noise_dn = -1; }},
      {"shot_noise_gain", [](CameraSpec&, ImagingConditions& i) { i.shot_noise_gain = -0.1; }},
      {"blur_sigma_px", [](CameraSpec&, ImagingConditions& i) { i.blur_sigma_px = 30; }},
      {"vignetting", [](CameraSpec&, ImagingConditions& i) { i.vignetting = 1; }},
  };
  for (const Case& c : cases) {
    CameraSpec camera;
    ImagingConditions conditions;
    c.spoil(camera, conditions);
    CAPTURE(c.field);
    CHECK_THROWS_WITH_AS(render_plane(camera, pose, white, conditions), doctest::Contains(c.field),
                         std::invalid_argument);
  }
  const CameraSpec camera;
  const ImagingConditions conditions;
  CHECK_THROWS_WITH_AS(render_plane(camera, pose, PlanarTarget{}, conditions), doctest::Contains("reflectance"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS(chessboard(1, 5, 0.02), doctest::Contains("inner_cols"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(chessboard(5, 5, 0.0), doctest::Contains("square_m"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(texture(cv::Mat(), 0.01), doctest::Contains("grey"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(texture(cv::Mat(2, 2, CV_8UC1), -1), doctest::Contains("metres_per_pixel"),
                       std::invalid_argument);
}

}  // namespace
}  // namespace kincal::sim

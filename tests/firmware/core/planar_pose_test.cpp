// planar_pose.hpp against double-precision references: the truth for exact image points, an
// independent double Gauss-Newton (numeric Jacobian, same cost) for noisy ones, with and without
// the ranger-plane prior; three points with a prior; a tilted prior that must not drag the pose;
// every refusal; the fiducial perspective bias against a brute-force area integral in double;
// range_plane_covariance against the plane fit's numeric derivative.
#include "firmware/core/planar_pose.hpp"

#include <doctest.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "tests/firmware/core/random_source.hpp"

using namespace kincal::core;

namespace {

constexpr double kSide_m = 0.00635;  // the small fiducial's side s (1/4 inch)

// The ARID rig's camera (host/sim/render.hpp CameraSpec, host/demo/simulated_rig.cpp distortion).
CameraIntrinsics arid_camera() {
  CameraIntrinsics c;
  c.fx_px = 600.0f;
  c.fy_px = 600.0f;
  c.cx_px = 319.5f;
  c.cy_px = 239.5f;
  c.distortion = {-0.05f, 0.01f, 0.0f, 0.0f, 0.0f};
  return c;
}

struct PoseD {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

struct Fiducial {
  Eigen::Vector2d centre_m;
  Eigen::Vector2d half_size_m;
};

// One calibration square's six fiducials (host/sim/strip.hpp): p1..p6, p4 twice as long in y.
std::vector<Fiducial> square_fiducials(double x_offset_m = 0.0) {
  const double s = kSide_m, q = 0.5 * s;
  return {{{x_offset_m - 7 * s, 7 * s}, {q, q}}, {{x_offset_m, 7 * s}, {q, q}},
          {{x_offset_m - 7 * s, 0}, {q, q}},     {{x_offset_m, 0}, {q, s}},
          {{x_offset_m + 7 * s, 0}, {q, q}},     {{x_offset_m, -7 * s}, {q, q}}};
}

// The square facing the camera (its +z toward the camera), spun in-plane, then tilted up to
// max_tilt_rad about a random axis; its centre near the optical axis at the given distance.
PoseD random_view(kincal::test::RandomSource& random, double max_tilt_rad, double min_m, double max_m) {
  const Eigen::Matrix3d facing = Eigen::Vector3d(1, -1, -1).asDiagonal();
  const Eigen::Vector3d axis(random.uniform(-1, 1), random.uniform(-1, 1), 0);
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(random.uniform(0, max_tilt_rad), axis.normalized()).toRotationMatrix();
  const Eigen::Matrix3d spin =
      Eigen::AngleAxisd(random.uniform(-3.14, 3.14), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const double distance = random.uniform(min_m, max_m);
  return {tilt * facing * spin,
          Eigen::Vector3d(random.uniform(-0.1, 0.1) * distance, random.uniform(-0.1, 0.1) * distance, distance)};
}

// OpenCV's projection in double.
Eigen::Vector2d project_d(const CameraIntrinsics& c, const Eigen::Vector3d& p) {
  const double x = p.x() / p.z(), y = p.y() / p.z();
  const auto w = [](float v) { return static_cast<double>(v); };
  const Distortion<double> k{w(c.distortion.k1), w(c.distortion.k2), w(c.distortion.p1), w(c.distortion.p2),
                             w(c.distortion.k3)};
  const Eigen::Vector2d d = distort_normalized(k, Eigen::Vector2d(x, y));
  return {w(c.fx_px) * d.x() + w(c.cx_px), w(c.fy_px) * d.y() + w(c.cy_px)};
}

Eigen::Vector3d on_target(const PoseD& pose, const Eigen::Vector2d& s) {
  return pose.rotation * Eigen::Vector3d(s.x(), s.y(), 0) + pose.translation;
}

// Approximately normal (sum of 12 uniforms): no libm in the M4 run's random numbers.
double gaussian(kincal::test::RandomSource& random) {
  double sum = -6.0;
  for (int i = 0; i < 12; ++i) sum += random.unit();
  return sum;
}

std::vector<PlanarCorrespondence> correspondences(const CameraIntrinsics& camera, const PoseD& pose,
                                                  const std::vector<Fiducial>& fiducials, double noise_px,
                                                  kincal::test::RandomSource& random) {
  std::vector<PlanarCorrespondence> out;
  for (const Fiducial& f : fiducials) {
    const Eigen::Vector2d px = project_d(camera, on_target(pose, f.centre_m));
    PlanarCorrespondence c;
    c.pixel_px = Vector2<float>(static_cast<float>(px.x() + noise_px * gaussian(random)),
                                static_cast<float>(px.y() + noise_px * gaussian(random)));
    c.target_m = f.centre_m.cast<float>();
    c.fiducial_half_size_m = f.half_size_m.cast<float>();
    out.push_back(c);
  }
  return out;
}

// The slope form (c0, slope_x, slope_y) of the pose's plane, and the CalibrationPlane of it.
Eigen::Vector3d slope_form(const PoseD& pose) {
  const Eigen::Vector3d m = pose.rotation.col(2);
  return {m.dot(pose.translation) / m.z(), -m.x() / m.z(), -m.y() / m.z()};
}

PlanePrior prior_from_slope_form(const Eigen::Vector3d& f, const Eigen::Matrix3d& covariance) {
  const Eigen::Vector3d n = Eigen::Vector3d(-f(1), -f(2), 1.0).normalized();
  PlanePrior prior;
  prior.plane.normal = n.cast<float>();
  prior.plane.distance_m = static_cast<float>(f(0) * n.z());
  prior.plane.sensors_used = 0xF;
  prior.covariance = covariance.cast<float>();
  return prior;
}

// The ARID rangers' covariance (0.5 mm on a + of 10 cm), from range_plane_covariance.
Eigen::Matrix3d ranger_covariance() {
  RangePlaneModel model;
  REQUIRE(prepare_range_plane(plus_pattern_layout(0.1f, RangeModel::along_beam), model) == PlaneStatus::ok);
  CalibrationPlane plane;
  plane.sensors_used = 0xF;
  Matrix3<float> covariance;
  REQUIRE(range_plane_covariance(model, plane, 0.5e-3f, covariance) == PlaneStatus::ok);
  return covariance.cast<double>();
}

double rotation_angle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const Eigen::Matrix3d d = a * b.transpose();
  const Eigen::Vector3d axial(d(2, 1) - d(1, 2), d(0, 2) - d(2, 0), d(1, 0) - d(0, 1));
  return std::atan2(0.5 * axial.norm(), 0.5 * (d.trace() - 1.0));
}

PoseD to_double(const RigidTransform<float>& t) { return {t.rotation.cast<double>(), t.translation.cast<double>()}; }

// The same cost in double: whitened pixel residuals and the prior's, minimized by Gauss-Newton
// with a central-difference Jacobian, from the truth; perturbation t += dt, R = exp(dphi) R.
struct ReferenceProblem {
  CameraIntrinsics camera;
  std::vector<PlanarCorrespondence> points;
  double sigma_px = 0.1;
  const PlanePrior* prior = nullptr;

  Eigen::VectorXd residuals(const PoseD& pose) const {
    const int n = static_cast<int>(points.size());
    Eigen::VectorXd r(2 * n + (prior != nullptr ? 3 : 0));
    for (int i = 0; i < n; ++i) {
      const auto& p = points[static_cast<std::size_t>(i)];
      const Eigen::Vector2d px = project_d(camera, on_target(pose, p.target_m.cast<double>()));
      r.segment<2>(2 * i) = (px - p.pixel_px.cast<double>()) / sigma_px;
    }
    if (prior != nullptr) {
      const Eigen::Vector3d n3 = prior->plane.normal.cast<double>();
      const Eigen::Vector3d measured(static_cast<double>(prior->plane.distance_m) / n3.z(), -n3.x() / n3.z(),
                                     -n3.y() / n3.z());
      const Eigen::Matrix3d l = prior->covariance.cast<double>().llt().matrixL();
      r.tail<3>() = l.triangularView<Eigen::Lower>().solve(slope_form(pose) - measured);
    }
    return r;
  }

  static PoseD moved(const PoseD& pose, const Eigen::Matrix<double, 6, 1>& delta) {
    const Eigen::Vector3d phi = delta.tail<3>();
    const double angle = phi.norm();
    const Eigen::Matrix3d q =
        angle > 0 ? Eigen::AngleAxisd(angle, phi / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
    return {q * pose.rotation, pose.translation + delta.head<3>()};
  }

  Eigen::MatrixXd jacobian(const PoseD& pose) const {
    const Eigen::VectorXd r0 = residuals(pose);
    Eigen::MatrixXd j(r0.size(), 6);
    for (int k = 0; k < 6; ++k) {
      Eigen::Matrix<double, 6, 1> h = Eigen::Matrix<double, 6, 1>::Zero();
      h(k) = 1e-6;
      j.col(k) = (residuals(moved(pose, h)) - residuals(moved(pose, -h))) / 2e-6;
    }
    return j;
  }

  PoseD solve(PoseD pose, Eigen::Matrix<double, 6, 6>& covariance) const {
    for (int it = 0; it < 20; ++it) {
      const Eigen::MatrixXd j = jacobian(pose);
      const Eigen::Matrix<double, 6, 6> normal = j.transpose() * j;
      const Eigen::Matrix<double, 6, 1> step = normal.ldlt().solve(-(j.transpose() * residuals(pose)));
      pose = moved(pose, step);
      if (step.cwiseAbs().maxCoeff() < 1e-13) break;
    }
    const Eigen::MatrixXd j = jacobian(pose);
    covariance = (j.transpose() * j).inverse();
    return pose;
  }
};

PlanarPoseOptions options_without_bias() {
  PlanarPoseOptions o;
  o.perspective_passes = 0;
  return o;
}

}  // namespace

TEST_CASE("planar_pose recovers the pose from exact image points to float precision") {
  kincal::test::RandomSource random(0x9A7A);
  const CameraIntrinsics camera = arid_camera();
  PlanarPoseWorkspace workspace;
  double worst_rotation = 0, worst_translation = 0, worst_rms = 0;
  int most_iterations = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const PoseD truth = random_view(random, 40.0 * std::numbers::pi / 180, 0.1, 0.5);
    // One square, or two side by side (a strip frame: the origin off the first square).
    std::vector<Fiducial> fiducials = square_fiducials(trial % 2 == 0 ? 0.0 : -0.05);
    if (trial % 2 == 1) {
      for (const Fiducial& f : square_fiducials(0.05)) fiducials.push_back(f);
    }
    const auto points = correspondences(camera, truth, fiducials, 0.0, random);
    PlanarPose pose;
    REQUIRE(planar_pose(camera, points, nullptr, options_without_bias(), workspace, pose) == PlanarPoseStatus::ok);
    CHECK(pose.status == PlanarPoseStatus::ok);
    CHECK(pose.point_count == points.size());
    CHECK_FALSE(pose.prior_used);
    const PoseD got = to_double(pose.camera_T_target);
    worst_rotation = std::fmax(worst_rotation, rotation_angle(got.rotation, truth.rotation));
    worst_translation =
        std::fmax(worst_translation, (got.translation - truth.translation).norm() / truth.translation.norm());
    worst_rms = std::fmax(worst_rms, static_cast<double>(pose.reprojection_rms_px));
    most_iterations = std::max(most_iterations, static_cast<int>(pose.iterations));
    CHECK((got.rotation.transpose() * got.rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-6);
    CHECK(got.rotation.determinant() > 0);
  }
  MESSAGE("exact points: worst rotation ", worst_rotation, " rad, translation ", worst_translation, " per m, rms ",
          worst_rms, " px, most iterations ", most_iterations);
  CHECK(worst_rotation < 5e-6);  // measured 3.3e-6: pixel rounding through the weak tilt
  CHECK(worst_translation < 2e-6);
  CHECK(worst_rms < 1e-3);
}

TEST_CASE("planar_pose reaches the double-precision optimum of noisy points, with and without the prior") {
  kincal::test::RandomSource random(0x5EED);
  const CameraIntrinsics camera = arid_camera();
  const Eigen::Matrix3d ranger = ranger_covariance();
  const Eigen::Matrix3d ranger_l = ranger.llt().matrixL();
  PlanarPoseWorkspace workspace;
  double worst_rotation = 0, worst_translation = 0, worst_covariance = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const PoseD truth = random_view(random, 40.0 * std::numbers::pi / 180, 0.15, 0.5);
    const auto points = correspondences(camera, truth, square_fiducials(), 0.1, random);
    Eigen::Vector3d noise(gaussian(random), gaussian(random), gaussian(random));
    const PlanePrior prior = prior_from_slope_form(slope_form(truth) + ranger_l * noise, ranger);
    const bool with_prior = trial % 2 == 0;
    PlanarPoseOptions options = options_without_bias();
    options.pixel_sigma_px = 0.1f;
    PlanarPose pose;
    REQUIRE(planar_pose(camera, points, with_prior ? &prior : nullptr, options, workspace, pose) ==
            PlanarPoseStatus::ok);
    CHECK(pose.prior_used == with_prior);

    ReferenceProblem problem{camera, points, 0.1, with_prior ? &prior : nullptr};
    Eigen::Matrix<double, 6, 6> covariance;
    const PoseD reference = problem.solve(truth, covariance);
    const PoseD got = to_double(pose.camera_T_target);
    // Relative to the pose's own uncertainty: float must not matter against the noise.
    const double sigma_rotation = std::sqrt(covariance.bottomRightCorner<3, 3>().trace());
    const double sigma_translation = std::sqrt(covariance.topLeftCorner<3, 3>().trace());
    worst_rotation = std::fmax(worst_rotation, rotation_angle(got.rotation, reference.rotation) / sigma_rotation);
    worst_translation =
        std::fmax(worst_translation, (got.translation - reference.translation).norm() / sigma_translation);
    const Eigen::Matrix<double, 6, 6> c = pose.covariance.cast<double>();
    for (int r = 0; r < 6; ++r)
      for (int k = 0; k < 6; ++k)
        worst_covariance = std::fmax(
            worst_covariance, std::fabs(c(r, k) - covariance(r, k)) / std::sqrt(covariance(r, r) * covariance(k, k)));
    const double rms = std::sqrt(problem.residuals(reference).head(2 * static_cast<int>(points.size())).squaredNorm() /
                                 static_cast<double>(2 * points.size())) *
                       0.1;
    CHECK(std::fabs(static_cast<double>(pose.reprojection_rms_px) - rms) < 1e-3);
  }
  MESSAGE("noisy points: worst difference from the double optimum: rotation ", worst_rotation, " sigma, translation ",
          worst_translation, " sigma; covariance ", worst_covariance, " (correlation units)");
  CHECK(worst_rotation < 0.01);
  CHECK(worst_translation < 0.01);
  CHECK(worst_covariance < 0.01);
}

TEST_CASE("three fiducials and the ranger plane give a pose; the prior alone fixes what they cannot") {
  kincal::test::RandomSource random(0x3F1D);
  const CameraIntrinsics camera = arid_camera();
  const Eigen::Matrix3d ranger = ranger_covariance();
  const Eigen::Matrix3d ranger_l = ranger.llt().matrixL();
  PlanarPoseWorkspace workspace;
  double worst_exact = 0, worst_rotation = 0, worst_translation = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const PoseD truth = random_view(random, 40.0 * std::numbers::pi / 180, 0.15, 0.5);
    std::vector<Fiducial> three = square_fiducials();
    three = {three[1], three[3], three[4]};  // p2, p4, p5: an L
    const bool exact = trial % 2 == 0;
    const auto points = correspondences(camera, truth, three, exact ? 0.0 : 0.1, random);
    const Eigen::Vector3d noise(gaussian(random), gaussian(random), gaussian(random));
    const PlanePrior prior = prior_from_slope_form(
        slope_form(truth) + (exact ? Eigen::Vector3d::Zero().eval() : (ranger_l * noise).eval()), ranger);
    PlanarPose pose;
    REQUIRE(planar_pose(camera, points, &prior, options_without_bias(), workspace, pose) == PlanarPoseStatus::ok);
    CHECK(pose.prior_used);
    const PoseD got = to_double(pose.camera_T_target);
    if (exact) {
      worst_exact = std::fmax(worst_exact, rotation_angle(got.rotation, truth.rotation));
      worst_exact = std::fmax(worst_exact, (got.translation - truth.translation).norm() / truth.translation.norm());
      continue;
    }
    ReferenceProblem problem{camera, points, 0.1, &prior};
    Eigen::Matrix<double, 6, 6> covariance;
    const PoseD reference = problem.solve(truth, covariance);
    worst_rotation = std::fmax(worst_rotation, rotation_angle(got.rotation, reference.rotation) /
                                                   std::sqrt(covariance.bottomRightCorner<3, 3>().trace()));
    worst_translation = std::fmax(worst_translation, (got.translation - reference.translation).norm() /
                                                         std::sqrt(covariance.topLeftCorner<3, 3>().trace()));
  }
  MESSAGE("three points + prior: exact worst ", worst_exact, "; noisy vs double optimum rotation ", worst_rotation,
          " sigma, translation ", worst_translation, " sigma");
  CHECK(worst_exact < 5e-6);
  CHECK(worst_rotation < 0.01);
  CHECK(worst_translation < 0.01);

  // Without the prior three points are refused.
  const auto points = correspondences(camera, random_view(random, 0.3, 0.2, 0.4),
                                      {square_fiducials()[1], square_fiducials()[3], square_fiducials()[4]}, 0, random);
  PlanarPose pose;
  CHECK(planar_pose(camera, points, nullptr, PlanarPoseOptions{}, workspace, pose) == PlanarPoseStatus::too_few_points);
}

TEST_CASE("a flat but tilted ranger plane cannot drag the pose away from six fiducials") {
  kincal::test::RandomSource random(0x7117);
  const CameraIntrinsics camera = arid_camera();
  const Eigen::Matrix3d ranger = ranger_covariance();
  PlanarPoseWorkspace workspace;
  double smallest_chi2 = 1e9;
  for (int trial = 0; trial < 40; ++trial) {
    const PoseD truth = random_view(random, 40.0 * std::numbers::pi / 180, 0.2, 0.4);
    const auto points = correspondences(camera, truth, square_fiducials(), 0.07, random);
    // The plane tilted by 50 mrad per axis (about 7 of its sigmas: a plane the flatness check
    // passes but that is not the strip's) and shifted by 3 mm.
    Eigen::Vector3d wrong = slope_form(truth);
    wrong(1) += 0.05;
    wrong(2) -= 0.05;
    wrong(0) += 0.003;
    const PlanePrior prior = prior_from_slope_form(wrong, ranger);
    PlanarPoseOptions options = options_without_bias();
    options.pixel_sigma_px = 0.07f;
    PlanarPose fused, image_only;
    REQUIRE(planar_pose(camera, points, &prior, options, workspace, fused) == PlanarPoseStatus::ok);
    REQUIRE(planar_pose(camera, points, nullptr, options, workspace, image_only) == PlanarPoseStatus::ok);
    CHECK(fused.prior_rejected);
    CHECK_FALSE(fused.prior_used);
    smallest_chi2 = std::fmin(smallest_chi2, static_cast<double>(fused.prior_innovation_chi2));
    // The pose is the image's, bit for bit.
    CHECK(fused.camera_T_target.rotation == image_only.camera_T_target.rotation);
    CHECK(fused.camera_T_target.translation == image_only.camera_T_target.translation);
  }
  MESSAGE("tilted prior: smallest gate chi2 ", smallest_chi2);

  // A prior drawn from its own covariance is accepted (the gate refuses 0.1%).
  const Eigen::Matrix3d ranger_l = ranger.llt().matrixL();
  int accepted = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const PoseD truth = random_view(random, 40.0 * std::numbers::pi / 180, 0.2, 0.4);
    const auto points = correspondences(camera, truth, square_fiducials(), 0.07, random);
    const Eigen::Vector3d noise(gaussian(random), gaussian(random), gaussian(random));
    const PlanePrior prior = prior_from_slope_form(slope_form(truth) + ranger_l * noise, ranger);
    PlanarPoseOptions options = options_without_bias();
    options.pixel_sigma_px = 0.07f;
    PlanarPose fused;
    REQUIRE(planar_pose(camera, points, &prior, options, workspace, fused) == PlanarPoseStatus::ok);
    accepted += fused.prior_used ? 1 : 0;
  }
  CHECK(accepted >= 97);
}

TEST_CASE("planar_pose refuses bad input with a status") {
  const CameraIntrinsics camera = arid_camera();
  kincal::test::RandomSource random(0xBAD);
  PlanarPoseWorkspace workspace;
  PlanarPose pose;
  const PoseD view = random_view(random, 0.3, 0.25, 0.35);
  const auto good = correspondences(camera, view, square_fiducials(), 0.0, random);
  const Eigen::Matrix3d ranger = ranger_covariance();
  const PlanePrior prior = prior_from_slope_form(slope_form(view), ranger);
  const PlanarPoseOptions options;

  auto run = [&](const std::vector<PlanarCorrespondence>& points, const PlanePrior* p,
                 const PlanarPoseOptions& o = PlanarPoseOptions{}) {
    const PlanarPoseStatus status = planar_pose(camera, points, p, o, workspace, pose);
    CHECK(pose.status == status);
    return status;
  };
  CHECK(run(good, nullptr) == PlanarPoseStatus::ok);
  CHECK(run(good, &prior) == PlanarPoseStatus::ok);

  SUBCASE("too few, too many") {
    CHECK(run({good[0], good[1], good[2]}, nullptr) == PlanarPoseStatus::too_few_points);
    CHECK(run({good[0], good[1]}, &prior) == PlanarPoseStatus::too_few_points);
    CHECK(run({}, &prior) == PlanarPoseStatus::too_few_points);
    std::vector<PlanarCorrespondence> many;
    while (many.size() <= static_cast<std::size_t>(kPlanarPoseMaxPoints)) many.push_back(good[many.size() % 6]);
    CHECK(run(many, nullptr) == PlanarPoseStatus::too_many_points);
  }
  SUBCASE("non-finite") {
    auto bad = good;
    bad[2].pixel_px.x() = std::numeric_limits<float>::quiet_NaN();
    CHECK(run(bad, nullptr) == PlanarPoseStatus::non_finite);
    bad = good;
    bad[4].target_m.y() = std::numeric_limits<float>::infinity();
    CHECK(run(bad, nullptr) == PlanarPoseStatus::non_finite);
    PlanarPoseOptions o;
    o.pixel_sigma_px = 0.0f;
    CHECK(run(good, nullptr, o) == PlanarPoseStatus::non_finite);
  }
  SUBCASE("bad intrinsics, pixels outside the lens model") {
    CameraIntrinsics broken = camera;
    broken.fx_px = 0.0f;
    CHECK(planar_pose(broken, good, nullptr, options, workspace, pose) == PlanarPoseStatus::bad_intrinsics);
    CameraIntrinsics strong = camera;
    strong.distortion.k1 = -0.4f;
    strong.max_normalized_radius = 1.0f;
    auto bad = good;
    bad[0].pixel_px = Vector2<float>(5000.0f, 4000.0f);
    CHECK(planar_pose(strong, bad, nullptr, options, workspace, pose) == PlanarPoseStatus::outside_model_domain);
  }
  SUBCASE("collinear target points") {
    auto line = good;
    for (std::size_t i = 0; i < line.size(); ++i)
      line[i].target_m = Vector2<float>(0.01f * static_cast<float>(i), 0.0f);
    CHECK(run(line, nullptr) == PlanarPoseStatus::collinear_points);
    CHECK(run({line[0], line[1], line[2]}, &prior) == PlanarPoseStatus::collinear_points);
  }
  SUBCASE("coincident image points") {
    auto same = good;
    for (auto& p : same) p.pixel_px = good[0].pixel_px;
    CHECK(run(same, nullptr) == PlanarPoseStatus::degenerate_geometry);
  }
  SUBCASE("bad prior") {
    PlanePrior p = prior;
    p.covariance(1, 1) = -1.0f;
    CHECK(run(good, &p) == PlanarPoseStatus::bad_prior);
    p = prior;
    p.covariance(0, 1) = 1.0f;  // not symmetric
    CHECK(run(good, &p) == PlanarPoseStatus::bad_prior);
    p = prior;
    p.plane.distance_m = std::numeric_limits<float>::quiet_NaN();
    CHECK(run(good, &p) == PlanarPoseStatus::bad_prior);
    p = prior;
    p.plane.normal = Vector3<float>(0.0f, 0.0f, -1.0f);
    CHECK(run(good, &p) == PlanarPoseStatus::bad_prior);
    p = prior;
    p.covariance.setZero();
    CHECK(run(good, &p) == PlanarPoseStatus::bad_prior);
  }
  SUBCASE("not converged within the allowed steps") {
    const auto noisy = correspondences(camera, view, square_fiducials(), 0.3, random);
    PlanarPoseOptions o;
    o.max_iterations = 1;
    CHECK(run(noisy, nullptr, o) == PlanarPoseStatus::not_converged);
    o.max_iterations = 0;
    CHECK(run(noisy, nullptr, o) == PlanarPoseStatus::not_converged);
  }
  SUBCASE("a target point behind the camera") {
    // A steeply tilted plane crossing the camera's z = 0 plane: one end in front, one behind;
    // the pinhole image of the point behind is still a pixel.
    CameraIntrinsics pinhole = camera;
    pinhole.distortion = {};
    PoseD steep;
    steep.rotation = Eigen::AngleAxisd(80.0 * std::numbers::pi / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
    steep.translation = Eigen::Vector3d(0, 0, 0.05);
    std::vector<PlanarCorrespondence> points;
    for (const double x : {-0.2, 0.2}) {
      for (const double y : {-0.02, 0.02}) {
        const Eigen::Vector3d p = on_target(steep, {x, y});
        PlanarCorrespondence c;
        c.pixel_px = Vector2<float>(static_cast<float>(600 * p.x() / p.z() + 319.5),
                                    static_cast<float>(600 * p.y() / p.z() + 239.5));
        c.target_m = Vector2<float>(static_cast<float>(x), static_cast<float>(y));
        points.push_back(c);
      }
    }
    CHECK(planar_pose(pinhole, points, nullptr, options, workspace, pose) == PlanarPoseStatus::behind_camera);
  }
}

namespace {

// The area centroid of the image of a target rectangle, brute force: the image-area integral
// of the pixel over the rectangle, integral of pixel(s) |det d pixel / d s| ds (midpoint rule,
// 120 x 120 cells, central-difference Jacobian), in double.
Eigen::Vector2d brute_force_centroid(const CameraIntrinsics& camera, const PoseD& pose, const Fiducial& f) {
  constexpr int kCells = 120;
  const double hx = 2 * f.half_size_m.x() / kCells, hy = 2 * f.half_size_m.y() / kCells;
  Eigen::Vector2d moment = Eigen::Vector2d::Zero();
  double area = 0;
  for (int i = 0; i < kCells; ++i) {
    for (int j = 0; j < kCells; ++j) {
      const Eigen::Vector2d s = f.centre_m - f.half_size_m + Eigen::Vector2d((i + 0.5) * hx, (j + 0.5) * hy);
      const double e = 1e-7;
      const Eigen::Vector2d du = (project_d(camera, on_target(pose, s + Eigen::Vector2d(e, 0))) -
                                  project_d(camera, on_target(pose, s - Eigen::Vector2d(e, 0)))) /
                                 (2 * e);
      const Eigen::Vector2d dv = (project_d(camera, on_target(pose, s + Eigen::Vector2d(0, e))) -
                                  project_d(camera, on_target(pose, s - Eigen::Vector2d(0, e)))) /
                                 (2 * e);
      const double w = std::fabs(du.x() * dv.y() - du.y() * dv.x());
      moment += w * project_d(camera, on_target(pose, s));
      area += w;
    }
  }
  return moment / area;
}

}  // namespace

TEST_CASE("fiducial_centroid_bias_px matches the brute-force area centroid of the fiducial's image") {
  kincal::test::RandomSource random(0xF1D0);
  PlanarPoseWorkspace workspace;
  double worst = 0, largest_bias = 0;
  for (int trial = 0; trial < 24; ++trial) {
    CameraIntrinsics camera = arid_camera();
    if (trial % 3 == 2) camera.distortion = {-0.3f, 0.1f, 0.002f, -0.001f, 0.0f};  // a stronger lens too
    const PoseD pose = random_view(random, 40.0 * std::numbers::pi / 180, 0.1, 0.5);
    const Fiducial f = square_fiducials()[static_cast<std::size_t>(trial % 6)];
    const Eigen::Vector2d truth =
        brute_force_centroid(camera, pose, f) - project_d(camera, on_target(pose, f.centre_m));
    RigidTransform<float> camera_T_target;
    camera_T_target.rotation = pose.rotation.cast<float>();
    camera_T_target.translation = pose.translation.cast<float>();
    Vector2<float> bias;
    REQUIRE(fiducial_centroid_bias_px(camera, camera_T_target, f.centre_m.cast<float>(), f.half_size_m.cast<float>(),
                                      bias));
    worst = std::fmax(worst, (bias.cast<double>() - truth).norm());
    largest_bias = std::fmax(largest_bias, truth.norm());
  }
  MESSAGE("perspective bias: largest ", largest_bias, " px, worst error ", worst, " px");
  CHECK(largest_bias > 0.05);  // the bias is real here, so the check below means something
  CHECK(worst < 0.002);

  // Refusals: a corner behind the camera, a degenerate rectangle.
  RigidTransform<float> behind;
  behind.translation = Vector3<float>(0.0f, 0.0f, 0.001f);
  behind.rotation = Eigen::AngleAxisf(1.4f, Vector3<float>::UnitY()).toRotationMatrix();
  Vector2<float> bias(7.0f, 7.0f);
  CHECK_FALSE(
      fiducial_centroid_bias_px(arid_camera(), behind, Vector2<float>(0.0f, 0.0f), Vector2<float>(0.01f, 0.01f), bias));
  RigidTransform<float> ahead;
  ahead.translation = Vector3<float>(0.0f, 0.0f, 0.3f);
  CHECK_FALSE(
      fiducial_centroid_bias_px(arid_camera(), ahead, Vector2<float>(0.0f, 0.0f), Vector2<float>(0.0f, 0.01f), bias));
  CHECK(bias == Vector2<float>(7.0f, 7.0f));
}

TEST_CASE("planar_pose's perspective pass removes the centroid bias of tilted fiducials") {
  kincal::test::RandomSource random(0xC0C0);
  const CameraIntrinsics camera = arid_camera();
  PlanarPoseWorkspace workspace;
  double worst_without = 0, worst_with = 0;
  for (int trial = 0; trial < 8; ++trial) {
    const PoseD truth = random_view(random, 40.0 * std::numbers::pi / 180, 0.15, 0.3);
    const std::vector<Fiducial> fiducials = square_fiducials();
    // What a perfect centroid estimator measures: the area centroid of each image.
    std::vector<PlanarCorrespondence> points = correspondences(camera, truth, fiducials, 0.0, random);
    for (std::size_t i = 0; i < points.size(); ++i)
      points[i].pixel_px = brute_force_centroid(camera, truth, fiducials[i]).cast<float>();
    PlanarPoseOptions options;
    options.perspective_passes = 0;
    PlanarPose without, with;
    REQUIRE(planar_pose(camera, points, nullptr, options, workspace, without) == PlanarPoseStatus::ok);
    options.perspective_passes = 1;
    REQUIRE(planar_pose(camera, points, nullptr, options, workspace, with) == PlanarPoseStatus::ok);
    const auto error = [&](const PlanarPose& p) {
      return (p.camera_T_target.translation.cast<double>() - truth.translation).norm();
    };
    worst_without = std::fmax(worst_without, error(without));
    worst_with = std::fmax(worst_with, error(with));
    CHECK(with.iterations > without.iterations);
  }
  MESSAGE("translation error from area centroids: ", worst_without * 1e3, " mm without the perspective pass, ",
          worst_with * 1e3, " mm with it");
  CHECK(worst_with < 0.2 * worst_without);
}

TEST_CASE("range_plane_covariance is the plane fit's sensitivity to the ranges, squared") {
  for (const RangeModel model_kind : {RangeModel::along_beam, RangeModel::perpendicular}) {
    RangeSensorLayout layout = plus_pattern_layout(0.1f, model_kind);
    layout.origin_z_m = 0.01f;
    RangePlaneModel model;
    REQUIRE(prepare_range_plane(layout, model) == PlaneStatus::ok);
    for (const int missing : {-1, 2}) {
      std::array<float, 4> ranges = {0.30f, 0.31f, 0.33f, 0.32f};
      if (missing >= 0) ranges[static_cast<std::size_t>(missing)] = std::numeric_limits<float>::quiet_NaN();
      CalibrationPlane plane;
      REQUIRE(fit_range_plane(model, ranges, plane) == PlaneStatus::ok);
      Matrix3<float> covariance;
      REQUIRE(range_plane_covariance(model, plane, 0.5e-3f, covariance) == PlaneStatus::ok);
      // Numeric d(slope form)/d(range_i) through fit_range_plane, in float with a 1 mm step.
      Eigen::Matrix<double, 3, 4> sensitivity = Eigen::Matrix<double, 3, 4>::Zero();
      const auto form = [](const CalibrationPlane& p) {
        const Eigen::Vector3d n = p.normal.cast<double>();
        return Eigen::Vector3d(static_cast<double>(p.distance_m) / n.z(), -n.x() / n.z(), -n.y() / n.z());
      };
      for (int i = 0; i < 4; ++i) {
        if (i == missing) continue;
        auto up = ranges, down = ranges;
        up[static_cast<std::size_t>(i)] += 1e-3f;
        down[static_cast<std::size_t>(i)] -= 1e-3f;
        CalibrationPlane pu, pd;
        REQUIRE(fit_range_plane(model, up, pu) == PlaneStatus::ok);
        REQUIRE(fit_range_plane(model, down, pd) == PlaneStatus::ok);
        sensitivity.col(i) = (form(pu) - form(pd)) / 2e-3;
      }
      const Eigen::Matrix3d expected = 0.25e-6 * sensitivity * sensitivity.transpose();
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k)
          CHECK(std::fabs(static_cast<double>(covariance(r, k)) - expected(r, k)) <=
                2e-3 * std::sqrt(expected(r, r) * expected(k, k)));
    }
  }
  RangePlaneModel model;
  REQUIRE(prepare_range_plane(plus_pattern_layout(0.1f, RangeModel::along_beam), model) == PlaneStatus::ok);
  CalibrationPlane plane;
  Matrix3<float> covariance;
  plane.sensors_used = 0x3;
  CHECK(range_plane_covariance(model, plane, 0.5e-3f, covariance) == PlaneStatus::range_missing);
  plane.sensors_used = 0xF;
  CHECK(range_plane_covariance(model, plane, 0.0f, covariance) == PlaneStatus::bad_layout);
  plane.normal = Vector3<float>(0.0f, 0.0f, -1.0f);
  CHECK(range_plane_covariance(model, plane, 0.5e-3f, covariance) == PlaneStatus::plane_not_facing);
}

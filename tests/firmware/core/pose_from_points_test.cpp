// pose_from_points.hpp against a double-precision SVD (Kabsch) fit: exact and noisy fiducials
// on a 4-inch calibration square, random poses, proper rotations; Doty's stacked axes shown not
// to be a rotation under the same noise; every refusal.
#include "firmware/core/pose_from_points.hpp"

#include <doctest.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <vector>

#include "tests/firmware/core/random_source.hpp"

using namespace kincal::core;

namespace {

constexpr double kSquare_m = 0.1016;  // Doty's four-inch calibration square

// Fiducials of one square (Doty's Fig. 7.3 layout: centre and four perimeter marks along the
// axes), plus optional extra marks in its corners.
std::vector<Eigen::Vector3d> square_fiducials(bool corners) {
  const double a = 0.4375 * kSquare_m;  // 1.75 inch from the centre
  std::vector<Eigen::Vector3d> p = {{0, 0, 0}, {a, 0, 0}, {0, a, 0}, {-a, 0, 0}, {0, -a, 0}};
  if (corners) {
    for (const double sx : {-1.0, 1.0})
      for (const double sy : {-1.0, 1.0}) p.emplace_back(0.45 * kSquare_m * sx, 0.45 * kSquare_m * sy, 0);
  }
  return p;
}

struct PoseD {
  Eigen::Matrix3d rotation;
  Eigen::Vector3d translation;
};

// The least-squares rigid fit by SVD of the cross-covariance (Kabsch/Umeyama), in double.
PoseD kabsch(const std::vector<Eigen::Vector3d>& s, const std::vector<Eigen::Vector3d>& c) {
  Eigen::Vector3d sm = Eigen::Vector3d::Zero(), cm = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < s.size(); ++i) {
    sm += s[i];
    cm += c[i];
  }
  sm /= static_cast<double>(s.size());
  cm /= static_cast<double>(s.size());
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < s.size(); ++i) h += (c[i] - cm) * (s[i] - sm).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d r = svd.matrixU() * d * svd.matrixV().transpose();
  return {r, cm - r * sm};
}

double rotation_angle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const Eigen::Matrix3d d = a * b.transpose();
  const Eigen::Vector3d axial(d(2, 1) - d(1, 2), d(0, 2) - d(2, 0), d(1, 0) - d(0, 1));
  return std::atan2(0.5 * axial.norm(), 0.5 * (d.trace() - 1.0));
}

std::vector<Vector3<float>> to_float(const std::vector<Eigen::Vector3d>& points) {
  std::vector<Vector3<float>> out;
  for (const auto& p : points) out.push_back(p.cast<float>());
  return out;
}

// A pose of the square seen from a camera 0.2..1.5 m away, tilted up to 60 degrees.
PoseD random_view(kincal::test::RandomSource& random) {
  const Eigen::Matrix3d tilt = random.rotation_up_to(1.0);
  const Eigen::Matrix3d spin =
      Eigen::AngleAxisd(random.uniform(-3.14, 3.14), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const double distance = random.uniform(0.2, 1.5);
  return {tilt * spin, Eigen::Vector3d(random.uniform(-0.1, 0.1), random.uniform(-0.1, 0.1), distance)};
}

}  // namespace

TEST_CASE("pose_from_points matches the double-precision SVD fit, exact and noisy points") {
  kincal::test::RandomSource random(0x9053);
  double worst_rotation = 0.0, worst_translation = 0.0, worst_orthonormal = 0.0, worst_rms = 0.0;
  for (int trial = 0; trial < 1000; ++trial) {
    const auto square = square_fiducials(trial % 2 == 0);
    const PoseD truth = random_view(random);
    const double noise = trial % 3 == 0 ? 0.0 : random.uniform(0.0, 0.0005);  // up to 0.5 mm
    std::vector<Eigen::Vector3d> camera;
    for (const auto& s : square)
      camera.push_back(truth.rotation * s + truth.translation +
                       noise * Eigen::Vector3d(random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1)));
    const auto square_f = to_float(square), camera_f = to_float(camera);
    // The reference fits exactly the float inputs the code sees.
    std::vector<Eigen::Vector3d> square_d, camera_d;
    for (std::size_t i = 0; i < square.size(); ++i) {
      square_d.push_back(square_f[i].cast<double>());
      camera_d.push_back(camera_f[i].cast<double>());
    }
    const PoseD reference = kabsch(square_d, camera_d);

    PoseFit fit;
    REQUIRE(pose_from_points(square_f, camera_f, PoseOptions{}, fit) == PoseStatus::ok);
    const Eigen::Matrix3d r = fit.camera_T_square.rotation.cast<double>();
    worst_rotation = std::fmax(worst_rotation, rotation_angle(r, reference.rotation));
    worst_translation =
        std::fmax(worst_translation, (fit.camera_T_square.translation.cast<double>() - reference.translation).norm() /
                                         reference.translation.norm());
    worst_orthonormal =
        std::fmax(worst_orthonormal, (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff());
    CHECK(r.determinant() > 0.0);
    double sum2 = 0.0;
    for (std::size_t i = 0; i < square.size(); ++i)
      sum2 += (reference.rotation * square_d[i] + reference.translation - camera_d[i]).squaredNorm();
    const double reference_rms = std::sqrt(sum2 / static_cast<double>(square.size()));
    worst_rms = std::fmax(worst_rms, std::fabs(static_cast<double>(fit.residual_rms_m) - reference_rms));
    CHECK(fit.point_count == static_cast<int>(square.size()));
  }
  CHECK(worst_rotation <= static_cast<double>(kPoseRotationErrorRad));
  CHECK(worst_translation <= static_cast<double>(kPoseTranslationErrorPerM));
  CHECK(worst_orthonormal <= 5e-7);
  CHECK(worst_rms <= 2e-7);
  MESSAGE("pose_from_points worst rotation ", worst_rotation, " rad, translation ", worst_translation,
          " per m, orthonormality ", worst_orthonormal, ", rms ", worst_rms, " m");
}

TEST_CASE("Doty's stacked axes are not a rotation under noise; the fit always is") {
  kincal::test::RandomSource random(0xD07F);
  double worst_doty = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const auto square = square_fiducials(false);
    const PoseD truth = random_view(random);
    std::vector<Eigen::Vector3d> camera;
    for (const auto& s : square)
      camera.push_back(truth.rotation * s + truth.translation +
                       0.0005 * Eigen::Vector3d(random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1)));
    // Doty 7-33: x along the horizontal pair, y along the vertical pair, z = x cross y.
    const Eigen::Vector3d x = (camera[1] - camera[3]).normalized(), y = (camera[2] - camera[4]).normalized();
    Eigen::Matrix3d doty;
    doty << x, y, x.cross(y);
    worst_doty = std::fmax(worst_doty, (doty.transpose() * doty - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff());
    PoseFit fit;
    REQUIRE(pose_from_points(to_float(square), to_float(camera), PoseOptions{}, fit) == PoseStatus::ok);
    const Eigen::Matrix3d r = fit.camera_T_square.rotation.cast<double>();
    CHECK((r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= 5e-7);
  }
  CHECK(worst_doty > 1e-3);  // half a millimetre of noise on 89 mm baselines: ~1e-2 off orthogonal
}

TEST_CASE("pose_from_points refuses what it cannot solve") {
  const auto square = to_float(square_fiducials(false));
  PoseFit fit;
  const PoseOptions options;
  CHECK(pose_from_points(std::span(square).first(2), std::span(square).first(2), options, fit) ==
        PoseStatus::too_few_points);
  CHECK(pose_from_points(std::span(square).first(3), std::span(square).first(4), options, fit) ==
        PoseStatus::size_mismatch);
  std::vector<Vector3<float>> many(static_cast<std::size_t>(kMaxPosePoints) + 1, Vector3<float>::Zero());
  CHECK(pose_from_points(many, many, options, fit) == PoseStatus::too_many_points);

  // Centre and the horizontal pair: collinear, rotation about the x axis undetermined.
  const std::array<Vector3<float>, 3> line = {square[0], square[1], square[3]};
  CHECK(pose_from_points(line, line, options, fit) == PoseStatus::collinear_points);
  // Four points 10 um off a line 89 mm long.
  std::array<Vector3<float>, 4> almost = {square[0], square[1], square[3], Vector3<float>(0.01f, 1e-5f, 0.0f)};
  CHECK(pose_from_points(almost, almost, options, fit) == PoseStatus::collinear_points);
  // Good square points, but the measurements all on one spot.
  const std::array<Vector3<float>, 5> spot = {Vector3<float>(0, 0, 1), Vector3<float>(0, 0, 1), Vector3<float>(0, 0, 1),
                                              Vector3<float>(0, 0, 1), Vector3<float>(0, 0, 1)};
  CHECK(pose_from_points(square, spot, options, fit) == PoseStatus::collinear_points);
  // An octahedron measured in a mirror: every half-turn about an axis in the mirror plane fits
  // equally well, so no rotation is the unique best one. (A planar layout's mirror image is a
  // half-turn, which is why this needs points off the plane.)
  std::vector<Vector3<float>> octahedron, mirrored;
  for (int axis = 0; axis < 3; ++axis) {
    for (const float sign : {-0.05f, 0.05f}) {
      Vector3<float> p = Vector3<float>::Zero();
      p(axis) = sign;
      octahedron.push_back(p);
      mirrored.push_back(Vector3<float>(-p.x(), p.y(), p.z() + 1.0f));
    }
  }
  CHECK(pose_from_points(octahedron, mirrored, options, fit) == PoseStatus::ambiguous_rotation);
  CHECK(pose_from_points(octahedron, octahedron, options, fit) == PoseStatus::ok);
  std::vector<Vector3<float>> bad = square;
  bad[2].y() = NAN;
  CHECK(pose_from_points(square, bad, options, fit) == PoseStatus::non_finite);
}

TEST_CASE("pose_from_points: three points are enough, residual reflects noise") {
  const std::array<Vector3<float>, 3> square = {Vector3<float>(0, 0, 0), Vector3<float>(0.1f, 0, 0),
                                                Vector3<float>(0, 0.1f, 0)};
  const Eigen::Matrix3f r = Eigen::AngleAxisf(0.3f, Vector3<float>(1, 2, 3).normalized()).toRotationMatrix();
  std::array<Vector3<float>, 3> camera;
  for (std::size_t i = 0; i < 3; ++i) camera[i] = r * square[i] + Vector3<float>(0.05f, -0.02f, 0.7f);
  PoseFit fit;
  REQUIRE(pose_from_points(square, camera, PoseOptions{}, fit) == PoseStatus::ok);
  CHECK((fit.camera_T_square.rotation - r).cwiseAbs().maxCoeff() < 1e-6f);
  CHECK(fit.residual_rms_m < 1e-6f);
}

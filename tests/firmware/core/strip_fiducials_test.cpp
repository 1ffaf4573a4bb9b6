// strip_fiducials.hpp on synthetic blob lists: the neighbouring squares' fiducials placed where a
// strip puts them are taken with their targets in the reference square's frame; blobs of the
// wrong size, off the prediction, cut by the border, already taken or outside the frame are not;
// the output's capacity and every refused argument.
#include "firmware/core/strip_fiducials.hpp"

#include <doctest.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

using namespace kincal::core;

namespace {

constexpr float kSideM = 0.00635f;      // the small fiducial's side s (1/4 inch)
constexpr float kPitchM = 16 * kSideM;  // 4-inch squares side by side
constexpr std::uint16_t kWidth = 640, kHeight = 480;

CameraIntrinsics camera() {
  CameraIntrinsics c;
  c.fx_px = 520.0f;
  c.fy_px = 520.0f;
  c.cx_px = 321.0f;
  c.cy_px = 238.0f;
  c.distortion = {-0.03f, 0.0f, 0.0f, 0.0f, 0.0f};
  return c;
}

// p1..p6 of a square (fiducial_id.hpp's layout), p4 twice as long along y.
std::array<StripFiducial, 6> pattern() {
  const float s = kSideM, h = 0.5f * kSideM;
  std::array<StripFiducial, 6> p{};
  const float centres[6][2] = {{-7 * s, 7 * s}, {0, 7 * s}, {-7 * s, 0}, {0, 0}, {7 * s, 0}, {0, -7 * s}};
  for (std::size_t k = 0; k < 6; ++k) {
    p[k].centre_m = Vector2<float>(centres[k][0], centres[k][1]);
    p[k].half_size_m = Vector2<float>(h, k == 3 ? s : h);
  }
  return p;
}

// The square facing the camera 0.35 m away, tilted 15 degrees about an oblique axis.
RigidTransform<float> camera_T_square() {
  RigidTransform<float> t;
  const Eigen::Matrix3d facing = Eigen::Vector3d(1, -1, -1).asDiagonal();
  t.rotation = (Eigen::AngleAxisd(0.26, Eigen::Vector3d(0.6, 0.8, 0).normalized()) * facing).cast<float>();
  t.translation = Vector3<float>(0.01f, -0.005f, 0.35f);
  return t;
}

Vector2<float> project(const Vector2<float>& target_m) {
  Vector2<float> px;
  REQUIRE(project_point(camera(), camera_T_square() * Vector3<float>(target_m.x(), target_m.y(), 0.0f), px) ==
          CameraStatus::ok);
  return px;
}

// A blob at `pixel` of `area` pixels.
Blob blob_at(const Vector2<float>& pixel, std::uint32_t area_px, std::uint8_t flags = 0) {
  Blob b;
  b.x_px = q16_16::from_double(pixel.x());
  b.y_px = q16_16::from_double(pixel.y());
  b.area_px = area_px;
  b.flags = flags;
  return b;
}

// The image area of fiducial k of square `offset` (shoelace over the projected corners).
float image_area_px2(std::size_t k, int offset) {
  const StripFiducial f = pattern()[k];
  const Vector2<float> c = f.centre_m + Vector2<float>(static_cast<float>(offset) * kPitchM, 0.0f);
  const float sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1};
  float twice = 0.0f;
  for (int i = 0; i < 4; ++i) {
    const int j = (i + 1) % 4;
    const Vector2<float> a = project(c + Vector2<float>(sx[i] * f.half_size_m.x(), sy[i] * f.half_size_m.y()));
    const Vector2<float> b = project(c + Vector2<float>(sx[j] * f.half_size_m.x(), sy[j] * f.half_size_m.y()));
    twice += a.x() * b.y() - b.x() * a.y();
  }
  return 0.5f * std::fabs(twice);
}

struct Setup {
  std::vector<Blob> blobs;
  std::vector<std::uint8_t> taken;
  std::array<PlanarCorrespondence, kPlanarPoseMaxPoints> points{};
  StripMatch match;

  // One blob per fiducial of the squares in `offsets`, where the strip puts it, at its image area;
  // square 0's blobs already taken (the reference square's own).
  explicit Setup(std::initializer_list<int> offsets) {
    for (const int n : offsets)
      for (std::size_t k = 0; k < 6; ++k) {
        const Vector2<float> target = pattern()[k].centre_m + Vector2<float>(static_cast<float>(n) * kPitchM, 0.0f);
        blobs.push_back(blob_at(project(target), static_cast<std::uint32_t>(std::lround(image_area_px2(k, n)))));
        taken.push_back(n == 0 ? 1 : 0);
      }
  }
  StripMatchStatus run(std::size_t point_count = 0, std::size_t capacity = kPlanarPoseMaxPoints,
                       std::uint8_t reference_found = 0x3F, float pitch_m = kPitchM) {
    const auto p = pattern();
    return match_strip_fiducials(camera(), kWidth, kHeight, camera_T_square(), p, reference_found, pitch_m, blobs,
                                 taken, StripMatchOptions{}, std::span<PlanarCorrespondence>(points.data(), capacity),
                                 point_count, match);
  }
};

}  // namespace

TEST_CASE("strip fiducials: the neighbours' fiducials are taken with their targets in the square's frame") {
  Setup s({0, -1, 1});
  REQUIRE(s.run(2) == StripMatchStatus::ok);
  CHECK(s.match.points_added == 12);
  CHECK(s.match.squares_matched == 2);
  // Every non-reference blob taken once; the reference's untouched.
  for (std::size_t i = 0; i < s.blobs.size(); ++i) CHECK(s.taken[i] == 1);
  // Appended after the caller's two points, in order -1 then +1, pattern order within a square;
  // each pixel is its blob's, each target its fiducial's in the reference square's frame.
  for (std::size_t j = 0; j < 12; ++j) {
    const int n = j < 6 ? -1 : 1;
    const std::size_t k = j % 6;
    const PlanarCorrespondence& c = s.points[2 + j];
    const Vector2<float> target = pattern()[k].centre_m + Vector2<float>(static_cast<float>(n) * kPitchM, 0.0f);
    CHECK(c.target_m.x() == doctest::Approx(target.x()).epsilon(1e-6));
    CHECK(c.target_m.y() == doctest::Approx(target.y()).epsilon(1e-6));
    CHECK(c.fiducial_half_size_m == pattern()[k].half_size_m);
    const Blob& b = s.blobs[(n == -1 ? 6 : 12) + k];
    CHECK(c.pixel_px.x() == b.x_px.to_float());
    CHECK(c.pixel_px.y() == b.y_px.to_float());
  }
  // Squares beyond those in the frame are predicted outside it: nothing more is taken.
  CHECK(s.points[14].target_m == Vector2<float>::Zero());
}

TEST_CASE("strip fiducials: blobs of the wrong size, off the prediction, cut or taken are left") {
  Setup s({-1});
  const float side_px = std::sqrt(image_area_px2(1, -1));
  s.blobs[0].area_px *= 3;  // p1: too large
  s.blobs[1].x_px =
      q16_16::from_double(s.blobs[1].x_px.to_double() + 1.2 * static_cast<double>(side_px));  // p2: beyond the gate
  s.blobs[2].flags = kTouchesBorder;                                                          // p3: cut by the frame
  s.blobs[3].flags = kIncomplete;                                                             // p4: pixels lost
  s.taken[4] = 1;                                                                             // p5: another square's
  REQUIRE(s.run() == StripMatchStatus::ok);
  CHECK(s.match.points_added == 1);  // p6 only
  CHECK(s.match.squares_matched == 1);
  CHECK(s.points[0].pixel_px.x() == s.blobs[5].x_px.to_float());
  CHECK(s.taken == std::vector<std::uint8_t>{0, 0, 0, 0, 1, 1});

  // A blob nudged within the gate is still taken, and the nearest of two candidates wins.
  Setup t({-1});
  t.blobs[1].x_px = q16_16::from_double(t.blobs[1].x_px.to_double() + 0.8 * static_cast<double>(side_px));
  t.blobs.push_back(t.blobs[1]);
  t.blobs.back().x_px = q16_16::from_double(t.blobs[1].x_px.to_double() - 0.5 * static_cast<double>(side_px));
  t.taken.push_back(0);
  REQUIRE(t.run() == StripMatchStatus::ok);
  CHECK(t.match.points_added == 6);
  CHECK(t.taken[1] == 0);
  CHECK(t.taken.back() == 1);
}

TEST_CASE("strip fiducials: the reference square's own missing fiducials are found, also without a pitch") {
  // FID gave p1, p2, p4, p6 of square 0 (their blobs taken); p3 and p5 are searched where the
  // pose puts them, not the neighbours' p5 and p3 two sides beyond them.
  Setup s({0, -1, 1});
  for (const std::size_t k : {2u, 4u}) s.taken[k] = 0;
  REQUIRE(s.run(0, kPlanarPoseMaxPoints, 0b101011, 0.0f) == StripMatchStatus::ok);
  CHECK(s.match.points_added == 2);
  CHECK(s.match.reference_added == 2);
  CHECK(s.match.squares_matched == 0);
  CHECK(s.points[0].pixel_px.x() == s.blobs[2].x_px.to_float());  // p3
  CHECK(s.points[1].pixel_px.x() == s.blobs[4].x_px.to_float());  // p5
  CHECK(s.points[0].target_m == pattern()[2].centre_m);
  for (std::size_t i = 6; i < s.blobs.size(); ++i) CHECK(s.taken[i] == 0);

  // With the pitch: the square's two, then both neighbours' six.
  for (const std::size_t k : {2u, 4u}) s.taken[k] = 0;
  REQUIRE(s.run(0, kPlanarPoseMaxPoints, 0b101011) == StripMatchStatus::ok);
  CHECK(s.match.points_added == 14);
  CHECK(s.match.reference_added == 2);
  CHECK(s.match.squares_matched == 2);
}

TEST_CASE("strip fiducials: the output stops when full; refused arguments") {
  Setup s({-1, 1});
  REQUIRE(s.run(0, 4) == StripMatchStatus::ok);
  CHECK(s.match.points_added == 4);
  CHECK(s.match.squares_matched == 1);

  const auto p = pattern();
  const std::array<StripFiducial, 9> too_long{};
  StripMatch m;
  std::array<PlanarCorrespondence, 4> points{};
  const auto call = [&](float pitch_m, std::span<const StripFiducial> pat, std::size_t taken_size, std::uint16_t width,
                        std::size_t point_count) {
    return match_strip_fiducials(camera(), width, kHeight, camera_T_square(), pat, 0x3F, pitch_m, s.blobs,
                                 std::span<std::uint8_t>(s.taken.data(), taken_size), StripMatchOptions{}, points,
                                 point_count, m);
  };
  const std::size_t n = s.blobs.size();
  CHECK(call(kPitchM, p, n, kWidth, 0) == StripMatchStatus::ok);
  CHECK(call(0.0f, p, n, kWidth, 0) == StripMatchStatus::ok);  // the reference square alone
  CHECK(call(-kPitchM, p, n, kWidth, 0) == StripMatchStatus::bad_arguments);
  CHECK(call(std::numeric_limits<float>::infinity(), p, n, kWidth, 0) == StripMatchStatus::bad_arguments);
  CHECK(call(std::numeric_limits<float>::quiet_NaN(), p, n, kWidth, 0) == StripMatchStatus::bad_arguments);
  CHECK(call(kPitchM, too_long, n, kWidth, 0) == StripMatchStatus::bad_arguments);
  CHECK(call(kPitchM, p, n - 1, kWidth, 0) == StripMatchStatus::bad_arguments);
  CHECK(call(kPitchM, p, n, 0, 0) == StripMatchStatus::bad_arguments);
  CHECK(call(kPitchM, p, n, kWidth, 5) == StripMatchStatus::bad_arguments);
}

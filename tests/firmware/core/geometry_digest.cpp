// The firmware core's float geometry, bit for bit: every entry point over a few hundred
// deterministic random inputs, one line per function with a 64-bit digest of every output bit
// pattern and status. Built for both targets; tests/firmware/core/compare_geometry_digests.py
// runs the native program and the Cortex-M4 image (QEMU) and fails naming each function whose
// digest differs.
//
// Output, one line per function:  DIGEST <name> <cases> <cases with status ok> <digest, hex>
//
// Inputs come from splitmix64 through float arithmetic only (integer-to-float conversion, +, -,
// *, /, sqrt: all correctly rounded on both targets), never through libm's transcendental
// functions or Eigen reductions, whose results may differ between newlib and glibc or between
// Eigen's scalar and SSE paths; so the inputs are the same bits on both targets and a digest
// that differs points at the function it names. Each function draws from its own seed, so
// adding a function leaves the others' inputs alone.
//
// NaN: every NaN enters the digest as one pattern. Which NaN an operation returns is not part
// of IEEE 754's promise (x86 makes a negative default NaN, ARM a positive one) nor of ours; that
// the result is a NaN is.
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <span>
#include <type_traits>

#include "firmware/core/camera_model.hpp"
#include "firmware/core/correction.hpp"
#include "firmware/core/error_model.hpp"
#include "firmware/core/joint_map.hpp"
#include "firmware/core/link_model.hpp"
#include "firmware/core/planar_pose.hpp"
#include "firmware/core/pose_from_points.hpp"
#include "firmware/core/range_plane.hpp"
#include "firmware/core/rigid_transform.hpp"
#include "firmware/core/sin_cos.hpp"
#include "firmware/core/stereo.hpp"
#include "tests/firmware/core/chain_fixtures.hpp"
#include "tests/firmware/core/splitmix64.hpp"

using namespace kincal::core;

namespace {

constexpr int kCases = 256;

// Float inputs without libm and without Eigen reductions (see the top of the file). Draw at
// most one value per function argument list: C++ leaves the order of argument evaluation open,
// and GCC's differs between x86-64 and ARM; braced lists ({a, b, c}) are evaluated in order.
class FloatSource {
 public:
  explicit FloatSource(std::uint64_t seed) : bits_(seed) {}

  int index(int count) { return bits_.below(count); }
  // Uniform in [lo, hi) from 24 random bits.
  float uniform(float lo, float hi) {
    const float unit = static_cast<float>(bits_.next() >> 40) * 0x1.0p-24f;
    return lo + (hi - lo) * unit;
  }
  Vector3<float> vector(float half_width) {
    return {uniform(-half_width, half_width), uniform(-half_width, half_width), uniform(-half_width, half_width)};
  }
  // A rotation from a random unit quaternion (normalized by one correctly rounded sqrt);
  // max_sin_half_angle < 1 keeps it near the identity.
  Matrix3<float> rotation(float max_sin_half_angle = 1.0f) {
    for (;;) {
      const float x = uniform(-max_sin_half_angle, max_sin_half_angle),
                  y = uniform(-max_sin_half_angle, max_sin_half_angle),
                  z = uniform(-max_sin_half_angle, max_sin_half_angle);
      const float w = max_sin_half_angle < 1.0f ? 1.0f : uniform(-1.0f, 1.0f);
      const float norm2 = ((w * w + x * x) + y * y) + z * z;
      if (!(norm2 > 0.01f && norm2 <= (max_sin_half_angle < 1.0f ? 4.0f : 1.0f))) continue;
      const float inverse_norm = 1.0f / std::sqrt(norm2);
      return Eigen::Quaternionf(w * inverse_norm, x * inverse_norm, y * inverse_norm, z * inverse_norm)
          .toRotationMatrix();
    }
  }
  RigidTransform<float> transform(float max_offset_m) {
    RigidTransform<float> t;
    t.rotation = rotation();
    t.translation = vector(max_offset_m);
    return t;
  }

 private:
  kincal::test::Splitmix64 bits_;
};

// FNV-1a over 32-bit words: the outputs' bit patterns, statuses and counts.
class Digest {
 public:
  explicit Digest(const char* name) : name_(name) {}
  ~Digest() { std::printf("DIGEST %s %d %d %016llx\n", name_, cases_, ok_, static_cast<unsigned long long>(hash_)); }
  Digest(const Digest&) = delete;
  Digest& operator=(const Digest&) = delete;

  // One call: its status (counted ok when it equals `ok`) and every output it wrote.
  template <class Status, class... Outputs>
  void add_call(Status status, Status ok, const Outputs&... outputs) {
    add_case(status == ok);
    add(status);
    (add(outputs), ...);
  }
  void add_case(bool ok) {
    ++cases_;
    ok_ += ok ? 1 : 0;
    add_word(ok ? 1u : 0u);
  }
  void add(float v) {
    std::uint32_t bits = 0x7FC00000u;
    if (!std::isnan(v)) std::memcpy(&bits, &v, sizeof bits);
    add_word(bits);
  }
  void add(int v) { add_word(static_cast<std::uint32_t>(v)); }
  template <class Status>
  requires std::is_enum_v<Status>
  void add(Status s) { add_word(static_cast<std::uint32_t>(s)); }
  template <class Derived>
  void add(const Eigen::MatrixBase<Derived>& m) {
    for (Eigen::Index c = 0; c < m.cols(); ++c)
      for (Eigen::Index r = 0; r < m.rows(); ++r) add(static_cast<float>(m(r, c)));
  }
  void add(const SinCos<float>& sc) {
    add(sc.sin);
    add(sc.cos);
  }
  void add(const RigidTransform<float>& t) {
    add(t.rotation);
    add(t.translation);
  }
  void add(const StereoPoint& p) {
    add(p.point_left_m);
    add(p.depth_sigma_m);
    add(p.ray_gap_px);
  }

 private:
  void add_word(std::uint32_t word) {
    for (int byte = 0; byte < 4; ++byte) {
      hash_ ^= (word >> (8 * byte)) & 0xFFu;
      hash_ *= 0x100000001B3u;
    }
  }
  const char* name_;
  std::uint64_t hash_ = 0xCBF29CE484222325u;
  int cases_ = 0;
  int ok_ = 0;
};

// --- Trigonometry and rigid transforms --------------------------------------------------------

void digest_trigonometry() {
  {
    Digest d("sin_cos");
    FloatSource r(1);
    for (int i = 0; i < kCases; ++i) {
      // Mostly joint angles; some far out (the reduction's exactness), a few beyond the range.
      const int kind = r.index(8);
      const float limit = kSinCosMaxArgumentRad;
      const float angle = kind == 0   ? r.uniform(-limit, limit)
                          : kind == 1 ? r.uniform(-2.0f, 2.0f) * limit
                                      : r.uniform(-7.0f, 7.0f);
      d.add_case(std::fabs(angle) <= limit);
      d.add(sin_cos(angle));
    }
  }
  {
    Digest d("small_angle_sin_cos+angle_sum");
    FloatSource r(2);
    for (int i = 0; i < kCases; ++i) {
      const SinCos<float> a = sin_cos(r.uniform(-3.2f, 3.2f));
      const SinCos<float> b = small_angle_sin_cos(r.uniform(-kSmallAngleMaxRad, kSmallAngleMaxRad));
      d.add_case(true);
      d.add(b);
      d.add(angle_sum(a, b));
    }
  }
  {
    Digest d("rigid_transform");
    FloatSource r(3);
    for (int i = 0; i < kCases; ++i) {
      const RigidTransform<float> a = r.transform(1.0f), b = r.transform(1.0f);
      RigidTransform<float> nudge;
      nudge.rotation = r.rotation(0.05f);
      nudge.translation = r.vector(0.01f);
      const RigidTransform<float> near = nudge * a;
      d.add_case(true);
      d.add(a * b);
      d.add(a.inverse());
      d.add(a * b.translation);
      d.add(small_pose_difference(near, a));
    }
  }
}

// --- Link models, forward kinematics, error model -------------------------------------------

ChainModel<float> random_chain(FloatSource& r, int joint_count) {
  ChainModel<float> m;
  m.joint_count = joint_count;
  for (std::size_t i = 0; i < static_cast<std::size_t>(joint_count); ++i) {
    Link<float>& link = m.links[i];
    link.convention = static_cast<LinkConvention>(r.index(3));
    link.joint = r.index(4) == 0 ? JointType::prismatic : JointType::revolute;
    link.parameters = {r.uniform(-0.5f, 0.5f), r.uniform(-3.1f, 3.1f), r.uniform(-1.0f, 1.0f), r.uniform(-3.1f, 3.1f),
                       r.uniform(-0.3f, 0.3f)};
  }
  m.base_T_frame0 = r.transform(0.5f);
  m.flange_T_tool = r.transform(0.2f);
  return m;
}

JointVector<float> random_joints(FloatSource& r, const ChainModel<float>& m, float max_angle_rad) {
  JointVector<float> q = JointVector<float>::Zero();
  for (int i = 0; i < m.joint_count; ++i) {
    q(i) = m.links[static_cast<std::size_t>(i)].joint == JointType::revolute ? r.uniform(-max_angle_rad, max_angle_rad)
                                                                             : r.uniform(-0.5f, 0.5f);
  }
  return q;
}

// Every parameter of the set off by +-angle_rad or +-length_m, random signs (chain_fixtures.hpp:
// integer bits only, so the same on both targets), in float.
ErrorVector<float> sign_errors(kincal::test::RandomSource& signs, const ParameterSet& set, double angle_rad,
                               double length_m) {
  return kincal::test::random_sign_errors(signs, set, angle_rad, length_m).cast<float>();
}

void digest_kinematics() {
  {
    Digest d("link_transform");
    FloatSource r(10);
    for (int i = 0; i < kCases; ++i) {
      const ChainModel<float> m = random_chain(r, 1);
      const Link<float>& link = m.links[0];
      const float q = link.joint == JointType::revolute ? r.uniform(-3.1f, 3.1f) : r.uniform(-0.5f, 0.5f);
      const LinkParameters<float>& p = link.parameters;
      d.add_case(true);
      d.add(link_transform(link, q));
      d.add(link_transform(link.convention, p.d_m, p.a_m, sin_cos(p.theta_rad), sin_cos(p.alpha_rad),
                           sin_cos(p.beta_rad)));
    }
  }
  Digest prepare("prepare_chain+joint_trig");
  Digest frames_digest("forward_kinematics");
  Digest tool("tool_pose");
  Digest direct("forward_kinematics(model)");
  Digest parameters("apply_parameter_errors+full_parameter_set");
  Digest error_matrix_digest("parameter_jacobian");
  Digest joints("joint_jacobian");
  FloatSource r(11);
  kincal::test::RandomSource signs(12);
  // In static storage: the error matrix and chains are kilobytes, the M4 test stack is small.
  static PreparedChain<float> chain;
  static ChainFrames<float> frames;
  static ChainModel<float> actual;
  static ErrorMatrix<float> error_matrix;
  for (int i = 0; i < kCases; ++i) {
    const ChainModel<float> m = random_chain(r, 1 + r.index(kMaxJoints));
    const JointVector<float> q = random_joints(r, m, 3.1f);
    prepare_chain(m, chain);
    JointTrig trig;
    joint_trig(chain, q, trig);
    prepare.add_case(true);
    for (const PreparedLink<float>& link : chain.links) {
      prepare.add(link.theta);
      prepare.add(link.alpha);
      prepare.add(link.beta);
    }
    for (int k = 0; k < m.joint_count; ++k) prepare.add(trig[static_cast<std::size_t>(k)]);

    forward_kinematics(chain, q, trig, frames);
    frames_digest.add_case(true);
    for (int k = 0; k <= m.joint_count; ++k) frames_digest.add(frames.base_T_frame[static_cast<std::size_t>(k)]);
    frames_digest.add(frames.base_T_tool);

    RigidTransform<float> base_T_tool;
    tool_pose(chain, q, trig, base_T_tool);
    tool.add_case(true);
    tool.add(base_T_tool);
    direct.add_case(true);
    direct.add(forward_kinematics(m, q));

    const bool with_base = r.index(2) == 0;
    const bool with_tool = r.index(2) == 0;
    const ParameterSet set = full_parameter_set(m, with_base, with_tool);
    const ErrorModelStatus applied = apply_parameter_errors(m, set, sign_errors(signs, set, 0.01, 0.002), actual);
    parameters.add_call(applied, ErrorModelStatus::ok, set.count, actual.base_T_frame0, actual.flange_T_tool);
    for (const Link<float>& link : actual.links) {
      const LinkParameters<float>& p = link.parameters;
      for (const float v : {p.d_m, p.theta_rad, p.a_m, p.alpha_rad, p.beta_rad}) parameters.add(v);
    }

    error_matrix.setZero();
    const ErrorModelStatus jacobian_status = parameter_jacobian(chain, q, trig, frames, set, error_matrix);
    error_matrix_digest.add_call(jacobian_status, ErrorModelStatus::ok, error_matrix);

    JointJacobian<float> jacobian;
    joint_jacobian(chain, frames, jacobian);
    joints.add_case(true);
    joints.add(jacobian);
  }
  Digest arid("doty_arid_error_matrix");
  for (int i = 0; i < kCases; ++i) {
    const std::array<float, 4> theta = {r.uniform(-3.1f, 3.1f), r.uniform(-3.1f, 3.1f), r.uniform(-3.1f, 3.1f),
                                        r.uniform(-3.1f, 3.1f)};
    const std::array<float, 3> a = {r.uniform(0.0f, 0.5f), r.uniform(0.0f, 0.5f), r.uniform(0.0f, 0.5f)};
    AridErrorMatrix e;
    doty_arid_error_matrix(theta, a, e);
    arid.add_case(true);
    arid.add(e);
  }
}

// --- Range plane, camera, pose, stereo ----------------------------------------------------------

void digest_range_plane() {
  Digest prepare("prepare_range_plane");
  Digest fit("fit_range_plane");
  FloatSource r(20);
  for (int i = 0; i < kCases; ++i) {
    const float spacing_m = r.uniform(0.05f, 0.3f);
    const RangeModel range_model = r.index(2) == 0 ? RangeModel::along_beam : RangeModel::perpendicular;
    RangeSensorLayout layout = plus_pattern_layout(spacing_m, range_model);
    for (Vector2<float>& p : layout.position_m) p += Vector2<float>{r.uniform(-0.01f, 0.01f), r.uniform(-0.01f, 0.01f)};
    layout.origin_z_m = r.uniform(-0.02f, 0.02f);
    RangePlaneModel model;
    const PlaneStatus prepared = prepare_range_plane(layout, model);
    prepare.add_call(prepared, PlaneStatus::ok);
    if (prepared != PlaneStatus::ok) continue;  // the model's matrices are not written
    prepare.add(model.least_squares);
    for (const auto& m : model.three_point) prepare.add(m);
    prepare.add(model.null_vector);

    // Readings of a tilted plane, with noise; now and then one missing or out of limits.
    const float base_m = r.uniform(0.05f, 2.0f), tilt_x = r.uniform(-0.6f, 0.6f), tilt_y = r.uniform(-0.6f, 0.6f);
    std::array<float, kRangeSensorCount> range_m{};
    for (std::size_t k = 0; k < kRangeSensorCount; ++k) {
      const Vector2<float>& p = layout.position_m[k];
      range_m[k] = base_m + tilt_x * p.x() + tilt_y * p.y() + r.uniform(-0.002f, 0.002f);
    }
    const int fault = r.index(8);
    if (fault == 0) range_m[static_cast<std::size_t>(r.index(4))] = std::numeric_limits<float>::quiet_NaN();
    if (fault == 1) range_m[static_cast<std::size_t>(r.index(4))] = 9.0f;
    CalibrationPlane plane;
    const PlaneStatus fitted = fit_range_plane(model, range_m, plane);
    fit.add_call(fitted, PlaneStatus::ok, plane.normal, plane.distance_m, plane.flatness_residual_m,
                 static_cast<int>(plane.sensors_used));
  }
}

CameraIntrinsics random_camera(FloatSource& r) {
  CameraIntrinsics c;
  c.fx_px = r.uniform(400.0f, 1200.0f);
  c.fy_px = c.fx_px * r.uniform(0.98f, 1.02f);
  c.cx_px = r.uniform(300.0f, 340.0f);
  c.cy_px = r.uniform(220.0f, 260.0f);
  c.distortion = {r.uniform(-0.4f, 0.25f), r.uniform(-0.1f, 0.25f), r.uniform(-0.002f, 0.002f),
                  r.uniform(-0.002f, 0.002f), r.uniform(-0.1f, 0.1f)};
  c.max_normalized_radius = 1.2f;
  return c;
}

CalibrationPlane random_plane(FloatSource& r) {
  CalibrationPlane plane;
  plane.normal = r.rotation(0.3f).col(2);
  plane.distance_m = r.uniform(0.1f, 2.0f);
  return plane;
}

void digest_camera() {
  Digest project("project_point");
  Digest distort("distort_normalized");
  Digest normalized_digest("pixel_to_normalized");
  Digest on_plane("point_on_plane");
  Digest plane_point("pixel_to_plane_point");
  FloatSource r(30);
  for (int i = 0; i < kCases; ++i) {
    const CameraIntrinsics camera = random_camera(r);
    const Vector3<float> point{r.uniform(-1.0f, 1.0f), r.uniform(-0.8f, 0.8f), r.uniform(-0.1f, 2.0f)};
    Vector2<float> pixel(0.0f, 0.0f);
    const CameraStatus projected = project_point(camera, point, pixel);
    project.add_call(projected, CameraStatus::ok, pixel);

    distort.add_case(true);
    distort.add(distort_normalized(camera.distortion, Vector2<float>{r.uniform(-1.0f, 1.0f), r.uniform(-1.0f, 1.0f)}));

    const Vector2<float> pixel_in{r.uniform(-0.5f, 639.5f), r.uniform(-0.5f, 479.5f)};
    NormalizedPoint normalized;  // written on ok only: start from zeros, not from stack contents
    normalized.xy.setZero();
    normalized.xy_per_px.setZero();
    const CameraStatus undistorted = pixel_to_normalized(camera, pixel_in, normalized);
    normalized_digest.add_call(undistorted, CameraStatus::ok, normalized.xy, normalized.xy_per_px);

    const CalibrationPlane plane = random_plane(r);
    Vector3<float> on(0.0f, 0.0f, 0.0f);
    const CameraStatus met = point_on_plane(plane, Vector2<float>{r.uniform(-1.5f, 1.5f), r.uniform(-1.5f, 1.5f)}, on);
    on_plane.add_call(met, CameraStatus::ok, on);

    Vector3<float> fiducial(0.0f, 0.0f, 0.0f);
    const CameraStatus both = pixel_to_plane_point(camera, plane, pixel_in, fiducial);
    plane_point.add_call(both, CameraStatus::ok, fiducial);
  }
}

void digest_pose() {
  Digest d("pose_from_points");
  FloatSource r(40);
  for (int i = 0; i < kCases; ++i) {
    const int n = 3 + r.index(6);
    std::array<Vector3<float>, 8> square{}, camera{};
    RigidTransform<float> camera_T_square;
    camera_T_square.rotation = r.rotation();
    camera_T_square.translation = Vector3<float>{r.uniform(-0.1f, 0.1f), r.uniform(-0.1f, 0.1f), r.uniform(0.2f, 1.5f)};
    const float noise_m = r.index(2) == 0 ? 0.0f : 0.0005f;
    const bool collinear = r.index(16) == 0;
    for (std::size_t k = 0; k < static_cast<std::size_t>(n); ++k) {
      square[k] = Vector3<float>{r.uniform(-0.05f, 0.05f), collinear ? 0.0f : r.uniform(-0.05f, 0.05f), 0.0f};
      camera[k] = camera_T_square * square[k] + r.vector(noise_m);
    }
    const auto count = static_cast<std::size_t>(n);
    PoseFit fit;
    const PoseStatus status =
        pose_from_points(std::span(square).first(count), std::span(camera).first(count), PoseOptions{}, fit);
    d.add_call(status, PoseStatus::ok, fit.camera_T_square, fit.residual_rms_m, fit.point_count);
  }
}

void digest_stereo() {
  Digest parallel("triangulate_parallel");
  Digest general("triangulate_pair");
  FloatSource r(50);
  for (int i = 0; i < kCases; ++i) {
    ParallelStereoRig rig;
    rig.focal_x_px = r.uniform(500.0f, 1500.0f);
    rig.focal_y_px = rig.focal_x_px * r.uniform(0.8f, 1.2f);
    rig.baseline_m = r.uniform(0.05f, 0.3f);
    rig.principal_left_px = Vector2<float>{r.uniform(300.0f, 340.0f), r.uniform(220.0f, 260.0f)};
    rig.principal_right_px = Vector2<float>{r.uniform(300.0f, 340.0f), rig.principal_left_px.y()};
    const Vector2<float> left_px{r.uniform(0.0f, 640.0f), r.uniform(0.0f, 480.0f)};
    const Vector2<float> right_px{left_px.x() - r.uniform(-5.0f, 200.0f), left_px.y() + r.uniform(-2.5f, 2.5f)};
    StereoPoint point;
    const StereoStatus status = triangulate_parallel(rig, left_px, right_px, r.uniform(0.0f, 1.0f), point);
    parallel.add_call(status, StereoStatus::ok, point);
  }
  for (int i = 0; i < kCases; ++i) {
    StereoPair pair;
    pair.left = random_camera(r);
    pair.right = random_camera(r);
    pair.left_T_right.rotation = r.rotation(0.05f);
    pair.left_T_right.translation = Vector3<float>{r.uniform(0.05f, 0.3f), r.uniform(-0.01f, 0.01f), 0.0f};
    const Vector3<float> p{r.uniform(-0.5f, 0.5f), r.uniform(-0.4f, 0.4f), r.uniform(0.5f, 5.0f)};
    Vector2<float> left_px(0.0f, 0.0f), right_px(0.0f, 0.0f);
    const bool projected = project_point(pair.left, p, left_px) == CameraStatus::ok &&
                           project_point(pair.right, pair.left_T_right.inverse() * p, right_px) == CameraStatus::ok;
    // Centroid noise; now and then a mismatched centroid.
    left_px += Vector2<float>{r.uniform(-0.3f, 0.3f), r.uniform(-0.3f, 0.3f)};
    if (r.index(8) == 0) right_px.y() += r.uniform(-20.0f, 20.0f);
    StereoPoint point;
    const StereoStatus status = projected ? triangulate_pair(pair, left_px, right_px, r.uniform(0.0f, 1.0f), point)
                                          : StereoStatus::undistortion_failed;
    general.add_call(status, StereoStatus::ok, point);
  }
}

// --- Online correction --------------------------------------------------------------------------

void digest_correction() {
  Digest prepare("prepare_correction");
  Digest correct("correct_joint_target");
  FloatSource r(60);
  kincal::test::RandomSource signs(61);
  // In static storage, as on the platform: model and workspace are kilobytes.
  static CorrectionModel model;
  static CorrectionWorkspace workspace;
  const ChainModel<float> arm = kincal::test::to_float(kincal::test::puma_like_arm());
  for (int i = 0; i < kCases; ++i) {
    // Half the cases the PUMA-like arm, half random chains of 1..8 joints.
    const bool puma = r.index(2) == 0;
    const ChainModel<float> nominal = puma ? arm : random_chain(r, 1 + r.index(kMaxJoints));
    const ParameterSet set = full_parameter_set(nominal, true, true);
    CorrectionOptions options;
    options.refinement_steps = r.index(kMaxRefinementSteps + 1);
    options.max_joint_step = 0.5f;
    const CorrectionStatus prepared =
        prepare_correction(nominal, set, sign_errors(signs, set, 0.0087, 0.001), options, model);
    prepare.add_call(prepared, CorrectionStatus::ok);
    for (const PreparedChain<float>* c : {&model.nominal, &model.calibrated}) {
      for (const PreparedLink<float>& link : c->links) {
        prepare.add(link.theta);
        prepare.add(link.alpha);
        prepare.add(link.beta);
        prepare.add(link.d_m);
        prepare.add(link.a_m);
      }
      prepare.add(c->base_T_frame0);
      prepare.add(c->flange_T_tool);
    }
    if (prepared != CorrectionStatus::ok) continue;

    Correction correction;  // its Eigen members start uninitialized, and failures leave them so
    correction.pose_error.setZero();
    correction.corrected_joint_target.setZero();
    const CorrectionStatus status = correct_joint_target(model, workspace, random_joints(r, nominal, 2.5f), correction);
    correct.add_call(status, CorrectionStatus::ok, correction.base_T_target, correction.base_T_corrected,
                     correction.pose_error, correction.corrected_joint_target);
  }
}

// --- Joint map (issue #12) -----------------------------------------------------------------------

MassModel<float> random_masses(FloatSource& r) {
  MassModel<float> m;
  for (std::size_t i = 0; i < kMaxJoints; ++i) {
    m.link_mass_kg[i] = r.uniform(0.0f, 20.0f);
    const Vector3<float> c = r.vector(0.3f);
    m.link_centre_of_mass_m[i] = {c(0), c(1), c(2)};
  }
  m.payload_mass_kg = r.uniform(0.0f, 5.0f);
  const Vector3<float> c = r.vector(0.2f), g = r.vector(9.8f);
  m.payload_centre_of_mass_m = {c(0), c(1), c(2)};
  m.gravity_mps2 = {g(0), g(1), g(2)};
  return m;
}

// Identity rows but for a few couplings to earlier or later joints, scales near 1.
JointMap<float> random_map(FloatSource& r, int joint_count, float max_compliance) {
  JointMap<float> map;
  map.joint_count = joint_count;
  for (int i = 0; i < joint_count; ++i) {
    if (r.index(3) == 0) map.coupling(i, r.index(joint_count)) += r.uniform(-1.0f, 1.0f);
    map.scale(i) = r.uniform(0.999f, 1.001f);
    map.compliance(i) = r.uniform(0.0f, max_compliance);
  }
  return map;
}

void digest_joint_map() {
  {
    Digest d("gravity_forces");
    FloatSource r(90);
    for (int i = 0; i < kCases; ++i) {
      const ChainModel<float> m = random_chain(r, 1 + r.index(kMaxJoints));
      const MassModel<float> masses = random_masses(r);
      PreparedChain<float> chain;
      prepare_chain(m, chain);
      DeflectionWorkspace<float> ws;
      const JointVector<float> q = random_joints(r, m, 3.0f);
      joint_trig(chain, q, ws.trig);
      forward_kinematics(chain, q, ws.trig, ws.frames);
      gravity_forces(chain, ws.frames, masses, ws.forces);
      d.add_case(true);
      d.add(ws.forces);
    }
  }
  {
    Digest d("coupled_values+invert_coupling+readings_from_coupled");
    FloatSource r(91);
    for (int i = 0; i < kCases; ++i) {
      const int n = 1 + r.index(kMaxJoints);
      const JointMap<float> map = random_map(r, n, 0.0f);
      JointVector<float> readings = JointVector<float>::Zero(), coupled, back;
      for (int k = 0; k < n; ++k) readings(k) = r.uniform(-3.0f, 3.0f);
      CouplingMatrix<float> scratch, inverse;
      const bool ok = invert_coupling(map, scratch, inverse);
      coupled_values(map, readings, coupled);
      readings_from_coupled(map, inverse, coupled, back);
      d.add_case(ok);
      d.add(coupled);
      if (ok) {
        d.add(inverse);
        d.add(back);
      }
    }
  }
  {
    Digest d("deflect+undeflect");
    FloatSource r(92);
    for (int i = 0; i < kCases; ++i) {
      const ChainModel<float> m = random_chain(r, 1 + r.index(kMaxJoints));
      const MassModel<float> masses = random_masses(r);
      const JointMap<float> map = random_map(r, m.joint_count, 3e-5f);
      PreparedChain<float> chain;
      prepare_chain(m, chain);
      DeflectionWorkspace<float> ws;
      JointVector<float> v, w;
      deflect(chain, masses, map.compliance, random_joints(r, m, 3.0f), ws, v);
      w = v;
      undeflect(chain, masses, map.compliance, v, 1 + r.index(2), ws, w);
      d.add_case(true);
      d.add(v);
      d.add(w);
    }
  }
  {
    Digest prepare("prepare_joint_map");
    Digest correct("correct_joint_readings");
    FloatSource r(93);
    kincal::test::RandomSource signs(94);
    static CorrectionModel model;
    static CorrectionWorkspace workspace;
    static JointMapModel map_model;
    const ChainModel<float> arm = kincal::test::to_float(kincal::test::puma_like_arm());
    for (int i = 0; i < kCases; ++i) {
      const bool puma = r.index(2) == 0;
      const ChainModel<float> nominal = puma ? arm : random_chain(r, 1 + r.index(kMaxJoints));
      const ParameterSet set = full_parameter_set(nominal, true, true);
      CorrectionOptions options;
      options.max_joint_step = 0.5f;
      if (prepare_correction(nominal, set, sign_errors(signs, set, 0.0087, 0.001), options, model) !=
          CorrectionStatus::ok)
        continue;
      const MassModel<float> masses = random_masses(r);
      const JointMap<float> nominal_map = random_map(r, nominal.joint_count, r.index(2) == 0 ? 0.0f : 1e-5f);
      JointMap<float> identified_map = nominal_map;
      for (int k = 0; k < nominal.joint_count; ++k) {
        identified_map.scale(k) = nominal_map.scale(k) + r.uniform(-5e-4f, 5e-4f);
        identified_map.compliance(k) = nominal_map.compliance(k) + r.uniform(0.0f, 3e-5f);
      }
      const CorrectionStatus prepared =
          prepare_joint_map(model, nominal_map, identified_map, masses, workspace, map_model);
      prepare.add_call(prepared, CorrectionStatus::ok, map_model.inverse_coupling);
      if (prepared != CorrectionStatus::ok) continue;
      Correction correction;
      correction.pose_error.setZero();
      correction.corrected_joint_target.setZero();
      JointVector<float> corrected = JointVector<float>::Zero();
      const CorrectionStatus status =
          correct_joint_readings(model, map_model, workspace, random_joints(r, nominal, 2.5f), correction, corrected);
      correct.add_call(status, CorrectionStatus::ok, correction.base_T_target, correction.corrected_joint_target,
                       corrected);
    }
  }
}

// Issue #13: the camera-first planar pose, its prior's covariance and the fiducial bias.
void digest_planar_pose() {
  Digest pose_digest("planar_pose");
  Digest covariance_digest("range_plane_covariance");
  Digest bias_digest("fiducial_centroid_bias_px");
  FloatSource r(130);
  RangePlaneModel plane_model;
  if (prepare_range_plane(plus_pattern_layout(0.1f, RangeModel::along_beam), plane_model) != PlaneStatus::ok) return;
  PlanarPoseWorkspace workspace;
  for (int i = 0; i < kCases; ++i) {
    CameraIntrinsics camera;
    camera.fx_px = r.uniform(500.0f, 700.0f);
    camera.fy_px = camera.fx_px;
    camera.cx_px = r.uniform(300.0f, 340.0f);
    camera.cy_px = r.uniform(220.0f, 260.0f);
    camera.distortion = {r.uniform(-0.1f, 0.0f), r.uniform(0.0f, 0.02f), 0.0f, 0.0f, 0.0f};
    // The target facing the camera (its z toward it: columns 1 and 2 negated), tilted.
    RigidTransform<float> camera_T_target;
    camera_T_target.rotation = r.rotation(0.3f);
    camera_T_target.rotation.col(1) = -camera_T_target.rotation.col(1);
    camera_T_target.rotation.col(2) = -camera_T_target.rotation.col(2);
    camera_T_target.translation = {r.uniform(-0.03f, 0.03f), r.uniform(-0.03f, 0.03f), r.uniform(0.15f, 0.5f)};
    const int n = 3 + r.index(8);
    std::array<PlanarCorrespondence, 10> points{};
    const bool collinear = r.index(16) == 0;
    for (std::size_t k = 0; k < static_cast<std::size_t>(n); ++k) {
      points[k].target_m = {r.uniform(-0.05f, 0.05f), collinear ? 0.0f : r.uniform(-0.05f, 0.05f)};
      points[k].fiducial_half_size_m = {0.003175f, r.index(6) == 0 ? 0.00635f : 0.003175f};
      const Vector3<float> p = camera_T_target * Vector3<float>{points[k].target_m.x(), points[k].target_m.y(), 0.0f};
      Vector2<float> pixel(0.0f, 0.0f);
      (void)project_point(camera, p, pixel);
      points[k].pixel_px = {pixel.x() + r.uniform(-0.2f, 0.2f), pixel.y() + r.uniform(-0.2f, 0.2f)};
    }
    // The ranger plane: the target's plane, tilted a little, with the rangers' covariance.
    PlanePrior prior;
    prior.plane.normal = -camera_T_target.rotation.col(2);
    prior.plane.normal.x() += r.uniform(-0.01f, 0.01f);
    const float n2 = prior.plane.normal.x() * prior.plane.normal.x() + prior.plane.normal.y() * prior.plane.normal.y() +
                     prior.plane.normal.z() * prior.plane.normal.z();
    prior.plane.normal = prior.plane.normal / std::sqrt(n2);
    prior.plane.distance_m = prior.plane.normal.x() * camera_T_target.translation.x() +
                             prior.plane.normal.y() * camera_T_target.translation.y() +
                             prior.plane.normal.z() * camera_T_target.translation.z();
    prior.plane.sensors_used = r.index(4) == 0 ? 0x7 : 0xF;
    const PlaneStatus covariance_status =
        range_plane_covariance(plane_model, prior.plane, r.uniform(0.0002f, 0.001f), prior.covariance);
    covariance_digest.add_call(covariance_status, PlaneStatus::ok, prior.covariance);

    PlanarPoseOptions options;
    options.pixel_sigma_px = r.uniform(0.05f, 0.2f);
    options.perspective_passes = static_cast<std::uint8_t>(r.index(2));
    const bool with_prior = n == 3 || r.index(2) == 0;
    PlanarPose pose;
    const PlanarPoseStatus status = planar_pose(camera, std::span(points).first(static_cast<std::size_t>(n)),
                                                with_prior ? &prior : nullptr, options, workspace, pose);
    pose_digest.add_call(status, PlanarPoseStatus::ok, pose.camera_T_target, pose.covariance, pose.reprojection_rms_px,
                         pose.prior_mahalanobis, pose.prior_innovation_chi2, static_cast<int>(pose.iterations),
                         static_cast<int>(pose.prior_used), static_cast<int>(pose.prior_rejected));

    Vector2<float> bias(0.0f, 0.0f);
    const bool bias_ok =
        fiducial_centroid_bias_px(camera, camera_T_target, points[0].target_m, points[0].fiducial_half_size_m, bias);
    bias_digest.add_case(bias_ok);
    bias_digest.add(bias);
  }
}

}  // namespace

int main() {
  digest_trigonometry();
  digest_kinematics();
  digest_range_plane();
  digest_camera();
  digest_pose();
  digest_stereo();
  digest_correction();
  digest_joint_map();
  digest_planar_pose();
  return 0;
}

// Instructions per call of the geometry entry points of issue #4 on the Cortex-M4 (QEMU,
// -icount shift=0): the online correction of a 6-joint arm, the camera pose from five fiducials,
// triangulation, and the smaller pieces they are built of. Inputs are prepared before the timed
// loops and vary from call to call; the loop's own cost is measured and subtracted.
#include <array>
#include <cstdint>
#include <cstdio>

#include "firmware/core/camera_model.hpp"
#include "firmware/core/correction.hpp"
#include "firmware/core/planar_pose.hpp"
#include "firmware/core/pose_from_points.hpp"
#include "firmware/core/range_plane.hpp"
#include "firmware/core/stereo.hpp"
#include "tests/bench/m4_instruction_counter.hpp"
#include "tests/firmware/core/chain_fixtures.hpp"

using namespace kincal::core;

namespace {

constexpr int kCalls = 256;
constexpr int kVariants = 16;

template <class T>
void keep(T& value) {
  __asm volatile("" : : "r"(&value) : "memory");
}

// Deterministic pseudo-random floats in [-1, 1) (no double arithmetic on the M4's soft path).
class Lcg {
 public:
  float next() {
    state_ = state_ * 1664525u + 1013904223u;
    return static_cast<float>(static_cast<std::int32_t>(state_ >> 8) - (1 << 23)) / static_cast<float>(1 << 23);
  }

 private:
  std::uint32_t state_ = 12345u;
};

template <class Call>
double instructions_per_call(kincal::bench::M4InstructionCounter& counter, Call call) {
  counter.start();
  for (int i = 0; i < kCalls; ++i) call(i % kVariants);
  return static_cast<double>(counter.stop_instructions()) / kCalls;
}

// The PUMA-like arm of tests/firmware/core/chain_fixtures.hpp, in float.
ChainModel<float> puma_like_arm() {
  ChainModel<float> m;
  m.joint_count = 6;
  const float half_pi = 1.57079633f;
  const float d[6] = {0.0f, 0.1501f, 0.0f, 0.4318f, 0.0f, 0.0563f};
  const float a[6] = {0.0f, 0.4318f, 0.0203f, 0.0f, 0.0f, 0.0f};
  const float alpha[6] = {half_pi, 0.0f, -half_pi, half_pi, -half_pi, 0.0f};
  for (std::size_t i = 0; i < 6; ++i) {
    m.links[i].convention = LinkConvention::doty;
    m.links[i].parameters = {d[i], 0.0f, a[i], alpha[i], 0.0f};
  }
  m.base_T_frame0.translation = Vector3<float>(0.0f, 0.0f, 0.6604f);
  m.flange_T_tool.translation = Vector3<float>(0.0f, 0.0f, 0.1f);
  return m;
}

Matrix3<float> rotation(float x, float y, float z) {
  return (Eigen::AngleAxisf(x, Vector3<float>::UnitX()) * Eigen::AngleAxisf(y, Vector3<float>::UnitY()) *
          Eigen::AngleAxisf(z, Vector3<float>::UnitZ()))
      .toRotationMatrix();
}

// In static storage, as on the platform: model and workspace are kilobytes, not stack.
CorrectionModel g_model;
CorrectionWorkspace g_workspace;
JointMapModel g_joint_map;

}  // namespace

int main() {
  kincal::bench::M4InstructionCounter counter;
  Lcg random;
  int failures = 0;
  const double loop = instructions_per_call(counter, [](int) {});

  // --- Correction: 6-joint arm, all 42 parameters off by 0.5 degree / 1 mm. ---
  const ChainModel<float> arm = puma_like_arm();
  const ParameterSet set = full_parameter_set(arm, true, true);
  ErrorVector<float> errors = ErrorVector<float>::Zero();
  for (int i = 0; i < set.count; ++i) {
    const ParameterKind k = set.ids[static_cast<std::size_t>(i)].kind;
    const bool length = k == ParameterKind::link_d || k == ParameterKind::link_a ||
                        (k >= ParameterKind::base_x && k <= ParameterKind::base_z) ||
                        (k >= ParameterKind::tool_x && k <= ParameterKind::tool_z);
    errors(i) = (random.next() < 0.0f ? -1.0f : 1.0f) * (length ? 0.001f : 0.0087266f);
  }
  // Targets away from singularities: random ones the correction accepts (near the PUMA's elbow,
  // wrist and shoulder singularities the step exceeds max_joint_step and is refused).
  CorrectionOptions accept_options;
  accept_options.max_joint_step = 0.1f;
  if (prepare_correction(arm, set, errors, accept_options, g_model) != CorrectionStatus::ok) return 1;
  std::array<JointVector<float>, kVariants> targets;
  for (auto& q : targets) {
    Correction probe;
    do {
      q = JointVector<float>::Zero();
      for (int i = 0; i < 6; ++i) q(i) = 2.0f * random.next();
    } while (correct_joint_target(g_model, g_workspace, q, probe) != CorrectionStatus::ok);
  }
  Correction correction;
  for (const int refinement : {1, 0}) {
    CorrectionOptions options;
    options.refinement_steps = refinement;
    options.max_joint_step = 0.5f;
    if (prepare_correction(arm, set, errors, options, g_model) != CorrectionStatus::ok) return 1;
    int refused = 0;
    const double instructions = instructions_per_call(counter, [&](int k) {
      refused += correct_joint_target(g_model, g_workspace, targets[static_cast<std::size_t>(k)], correction) !=
                 CorrectionStatus::ok;
      keep(correction);
    });
    failures += refused;
    if (refused != 0) std::printf("correction: %d refused\n", refused);
    std::printf("FIGURE correction%s_m4_instructions %.0f instructions\n", refinement == 0 ? "_first_order_step" : "",
                instructions - loop);
  }

  // --- The same correction through a joint map (issue #12): the controller reads the elbow
  // relative to the shoulder (chain joint 3 = reading 2 + reading 3), every gear is off by up to
  // 300 ppm, the identified shoulder and elbow sag under gravity (PUMA masses, 3 kg payload). ---
  {
    CorrectionOptions options;
    options.max_joint_step = 0.5f;
    if (prepare_correction(arm, set, errors, options, g_model) != CorrectionStatus::ok) return 1;
    JointMap<float> nominal_map;
    nominal_map.joint_count = 6;
    nominal_map.coupling(2, 1) = 1.0f;
    JointMap<float> identified_map = nominal_map;
    for (int i = 0; i < 6; ++i) identified_map.scale(i) = 1.0f + 3.0e-4f * random.next();
    identified_map.compliance(1) = 2.0e-5f;
    identified_map.compliance(2) = 3.0e-5f;
    const MassModel<float> masses = kincal::test::puma_like_masses<float>();
    if (prepare_joint_map(g_model, nominal_map, identified_map, masses, g_workspace, g_joint_map) !=
        CorrectionStatus::ok)
      return 1;
    std::array<JointVector<float>, kVariants> readings;
    for (std::size_t k = 0; k < readings.size(); ++k) {
      readings[k] = targets[k];
      readings[k](2) = targets[k](2) - targets[k](1);  // the same chain postures as above
    }
    JointVector<float> corrected = JointVector<float>::Zero();
    int refused = 0;
    const double instructions = instructions_per_call(counter, [&](int k) {
      refused += correct_joint_readings(g_model, g_joint_map, g_workspace, readings[static_cast<std::size_t>(k)],
                                        correction, corrected) != CorrectionStatus::ok;
      keep(corrected);
    });
    failures += refused;
    if (refused != 0) std::printf("correction with the joint map: %d refused\n", refused);
    std::printf("FIGURE correction_joint_map_m4_instructions %.0f instructions\n", instructions - loop);
  }

  // Forward kinematics alone (6 joints, prepared chain, frames kept).
  {
    JointTrig trig;
    ChainFrames<float> frames;
    const double instructions = instructions_per_call(counter, [&](int k) {
      const JointVector<float>& q = targets[static_cast<std::size_t>(k)];
      joint_trig(g_model.calibrated, q, trig);
      forward_kinematics(g_model.calibrated, q, trig, frames);
      keep(frames);
    });
    std::printf("FIGURE forward_kinematics_6_joints_m4_instructions %.0f instructions\n", instructions - loop);
  }
  {
    std::array<float, kVariants> angles;
    for (float& a : angles) a = 3.0f * random.next();
    SinCos<float> sc{};
    const double instructions = instructions_per_call(counter, [&](int k) {
      sc = sin_cos(angles[static_cast<std::size_t>(k)]);
      keep(sc);
    });
    std::printf("FIGURE sin_cos_m4_instructions %.0f instructions\n", instructions - loop);
  }

  // --- Camera pose from Doty's five fiducials (4-inch square, 0.5 mm of noise). ---
  {
    const float a = 0.04445f;
    const std::array<Vector3<float>, 5> square = {Vector3<float>(0, 0, 0), Vector3<float>(a, 0, 0),
                                                  Vector3<float>(0, a, 0), Vector3<float>(-a, 0, 0),
                                                  Vector3<float>(0, -a, 0)};
    std::array<std::array<Vector3<float>, 5>, kVariants> measured;
    for (auto& points : measured) {
      const Matrix3<float> r = rotation(0.4f * random.next(), 0.4f * random.next(), 3.0f * random.next());
      const Vector3<float> t(0.1f * random.next(), 0.1f * random.next(), 0.6f + 0.3f * random.next());
      for (std::size_t i = 0; i < 5; ++i)
        points[i] = r * square[i] + t + 0.0005f * Vector3<float>(random.next(), random.next(), random.next());
    }
    PoseFit fit;
    int refused = 0;
    const double instructions = instructions_per_call(counter, [&](int k) {
      refused += pose_from_points(square, measured[static_cast<std::size_t>(k)], PoseOptions{}, fit) != PoseStatus::ok;
      keep(fit);
    });
    failures += refused;
    if (refused != 0) std::printf("pose: %d refused\n", refused);
    std::printf("FIGURE pose_from_points_m4_instructions %.0f instructions\n", instructions - loop);
  }

  // --- Plane from the four rangers, and a fiducial pixel to its point on it. ---
  {
    RangePlaneModel plane_model;
    if (prepare_range_plane(plus_pattern_layout(0.1f, RangeModel::along_beam), plane_model) != PlaneStatus::ok)
      return 1;
    std::array<std::array<float, 4>, kVariants> ranges;
    for (auto& r : ranges) {
      const float base = 0.5f + 0.2f * random.next(), tilt_x = 0.02f * random.next(), tilt_y = 0.02f * random.next();
      r = {base + tilt_x, base + tilt_y, base - tilt_x, base - tilt_y};
    }
    CalibrationPlane plane;
    int refused = 0;
    double instructions = instructions_per_call(counter, [&](int k) {
      refused += fit_range_plane(plane_model, ranges[static_cast<std::size_t>(k)], plane) != PlaneStatus::ok;
      keep(plane);
    });
    std::printf("FIGURE fit_range_plane_m4_instructions %.0f instructions\n", instructions - loop);

    CameraIntrinsics camera;
    camera.fx_px = 612.3f;
    camera.fy_px = 611.8f;
    camera.cx_px = 319.6f;
    camera.cy_px = 241.2f;
    camera.distortion = {-0.412f, 0.215f, 0.0011f, -0.0007f, -0.061f};
    std::array<Vector2<float>, kVariants> pixels;
    for (auto& p : pixels) p = Vector2<float>(320.0f + 300.0f * random.next(), 240.0f + 220.0f * random.next());
    Vector3<float> point;
    instructions = instructions_per_call(counter, [&](int k) {
      refused += pixel_to_plane_point(camera, plane, pixels[static_cast<std::size_t>(k)], point) != CameraStatus::ok;
      keep(point);
    });
    failures += refused;
    if (refused != 0) std::printf("plane: %d refused\n", refused);
    std::printf("FIGURE pixel_to_plane_point_m4_instructions %.0f instructions\n", instructions - loop);
  }

  // --- Triangulation: Kapucu & Baysec's parallel rig, and a converging pair with distortion. ---
  {
    ParallelStereoRig rig;
    rig.focal_x_px = 909.09f;
    rig.focal_y_px = 769.23f;
    rig.baseline_m = 0.126f;
    rig.principal_left_px = rig.principal_right_px = Vector2<float>(319.5f, 239.5f);
    StereoPair pair;
    pair.left.fx_px = pair.right.fx_px = 909.09f;
    pair.left.fy_px = pair.right.fy_px = 769.23f;
    pair.left.cx_px = pair.right.cx_px = 319.5f;
    pair.left.cy_px = pair.right.cy_px = 239.5f;
    pair.left.distortion = pair.right.distortion = {-0.12f, 0.05f, 0.0005f, -0.0003f, 0.0f};
    pair.left_T_right.rotation = rotation(0.0f, -0.05f, 0.0f);
    pair.left_T_right.translation = Vector3<float>(0.126f, 0.0f, 0.0f);
    std::array<Vector3<float>, kVariants> points;
    std::array<Vector2<float>, kVariants> left_parallel, right_parallel, left_pair, right_pair;
    int refused = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Vector3<float> p(0.5f * random.next(), 0.3f * random.next(), 3.0f + 1.5f * random.next());
      left_parallel[i] = Vector2<float>(909.09f * p.x() / p.z() + 319.5f, 769.23f * p.y() / p.z() + 239.5f);
      right_parallel[i] = Vector2<float>(909.09f * (p.x() - 0.126f) / p.z() + 319.5f, left_parallel[i].y());
      refused += project_point(pair.left, p, left_pair[i]) != CameraStatus::ok;
      refused += project_point(pair.right, pair.left_T_right.inverse() * p, right_pair[i]) != CameraStatus::ok;
    }
    StereoPoint point;
    double instructions = instructions_per_call(counter, [&](int k) {
      const auto i = static_cast<std::size_t>(k);
      refused += triangulate_parallel(rig, left_parallel[i], right_parallel[i], 0.3f, point) != StereoStatus::ok;
      keep(point);
    });
    std::printf("FIGURE triangulate_parallel_m4_instructions %.0f instructions\n", instructions - loop);
    instructions = instructions_per_call(counter, [&](int k) {
      const auto i = static_cast<std::size_t>(k);
      refused += triangulate_pair(pair, left_pair[i], right_pair[i], 0.3f, point) != StereoStatus::ok;
      keep(point);
    });
    failures += refused;
    if (refused != 0) std::printf("stereo: %d refused\n", refused);
    std::printf("FIGURE triangulate_pair_m4_instructions %.0f instructions\n", instructions - loop);
  }
  // --- Issue #13: the camera-first pose, six fiducials of a square, with the ranger plane as the
  // prior, default options (one perspective pass) and without that pass. ---
  {
    CameraIntrinsics camera;
    camera.fx_px = 600.0f;
    camera.fy_px = 600.0f;
    camera.cx_px = 319.5f;
    camera.cy_px = 239.5f;
    camera.distortion = {-0.05f, 0.01f, 0.0f, 0.0f, 0.0f};
    const float s = 0.00635f, h = 0.5f * s;
    const std::array<Vector2<float>, 6> centres = {Vector2<float>(-7 * s, 7 * s), Vector2<float>(0, 7 * s),
                                                   Vector2<float>(-7 * s, 0),     Vector2<float>(0, 0),
                                                   Vector2<float>(7 * s, 0),      Vector2<float>(0, -7 * s)};
    RangePlaneModel plane_model;
    if (prepare_range_plane(plus_pattern_layout(0.1f, RangeModel::along_beam), plane_model) != PlaneStatus::ok)
      return 1;
    std::array<std::array<PlanarCorrespondence, 6>, kVariants> views;
    std::array<PlanePrior, kVariants> priors;
    for (std::size_t v = 0; v < kVariants; ++v) {
      RigidTransform<float> camera_T_square;
      camera_T_square.rotation = rotation(0.4f * random.next(), 0.4f * random.next(), 0.3f * random.next());
      camera_T_square.rotation.col(1) = -camera_T_square.rotation.col(1);  // the square faces the camera
      camera_T_square.rotation.col(2) = -camera_T_square.rotation.col(2);
      camera_T_square.translation =
          Vector3<float>(0.02f * random.next(), 0.02f * random.next(), 0.3f + 0.1f * random.next());
      for (std::size_t i = 0; i < 6; ++i) {
        PlanarCorrespondence& c = views[v][i];
        c.target_m = centres[i];
        c.fiducial_half_size_m = Vector2<float>(h, i == 3 ? s : h);
        Vector2<float> pixel;
        if (project_point(camera, camera_T_square * Vector3<float>(centres[i].x(), centres[i].y(), 0.0f), pixel) !=
            CameraStatus::ok)
          return 1;
        c.pixel_px = pixel + 0.07f * Vector2<float>(random.next(), random.next());
      }
      priors[v].plane.normal = -camera_T_square.rotation.col(2);
      priors[v].plane.distance_m = priors[v].plane.normal.dot(camera_T_square.translation);
      priors[v].plane.sensors_used = 0xF;
      if (range_plane_covariance(plane_model, priors[v].plane, 0.0005f, priors[v].covariance) != PlaneStatus::ok)
        return 1;
    }
    static PlanarPoseWorkspace workspace;
    PlanarPose pose;
    int refused = 0, iterations = 0;
    for (const int passes : {1, 0}) {
      PlanarPoseOptions options;
      options.pixel_sigma_px = 0.07f;
      options.perspective_passes = static_cast<std::uint8_t>(passes);
      iterations = 0;
      const double instructions = instructions_per_call(counter, [&](int k) {
        const auto i = static_cast<std::size_t>(k);
        refused += planar_pose(camera, views[i], &priors[i], options, workspace, pose) != PlanarPoseStatus::ok;
        iterations += pose.iterations;
        keep(pose);
      });
      std::printf("planar_pose, %d perspective pass(es): %.1f Gauss-Newton steps per call\n", passes,
                  static_cast<double>(iterations) / kCalls);
      std::printf("FIGURE planar_pose%s_m4_instructions %.0f instructions\n", passes == 0 ? "_no_bias_pass" : "",
                  instructions - loop);
    }
    failures += refused;
    if (refused != 0) std::printf("planar_pose: %d refused\n", refused);
  }
  if (failures != 0) std::printf("geometry_m4_bench: %d calls did not succeed\n", failures);
  return failures == 0 ? 0 : 1;
}

// The ARID platform's pose on the simulated rig (issue #13): today's ranger-plane pose against the
// camera-first pose fused with the ranger plane (core::planar_pose), in the same run, against the
// known true pose.
//
// Each view: Doty's strip (host/sim/strip.hpp, 16 four-inch squares) rendered by host/sim/render.hpp
// with the ARID camera (640x480, f = 600 px, k1 = -0.05, k2 = 0.01, as host/demo/simulated_rig.cpp)
// and the default imaging conditions, from 0.2-0.45 m, tilted up to 25 degrees about random axes,
// turned up to 20 degrees about the optical axis; the four rangers (host/sim/rangers.hpp: + of
// 10 cm, 0.5 mm noise). Then, as the platform does: the core labeler (fixed threshold) and Doty's
// FID on the blobs; FID again on the blobs left, for up to four squares; each square's identity in
// the strip from the truth (the host's job), its fiducials checked against the truth (a misidentified
// square is dropped and counted).
//   ranger plane   the first square's fiducials through pixel_to_plane_point on the ranger plane,
//                  pose_from_points (firmware/app's method before #13)
//   camera-first   planar_pose with the ranger plane as prior (range_plane_covariance), one square
//                  or every identified square (target = strip frame), with and without the
//                  perspective pass
// Error: the camera's pose in the first square's frame (square_T_camera, what the platform reports)
// against the truth: position (mm) and rotation angle (mrad), RMS over the views with a pose.
// Coverage: the fraction of views whose 6-D error (the estimate's own twist convention) lies in the
// 95% ellipsoid of the reported covariance (chi^2 6 dof <= 12.59). Also counted: views whose first
// square has only three fiducials (the prior then fixes what they cannot), and such squares in all.
#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <random>
#include <vector>

#include "firmware/core/blob_labeler.hpp"
#include "firmware/core/camera_model.hpp"
#include "firmware/core/fiducial_id.hpp"
#include "firmware/core/planar_pose.hpp"
#include "firmware/core/pose_from_points.hpp"
#include "firmware/core/range_plane.hpp"
#include "host/sim/rangers.hpp"
#include "host/sim/render.hpp"
#include "host/sim/strip.hpp"

using namespace kincal;

namespace {

constexpr int kViews = 200;
constexpr int kMaxSquares = 4;
constexpr float kPixelSigmaPx = 0.07f;  // the fiducial centroid noise of issue #13

struct Accumulator {
  double sum2_mm = 0, sum2_mrad = 0;
  int count = 0, inside95 = 0, failed = 0;
  void add(const Eigen::Isometry3d& square_T_camera_est, const Eigen::Isometry3d& square_T_camera_true) {
    sum2_mm += 1e6 * (square_T_camera_est.translation() - square_T_camera_true.translation()).squaredNorm();
    const double angle =
        Eigen::AngleAxisd(square_T_camera_est.linear() * square_T_camera_true.linear().transpose()).angle();
    sum2_mrad += 1e6 * angle * angle;
    ++count;
  }
  double rms_mm() const { return std::sqrt(sum2_mm / count); }
  double rms_mrad() const { return std::sqrt(sum2_mrad / count); }
};

Eigen::Isometry3d to_isometry(const core::RigidTransform<float>& t) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = t.rotation.cast<double>();
  out.translation() = t.translation.cast<double>();
  return out;
}

// Whether the error of camera_T_target lies in the 95% ellipsoid of the covariance of the twist
// [dt; dphi] (camera frame; R_true = exp([dphi]x) R_est, t_true = t_est + dt).
bool inside_95(const core::PlanarPose& pose, const Eigen::Isometry3d& camera_T_target_true) {
  const Eigen::Isometry3d est = to_isometry(pose.camera_T_target);
  Eigen::Matrix<double, 6, 1> e;
  e.head<3>() = camera_T_target_true.translation() - est.translation();
  const Eigen::AngleAxisd d(camera_T_target_true.linear() * est.linear().transpose());
  e.tail<3>() = d.angle() * d.axis();
  const Eigen::Matrix<double, 6, 6> c = pose.covariance.cast<double>();
  return e.dot(c.ldlt().solve(e)) <= 12.59;
}

}  // namespace

int main() {
  const sim::StripSpec strip{16};
  const sim::PlanarTarget target = sim::strip_target(strip);
  const auto fiducials = sim::square_fiducials(strip);
  sim::CameraSpec camera_spec;
  camera_spec.distortion = {-0.05, 0.01, 0, 0, 0};
  core::CameraIntrinsics camera;
  camera.fx_px = static_cast<float>(camera_spec.fx_px);
  camera.fy_px = static_cast<float>(camera_spec.fy_px);
  camera.cx_px = static_cast<float>(camera_spec.cx_px);
  camera.cy_px = static_cast<float>(camera_spec.cy_px);
  camera.distortion = {-0.05f, 0.01f, 0.0f, 0.0f, 0.0f};
  const sim::RangerSpec rangers;
  core::RangePlaneModel plane_model;
  core::RangeSensorLayout layout =
      core::plus_pattern_layout(static_cast<float>(rangers.spacing_m), core::RangeModel::along_beam);
  layout.origin_z_m = static_cast<float>(rangers.origin_z_m);
  if (core::prepare_range_plane(layout, plane_model) != core::PlaneStatus::ok) return 1;

  auto buffers = std::make_unique<core::VgaLabelerBuffers>();
  std::vector<core::Blob> blobs(256), remaining(256);
  std::vector<core::FidVerdict> verdicts(256);
  auto workspace = std::make_unique<core::PlanarPoseWorkspace>();

  std::mt19937_64 rng(1313);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Accumulator ranger_plane, one_square, one_square_no_bias, all_squares, all_squares_no_bias;
  int views_with_pose = 0, three_fiducial_views = 0, three_fiducial_squares = 0, misidentified = 0, squares_used = 0,
      prior_rejected = 0;
  double worst_bias_px = 0;
  for (int view = 0; view < kViews; ++view) {
    // The camera looks at a strip point from 0.2-0.45 m, tilted and turned.
    const double along = strip.square_m * (1.5 + (strip.squares - 3) * unit(rng));
    const Eigen::Vector3d strip_point(along, 0.03 * (unit(rng) - 0.5), 0);
    const double distance = 0.2 + 0.25 * unit(rng);
    const double tilt = 25.0 * std::numbers::pi / 180 * std::sqrt(unit(rng)),
                 azimuth = 2 * std::numbers::pi * unit(rng);
    Eigen::Isometry3d camera_T_strip =
        sim::facing_camera({0.02 * (unit(rng) - 0.5), 0.02 * (unit(rng) - 0.5), distance}, tilt * std::cos(azimuth),
                           tilt * std::sin(azimuth), strip_point);
    camera_T_strip.prerotate(
        Eigen::AngleAxisd(20.0 * std::numbers::pi / 180 * (2 * unit(rng) - 1), Eigen::Vector3d::UnitZ()));

    sim::ImagingConditions conditions;
    conditions.seed = 1000u + static_cast<std::uint64_t>(view);
    const cv::Mat image = sim::render_plane(camera_spec, camera_T_strip, target, conditions);
    const std::array<double, 4> ranges = sim::simulate_ranges(rangers, camera_T_strip, rng);

    core::BlobLabeler labeler(buffers->memory());
    core::LabelerConfig config;
    config.polarity = core::Polarity::kDark;
    config.threshold = 100;
    config.min_area_px = 4;
    core::FrameSummary summary;
    bool ok = labeler.begin_frame(config, blobs) == core::LabelStatus::kOk;
    for (int y = 0; y < image.rows && ok; ++y)
      ok = labeler.push_row({image.ptr<std::uint8_t>(y), static_cast<std::size_t>(image.cols)}) ==
           core::LabelStatus::kOk;
    ok = ok && labeler.end_frame(summary) == core::LabelStatus::kOk;
    std::array<float, 4> range_m{};
    for (int i = 0; i < 4; ++i)
      range_m[static_cast<std::size_t>(i)] = static_cast<float>(ranges[static_cast<std::size_t>(i)]);
    core::CalibrationPlane plane;
    core::PlanePrior prior;
    if (!ok || core::fit_range_plane(plane_model, range_m, plane) != core::PlaneStatus::ok ||
        core::range_plane_covariance(plane_model, plane, static_cast<float>(rangers.sigma_m), prior.covariance) !=
            core::PlaneStatus::ok) {
      continue;
    }
    prior.plane = plane;

    // Up to four squares: FID, then FID again on the blobs it did not use.
    std::size_t blob_count = summary.blobs;
    remaining.assign(blobs.begin(), blobs.begin() + static_cast<std::ptrdiff_t>(blob_count));
    struct Found {
      int index;
      core::FidResult fid;
    };
    std::vector<Found> found;
    for (int k = 0; k < kMaxSquares && blob_count > 0; ++k) {
      core::FidResult fid;
      if (core::identify_fiducials(core::FidModel{}, std::span<const core::Blob>(remaining.data(), blob_count),
                                   verdicts, fid) != core::FidStatus::kOk) {
        break;
      }
      // Which square: the one whose centre fiducial projects nearest the FID's p4 (or first point).
      const Eigen::Vector2d seen(fid.fiducials[0].x_px.to_double(), fid.fiducials[0].y_px.to_double());
      int best = -1;
      double best_d = 1e9;
      for (int s = 0; s < strip.squares; ++s) {
        const auto& f = fiducials[static_cast<std::size_t>(fid.fiducials[0].id - 1)];
        const Eigen::Vector3d p = sim::strip_T_square(strip, s) * Eigen::Vector3d(f.centre_m.x(), f.centre_m.y(), 0);
        const auto px = sim::project_points(camera_spec, camera_T_strip, std::span<const Eigen::Vector3d>(&p, 1));
        const double d = std::hypot(px[0].x - seen.x(), px[0].y - seen.y());
        if (d < best_d) {
          best_d = d;
          best = s;
        }
      }
      bool right = best >= 0 && best_d < 3.0;
      for (int i = 0; i < fid.count && right; ++i) {
        const auto& f = fiducials[static_cast<std::size_t>(fid.fiducials[static_cast<std::size_t>(i)].id - 1)];
        const Eigen::Vector3d p = sim::strip_T_square(strip, best) * Eigen::Vector3d(f.centre_m.x(), f.centre_m.y(), 0);
        const auto px = sim::project_points(camera_spec, camera_T_strip, std::span<const Eigen::Vector3d>(&p, 1));
        right = std::hypot(px[0].x - fid.fiducials[static_cast<std::size_t>(i)].x_px.to_double(),
                           px[0].y - fid.fiducials[static_cast<std::size_t>(i)].y_px.to_double()) < 3.0;
      }
      for (const Found& g : found) right = right && g.index != best;
      if (right) {
        found.push_back({best, fid});
      } else {
        ++misidentified;
      }
      // Drop the blobs this FID used, keep the rest in order.
      std::vector<bool> used(blob_count, false);
      for (int i = 0; i < fid.count; ++i) used[fid.fiducials[static_cast<std::size_t>(i)].blob_index] = true;
      std::size_t kept = 0;
      for (std::size_t b = 0; b < blob_count; ++b)
        if (!used[b]) remaining[kept++] = remaining[b];
      blob_count = kept;
    }
    if (found.empty()) continue;
    ++views_with_pose;
    squares_used += static_cast<int>(found.size());
    const Eigen::Isometry3d strip_T_first = sim::strip_T_square(strip, found[0].index);
    const Eigen::Isometry3d square_T_camera_true = (camera_T_strip * strip_T_first).inverse();
    if (found[0].fid.count == 3) ++three_fiducial_views;
    for (const Found& f : found) three_fiducial_squares += f.fid.count == 3 ? 1 : 0;

    // (a) today's: the first square's points on the ranger plane, rigid fit.
    {
      std::vector<core::Vector3<float>> square_points, camera_points;
      for (int i = 0; i < found[0].fid.count; ++i) {
        const auto& f = found[0].fid.fiducials[static_cast<std::size_t>(i)];
        core::Vector3<float> c;
        if (core::pixel_to_plane_point(camera, plane, {f.x_px.to_float(), f.y_px.to_float()}, c) !=
            core::CameraStatus::ok)
          continue;
        const auto& s = fiducials[static_cast<std::size_t>(f.id - 1)].centre_m;
        square_points.emplace_back(static_cast<float>(s.x()), static_cast<float>(s.y()), 0.0f);
        camera_points.push_back(c);
      }
      core::PoseFit fit;
      if (square_points.size() >= 3 &&
          core::pose_from_points(square_points, camera_points, core::PoseOptions{}, fit) == core::PoseStatus::ok) {
        ranger_plane.add(to_isometry(fit.camera_T_square).inverse(), square_T_camera_true);
      } else {
        ++ranger_plane.failed;
      }
    }

    // (b) camera-first: one square (square frame) or every square (strip frame).
    for (const bool every : {false, true}) {
      std::vector<core::PlanarCorrespondence> points;
      for (std::size_t q = 0; q < (every ? found.size() : 1u); ++q) {
        const Eigen::Isometry3d first_T_square = strip_T_first.inverse() * sim::strip_T_square(strip, found[q].index);
        for (int i = 0; i < found[q].fid.count; ++i) {
          const auto& f = found[q].fid.fiducials[static_cast<std::size_t>(i)];
          const auto& rect = fiducials[static_cast<std::size_t>(f.id - 1)];
          const Eigen::Vector3d t = first_T_square * Eigen::Vector3d(rect.centre_m.x(), rect.centre_m.y(), 0);
          core::PlanarCorrespondence c;
          c.pixel_px = {f.x_px.to_float(), f.y_px.to_float()};
          c.target_m = {static_cast<float>(t.x()), static_cast<float>(t.y())};
          c.fiducial_half_size_m = (0.5 * rect.size_m).cast<float>();
          points.push_back(c);
        }
      }
      for (const int passes : {0, 1}) {
        core::PlanarPoseOptions options;
        options.pixel_sigma_px = kPixelSigmaPx;
        options.perspective_passes = static_cast<std::uint8_t>(passes);
        core::PlanarPose pose;
        Accumulator& acc =
            every ? (passes == 1 ? all_squares : all_squares_no_bias) : (passes == 1 ? one_square : one_square_no_bias);
        if (core::planar_pose(camera, points, &prior, options, *workspace, pose) != core::PlanarPoseStatus::ok) {
          ++acc.failed;
          continue;
        }
        acc.add(to_isometry(pose.camera_T_target).inverse(), square_T_camera_true);
        acc.inside95 += inside_95(pose, camera_T_strip * strip_T_first) ? 1 : 0;
        if (every && passes == 1) {
          prior_rejected += pose.prior_rejected ? 1 : 0;
          for (const auto& c : points) {
            core::Vector2<float> bias;
            if (core::fiducial_centroid_bias_px(camera, pose.camera_T_target, c.target_m, c.fiducial_half_size_m, bias))
              worst_bias_px = std::fmax(worst_bias_px, static_cast<double>(bias.norm()));
          }
        }
      }
    }
  }

  std::printf("views %d, with a pose %d, squares used %d, misidentified squares dropped %d, prior rejected %d\n",
              kViews, views_with_pose, squares_used, misidentified, prior_rejected);
  const auto report = [&ranger_plane](const char* name, const Accumulator& a) {
    std::printf("%-40s rms %.3f mm %.3f mrad over %d views (%d failed)", name, a.rms_mm(), a.rms_mrad(), a.count,
                a.failed);
    if (&a != &ranger_plane) std::printf(", 95%% coverage %.3f", static_cast<double>(a.inside95) / a.count);
    std::printf("\n");
  };
  report("ranger plane (today)", ranger_plane);
  report("camera-first, one square, no bias pass", one_square_no_bias);
  report("camera-first, one square", one_square);
  report("camera-first, every square, no bias pass", all_squares_no_bias);
  report("camera-first, every square", all_squares);
  std::printf("FIGURE platform_pose_rms_mm %.4f mm\n", all_squares.rms_mm());
  std::printf("FIGURE platform_pose_rms_mrad %.4f mrad\n", all_squares.rms_mrad());
  std::printf("FIGURE platform_pose_ranger_plane_rms_mm %.4f mm\n", ranger_plane.rms_mm());
  std::printf("FIGURE platform_pose_ranger_plane_rms_mrad %.4f mrad\n", ranger_plane.rms_mrad());
  std::printf("FIGURE platform_pose_no_bias_rms_mm %.4f mm\n", all_squares_no_bias.rms_mm());
  std::printf("FIGURE platform_pose_no_bias_rms_mrad %.4f mrad\n", all_squares_no_bias.rms_mrad());
  std::printf("FIGURE platform_pose_one_square_rms_mm %.4f mm\n", one_square.rms_mm());
  std::printf("FIGURE platform_pose_one_square_rms_mrad %.4f mrad\n", one_square.rms_mrad());
  std::printf("FIGURE platform_pose_coverage_95 %.3f fraction\n",
              static_cast<double>(all_squares.inside95) / all_squares.count);
  std::printf("FIGURE platform_pose_three_fiducial_views %d views\n", three_fiducial_views);
  std::printf("FIGURE platform_pose_three_fiducial_squares %d squares\n", three_fiducial_squares);
  std::printf("FIGURE platform_pose_max_perspective_bias_px %.3f px\n", worst_bias_px);
  return views_with_pose > kViews / 2 ? 0 : 1;
}

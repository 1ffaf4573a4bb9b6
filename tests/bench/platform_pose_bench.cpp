// The ARID platform's pose on the simulated rig (issue #13): the old ranger-plane pose against
// the platform's camera-first pose (app::MeasurementPipeline, the firmware's own measurement step
// with core::planar_pose fused with the ranger plane), on one square and on every square of the
// strip in view, in the same run, against the known true pose.
//
// Each view: Doty's strip (host/sim/strip.hpp, 16 four-inch squares) rendered by host/sim/render.hpp
// with the ARID camera (640x480, f = 600 px, k1 = -0.05, k2 = 0.01, as host/demo/simulated_rig.cpp)
// and the default imaging conditions, from 0.2-0.45 m, tilted up to 25 degrees about random axes,
// turned up to 20 degrees about the optical axis; the four rangers (host/sim/rangers.hpp: + of
// 10 cm, 0.5 mm noise). Then:
//   every square   the platform's report with the geometry block's square pitch: the reference
//                  square's FID, then every fiducial of the strip in view (core::match_strip_fiducials)
//   one square     the same frame, the block without the pitch (the reference square alone)
//   no bias pass   planar_pose on the FID's square without the perspective pass
//   ranger plane   the FID's square's fiducials through pixel_to_plane_point on the ranger plane,
//                  pose_from_points (firmware/app's method before #13)
// The reference square's identity in the strip from the truth (the host's job: its fiducials
// within 3 px of a square's projected ones). Error: the camera's pose in the reference square's
// frame (square_T_camera, what the platform reports) against the truth: position (mm) and rotation
// angle (mrad), RMS over the views with a pose. Coverage: the fraction of views whose 6-D error
// (the report's (t, delta) convention) lies in the 95% ellipsoid of the reported covariance
// (chi^2 6 dof <= 12.59). Also counted: views whose square has only three fiducials, and how many
// squares the platform's poses used.
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <random>
#include <vector>

#include "firmware/app/platform_measurement.hpp"
#include "firmware/core/blob_labeler.hpp"
#include "firmware/core/camera_model.hpp"
#include "firmware/core/fiducial_id.hpp"
#include "firmware/core/planar_pose.hpp"
#include "firmware/core/pose_from_points.hpp"
#include "firmware/core/range_plane.hpp"
#include "host/sim/parameter_blocks.hpp"
#include "host/sim/rangers.hpp"
#include "host/sim/render.hpp"
#include "host/sim/strip.hpp"

using namespace kincal;

namespace {

constexpr int kViews = 200;

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

// The report's pose: square_T_camera.
Eigen::Isometry3d reported_pose(const shared::MeasurementReport& report) {
  Eigen::Vector3d phi;
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  for (int k = 0; k < 3; ++k) {
    out.translation()(k) = report.translation_raw[static_cast<std::size_t>(k)] * shared::kTranslationLsbM;
    phi(k) = report.rotation_raw[static_cast<std::size_t>(k)] * shared::kRotationLsbRad;
  }
  if (phi.norm() > 0) out.linear() = Eigen::AngleAxisd(phi.norm(), phi.normalized()).toRotationMatrix();
  return out;
}

// Whether the report's error lies in the 95% ellipsoid of its covariance: (t, delta) with
// true square_R_camera = exp([delta]x) reported (shared/measurement_report.hpp).
bool inside_95(const shared::MeasurementReport& report, const Eigen::Isometry3d& estimate,
               const Eigen::Isometry3d& truth) {
  Eigen::Matrix<double, 6, 1> e;
  e.head<3>() = truth.translation() - estimate.translation();
  const Eigen::AngleAxisd d(truth.linear() * estimate.linear().transpose());
  e.tail<3>() = d.angle() * d.axis();
  const Eigen::Matrix<double, 6, 6, Eigen::RowMajor> c(shared::pose_covariance(report).data());
  return e.dot(c.ldlt().solve(e)) <= 12.59;
}

// One ARID measurement of a rendered frame through the platform's pipeline, as its ports would
// drive it: the frame twice (metering, then labelling), the rangers' readings in micrometres.
void measure_frame(app::MeasurementPipeline& pipeline, const app::ParameterSet& parameters, const cv::Mat& image,
                   const std::array<double, 4>& ranges_m, shared::MeasurementReport& report) {
  constexpr std::uint8_t kArid =
      shared::section::kRanges | shared::section::kPlane | shared::section::kFiducials | shared::section::kPose;
  pipeline.begin({0, kArid}, parameters);
  const auto width = static_cast<std::uint16_t>(image.cols), height = static_cast<std::uint16_t>(image.rows);
  bool labelled = false;
  if (pipeline.accept_frame_size(width, height)) {
    for (int y = 0; y < image.rows; ++y) {
      std::copy_n(image.ptr<std::uint8_t>(y), width, pipeline.row().begin());
      pipeline.meter_row();
    }
    labelled = pipeline.begin_labelling();
    for (int y = 0; y < image.rows && labelled; ++y) {
      std::copy_n(image.ptr<std::uint8_t>(y), width, pipeline.row().begin());
      labelled = pipeline.label_row();
    }
  }
  std::array<std::uint32_t, shared::kRangers> ranges_um{};
  for (std::size_t i = 0; i < shared::kRangers; ++i)
    ranges_um[i] = std::isfinite(ranges_m[i]) && ranges_m[i] >= 0 && ranges_m[i] < 1.0
                       ? static_cast<std::uint32_t>(std::lround(ranges_m[i] * 1e6))
                       : app::kNoEchoUm;
  pipeline.finish(app::CaptureStatus::kOk, labelled, app::RangerStatus::kOk, ranges_um, 0, report);
}

}  // namespace

int main() {
  const sim::StripSpec strip{16};
  const sim::PlanarTarget target = sim::strip_target(strip);
  const auto fiducials = sim::square_fiducials(strip);
  sim::CameraSpec camera_spec;
  camera_spec.distortion = {-0.05, 0.01, 0, 0, 0};
  const sim::RangerSpec rangers;
  app::ParameterSet platform_parameters;
  platform_parameters.has_intrinsics = platform_parameters.has_geometry = true;
  platform_parameters.intrinsics = sim::to_intrinsics(camera_spec);
  platform_parameters.geometry = sim::platform_geometry(strip, rangers);
  const core::CameraIntrinsics camera = core::camera_from_block(platform_parameters.intrinsics);
  core::RangePlaneModel plane_model;
  core::RangeSensorLayout layout =
      core::plus_pattern_layout(static_cast<float>(rangers.spacing_m), core::RangeModel::along_beam);
  layout.origin_z_m = static_cast<float>(rangers.origin_z_m);
  if (core::prepare_range_plane(layout, plane_model) != core::PlaneStatus::ok) return 1;

  auto buffers = std::make_unique<core::VgaLabelerBuffers>();
  std::vector<core::Blob> blobs(256);
  std::vector<core::FidVerdict> verdicts(256);
  auto workspace = std::make_unique<core::PlanarPoseWorkspace>();
  auto pipeline = std::make_unique<app::MeasurementPipeline>();

  std::mt19937_64 rng(1313);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Accumulator ranger_plane, one_square, one_square_no_bias, all_squares;
  int views_with_pose = 0, three_fiducial_views = 0, misidentified = 0;
  std::array<int, 6> squares_per_view{};  // the platform's pose_squares, 5 and more in the last
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

    // The platform's own measurement step on this frame (app::MeasurementPipeline: Otsu threshold,
    // FID, ranger plane, camera-first pose), with the strip's pitch (every square in view) and
    // without it (the reference square alone).
    const auto platform_pose = [&](float pitch_m, shared::MeasurementReport& report) {
      app::ParameterSet parameters = platform_parameters;
      parameters.geometry.square_pitch_m = pitch_m;
      measure_frame(*pipeline, parameters, image, ranges, report);
      return report.status == shared::MeasureStatus::kOk && (report.sections & shared::section::kPose) != 0;
    };
    shared::MeasurementReport strip_report, square_report;
    const bool strip_ok = platform_pose(platform_parameters.geometry.square_pitch_m, strip_report);
    const bool square_ok = platform_pose(0.0f, square_report);

    // FID on the core labeler's blobs, for the ranger-plane pose and the no-bias variant.
    core::FidResult fid;
    if (core::identify_fiducials(core::FidModel{}, std::span<const core::Blob>(blobs.data(), summary.blobs), verdicts,
                                 fid) != core::FidStatus::kOk)
      continue;
    // Which square of the strip (the host's job; here from the truth): the one whose fiducial
    // projects nearest the first identified point, all its points within 3 px.
    const auto square_of = [&](std::span<const core::IdentifiedFiducial> identified) {
      for (int q = 0; q < strip.squares; ++q) {
        bool all = true;
        for (const auto& f : identified) {
          const auto& rect = fiducials[static_cast<std::size_t>(f.id - 1)];
          const Eigen::Vector3d p =
              sim::strip_T_square(strip, q) * Eigen::Vector3d(rect.centre_m.x(), rect.centre_m.y(), 0);
          const auto px = sim::project_points(camera_spec, camera_T_strip, std::span<const Eigen::Vector3d>(&p, 1));
          all = all && std::hypot(px[0].x - f.x_px.to_double(), px[0].y - f.y_px.to_double()) < 3.0;
        }
        if (all) return q;
      }
      return -1;
    };
    const int square = square_of(std::span<const core::IdentifiedFiducial>(fid.fiducials.data(), fid.count));
    if (square < 0) {
      ++misidentified;
      continue;
    }
    ++views_with_pose;
    const Eigen::Isometry3d strip_T_first = sim::strip_T_square(strip, square);
    const Eigen::Isometry3d square_T_camera_true = (camera_T_strip * strip_T_first).inverse();
    if (fid.count == 3) ++three_fiducial_views;

    // (a) the old pose: the square's points on the ranger plane, rigid fit.
    {
      std::vector<core::Vector3<float>> square_points, camera_points;
      for (int i = 0; i < fid.count; ++i) {
        const auto& f = fid.fiducials[static_cast<std::size_t>(i)];
        core::Vector3<float> c;
        if (core::pixel_to_plane_point(camera, plane, {f.x_px.to_float(), f.y_px.to_float()}, c) !=
            core::CameraStatus::ok)
          continue;
        const auto& sq = fiducials[static_cast<std::size_t>(f.id - 1)].centre_m;
        square_points.emplace_back(static_cast<float>(sq.x()), static_cast<float>(sq.y()), 0.0f);
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

    // (b) camera-first on the square alone without the perspective pass (core::planar_pose).
    {
      std::vector<core::PlanarCorrespondence> points;
      for (int i = 0; i < fid.count; ++i) {
        const auto& f = fid.fiducials[static_cast<std::size_t>(i)];
        const auto& rect = fiducials[static_cast<std::size_t>(f.id - 1)];
        core::PlanarCorrespondence c;
        c.pixel_px = {f.x_px.to_float(), f.y_px.to_float()};
        c.target_m = rect.centre_m.cast<float>();
        points.push_back(c);
      }
      core::PlanarPoseOptions options;
      options.pixel_sigma_px = app::MeasurementPipeline::kPixelSigmaPx;
      options.perspective_passes = 0;
      core::PlanarPose pose;
      if (core::planar_pose(camera, points, &prior, options, *workspace, pose) == core::PlanarPoseStatus::ok)
        one_square_no_bias.add(to_isometry(pose.camera_T_target).inverse(), square_T_camera_true);
      else
        ++one_square_no_bias.failed;
    }

    // (c) the platform's reports, in the frame of their reference square (the FID's, as above).
    for (const bool every : {false, true}) {
      const shared::MeasurementReport& report = every ? strip_report : square_report;
      Accumulator& acc = every ? all_squares : one_square;
      if (!(every ? strip_ok : square_ok)) {
        ++acc.failed;
        continue;
      }
      std::vector<core::IdentifiedFiducial> reported;
      for (std::size_t i = 0; i < report.fiducial_count; ++i) {
        core::IdentifiedFiducial f;
        f.id = report.fiducials[i].id;
        f.x_px = core::q16_16::from_double(report.fiducials[i].x_q6 * shared::kPixelLsbPx);
        f.y_px = core::q16_16::from_double(report.fiducials[i].y_q6 * shared::kPixelLsbPx);
        reported.push_back(f);
      }
      const int reference = square_of(reported);
      if (reference < 0) {
        ++acc.failed;
        continue;
      }
      const Eigen::Isometry3d truth = (camera_T_strip * sim::strip_T_square(strip, reference)).inverse();
      const Eigen::Isometry3d estimate = reported_pose(report);
      acc.add(estimate, truth);
      acc.inside95 += inside_95(report, estimate, truth) ? 1 : 0;
      if (every) squares_per_view[std::min<std::size_t>(report.pose_squares, squares_per_view.size() - 1)] += 1;
    }
  }

  std::printf("views %d, with a pose %d, the square's identity not found %d; the platform's poses by squares used:",
              kViews, views_with_pose, misidentified);
  for (std::size_t n = 1; n < squares_per_view.size(); ++n) std::printf(" %zu: %d", n, squares_per_view[n]);
  std::printf("\n");
  const auto report = [&ranger_plane, &one_square_no_bias](const char* name, const Accumulator& a) {
    std::printf("%-40s rms %.3f mm %.3f mrad over %d views (%d failed)", name, a.rms_mm(), a.rms_mrad(), a.count,
                a.failed);
    if (&a != &ranger_plane && &a != &one_square_no_bias)
      std::printf(", 95%% coverage %.3f", static_cast<double>(a.inside95) / a.count);
    std::printf("\n");
  };
  report("ranger plane (the old pose)", ranger_plane);
  report("camera-first, one square, no bias pass", one_square_no_bias);
  report("platform, one square", one_square);
  report("platform, every square in view", all_squares);
  std::printf("FIGURE platform_pose_rms_mm %.4f mm\n", all_squares.rms_mm());
  std::printf("FIGURE platform_pose_rms_mrad %.4f mrad\n", all_squares.rms_mrad());
  std::printf("FIGURE platform_pose_ranger_plane_rms_mm %.4f mm\n", ranger_plane.rms_mm());
  std::printf("FIGURE platform_pose_ranger_plane_rms_mrad %.4f mrad\n", ranger_plane.rms_mrad());
  std::printf("FIGURE platform_pose_one_square_no_bias_rms_mm %.4f mm\n", one_square_no_bias.rms_mm());
  std::printf("FIGURE platform_pose_one_square_no_bias_rms_mrad %.4f mrad\n", one_square_no_bias.rms_mrad());
  std::printf("FIGURE platform_pose_one_square_rms_mm %.4f mm\n", one_square.rms_mm());
  std::printf("FIGURE platform_pose_one_square_rms_mrad %.4f mrad\n", one_square.rms_mrad());
  std::printf("FIGURE platform_pose_coverage_95 %.3f fraction\n",
              static_cast<double>(all_squares.inside95) / all_squares.count);
  std::printf("FIGURE platform_pose_one_square_coverage_95 %.3f fraction\n",
              static_cast<double>(one_square.inside95) / one_square.count);
  std::printf("FIGURE platform_pose_three_fiducial_views %d views\n", three_fiducial_views);
  return views_with_pose > kViews / 2 ? 0 : 1;
}

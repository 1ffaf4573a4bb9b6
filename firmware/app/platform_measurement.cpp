#include "firmware/app/platform_measurement.hpp"

#include <cmath>
#include <limits>

#include "firmware/app/rotation_vector.hpp"

namespace kincal::app {

namespace {

constexpr float kSquarePlanarToleranceM = 1.0e-4f;  // fiducial z in the square frame
constexpr std::uint8_t kCentreFiducialId = 4;
constexpr std::uint32_t kMinBlobAreaPx = 4;  // single pixels and pairs are noise, not fiducials or a beacon

// The report's one status: the most fundamental failure wins (hardware, then configuration,
// then the scene, then what this platform cannot do).
int rank(shared::MeasureStatus status) {
  switch (status) {
    case shared::MeasureStatus::kOk:
      return 0;
    case shared::MeasureStatus::kNotAvailable:
      return 1;
    case shared::MeasureStatus::kNoTarget:
      return 2;
    case shared::MeasureStatus::kNoParameters:
      return 3;
    case shared::MeasureStatus::kCameraFailure:
      return 4;
    case shared::MeasureStatus::kRangerFailure:
      return 5;
  }
  return 0;
}

// round(value * scale) if |value * scale| <= limit.
bool to_raw(float value, float scale, std::int32_t limit, std::int32_t& raw) {
  const float scaled = value * scale;
  if (!(std::fabs(scaled) <= static_cast<float>(limit))) return false;
  raw = static_cast<std::int32_t>(scaled >= 0.0f ? scaled + 0.5f : scaled - 0.5f);
  raw = raw > limit ? limit : (raw < -limit ? -limit : raw);
  return true;
}

// q16_16 pixels to the report's uq10.6, rounded; negative -> 0, saturating at 65535.
std::uint16_t pixel_q6(core::q16_16 v) {
  if (v.raw() <= 0) return 0;
  const std::uint32_t q6 = (static_cast<std::uint32_t>(v.raw()) + (1u << 9)) >> 10;
  return static_cast<std::uint16_t>(q6 > 0xFFFFu ? 0xFFFFu : q6);
}

}  // namespace

float fiducial_side_m(const shared::PlatformGeometry& g) noexcept {
  if (g.fiducial_count < kCentreFiducialId) return 0.0f;
  const auto& centre = g.fiducial_square_m[kCentreFiducialId - 1u];
  float sum_m = 0.0f;
  int count = 0;
  for (const std::uint8_t id : {std::uint8_t{2}, std::uint8_t{3}, std::uint8_t{5}, std::uint8_t{6}}) {
    if (id > g.fiducial_count) continue;
    const auto& p = g.fiducial_square_m[id - 1u];
    const float dx = p[0] - centre[0], dy = p[1] - centre[1];
    sum_m += std::sqrt(dx * dx + dy * dy);
    ++count;
  }
  if (count == 0) return 0.0f;
  const float side_m = sum_m / static_cast<float>(count * core::FidModel{}.perimeter_distance_sides);
  return side_m > 0.0f && side_m < 1.0f ? side_m : 0.0f;
}

RangerLayoutCheck prepare_ranger_plane(const shared::PlatformGeometry& g, core::RangePlaneModel& model) noexcept {
  core::RangeSensorLayout layout;
  const float z0_m = g.rangers[0].origin_m[2];
  for (std::size_t i = 0; i < shared::kRangers; ++i) {
    const shared::RangerBeam& beam = g.rangers[i];
    const auto ranger = static_cast<std::uint8_t>(i);
    if (!(std::fabs(beam.direction[0]) <= kBeamAxisTolerance && std::fabs(beam.direction[1]) <= kBeamAxisTolerance &&
          beam.direction[2] > 0.0f))
      return {RangerLayoutStatus::kBeamOffAxis, ranger};
    if (!(std::fabs(beam.origin_m[2] - z0_m) <= kBeamOriginZToleranceM)) return {RangerLayoutStatus::kOriginZ, ranger};
    layout.position_m[i] = core::Vector2<float>(beam.origin_m[0], beam.origin_m[1]);
  }
  layout.origin_z_m = z0_m;
  layout.model = core::RangeModel::along_beam;
  layout.allow_three_point = false;
  if (core::prepare_range_plane(layout, model) != core::PlaneStatus::ok) return {RangerLayoutStatus::kNoPlane, 0};
  return {};
}

void report_covariance(const core::PlanarPose& pose, std::array<float, 36>& covariance) noexcept {
  // planar_pose's covariance is of the twist [dt; dphi] of camera_T_square in the camera frame
  // (R = exp([dphi]x) R_est, t = t_est + dt). With R, t camera_T_square and A = -R^T:
  //   square_t_camera = -R^T t      moves by  A dt + A [t]x dphi
  //   square_R_camera = R^T         moves by  exp([A dphi]x) on the left
  // so J = [A, A [t]x; 0, A] and the report's covariance is J C J^T. Plain loops: fixed
  // summation order, the same bits on both targets.
  const core::Matrix3<float>& r = pose.camera_T_target.rotation;
  const core::Vector3<float>& t = pose.camera_T_target.translation;
  std::array<std::array<float, 3>, 3> a{}, t_cross{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) a[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] = -r(j, i);
  t_cross[0] = {0.0f, -t(2), t(1)};
  t_cross[1] = {t(2), 0.0f, -t(0)};
  t_cross[2] = {-t(1), t(0), 0.0f};
  std::array<std::array<float, 6>, 6> jacobian{};
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = 0; j < 3; ++j) {
      float at = 0.0f;
      for (std::size_t k = 0; k < 3; ++k) at += a[i][k] * t_cross[k][j];
      jacobian[i][j] = a[i][j];
      jacobian[i][j + 3] = at;
      jacobian[i + 3][j + 3] = a[i][j];
    }
  std::array<std::array<float, 6>, 6> jc{};
  for (std::size_t i = 0; i < 6; ++i)
    for (std::size_t j = 0; j < 6; ++j) {
      float sum = 0.0f;
      for (std::size_t k = 0; k < 6; ++k)
        sum += jacobian[i][k] * pose.covariance(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(j));
      jc[i][j] = sum;
    }
  for (std::size_t i = 0; i < 6; ++i)
    for (std::size_t j = 0; j < 6; ++j) {
      float sum = 0.0f;
      for (std::size_t k = 0; k < 6; ++k) sum += jc[i][k] * jacobian[j][k];
      covariance[i * 6 + j] = sum;
    }
}

void MeasurementPipeline::note(shared::MeasureStatus status) noexcept {
  if (rank(status) > rank(status_)) status_ = status;
}

void MeasurementPipeline::begin(const MeasureRequest& request, const ParameterSet& parameters) noexcept {
  request_ = request;
  has_geometry_ = parameters.has_geometry;
  has_intrinsics_ = parameters.has_intrinsics;
  geometry_ = parameters.geometry;
  intrinsics_ = parameters.intrinsics;
  const std::uint8_t s = request.sections;
  const bool pose_possible = (s & shared::section::kPose) != 0 && has_geometry_ && has_intrinsics_;
  needs_camera_ = (s & (shared::section::kFiducials | shared::section::kBlobs)) != 0 || pose_possible;
  needs_rangers_ =
      (s & shared::section::kRanges) != 0 || ((s & shared::section::kPlane) != 0 && has_geometry_) || pose_possible;
  labeler_config_ = core::LabelerConfig{};
  labeler_config_.polarity = (s & (shared::section::kFiducials | shared::section::kPose)) != 0
                                 ? core::Polarity::kDark
                                 : core::Polarity::kBright;
  labeler_config_.min_area_px = kMinBlobAreaPx;
  histogram_.clear();
  width_px_ = height_px_ = 0;
  have_plane_ = false;
  blob_count_ = 0;
  fiducial_side_m_ = has_geometry_ ? fiducial_side_m(geometry_) : 0.0f;
  pose_options_ = core::PlanarPoseOptions{};
  pose_options_.pixel_sigma_px = kPixelSigmaPx;
  pose_options_.perspective_passes = fiducial_side_m_ > 0.0f ? 1 : 0;
  camera_ = core::camera_from_block(intrinsics_);
  square_is_planar_ = true;
  for (std::size_t k = 0; k < geometry_.fiducial_count && k < geometry_.fiducial_square_m.size(); ++k)
    if (!(std::fabs(geometry_.fiducial_square_m[k][2]) <= kSquarePlanarToleranceM)) square_is_planar_ = false;
}

bool MeasurementPipeline::accept_frame_size(std::uint16_t width_px, std::uint16_t height_px) noexcept {
  width_px_ = width_px;
  height_px_ = height_px;
  return width_px >= 1 && width_px <= kMaxWidthPx && height_px >= 1 && height_px <= core::kLabelerMaxRows;
}

void MeasurementPipeline::meter_row() noexcept {
  // Cannot fail: the step is 4, and a frame of at most 640 x 4096 pixels stays far below
  // kMaxHistogramSamples.
  (void)histogram_.add_row(row(), kHistogramStep);
}

bool MeasurementPipeline::begin_labelling() noexcept {
  std::uint8_t otsu = 0;
  if (core::otsu_threshold(histogram_, otsu) != core::ThresholdStatus::kOk) return false;
  labeler_config_.threshold = labeler_config_.polarity == core::Polarity::kDark ? core::dark_threshold(otsu) : otsu;
  return labeler_.begin_frame(labeler_config_, blobs_) == core::LabelStatus::kOk;
}

bool MeasurementPipeline::label_row() noexcept { return labeler_.commit_row(width_px_) == core::LabelStatus::kOk; }

bool MeasurementPipeline::compute_plane(const std::array<std::uint32_t, shared::kRangers>& ranges_um) noexcept {
  if (prepare_ranger_plane(geometry_, plane_model_).status != RangerLayoutStatus::kOk) {
    note(shared::MeasureStatus::kNoParameters);
    return false;
  }
  std::array<float, core::kRangeSensorCount> range_m{};
  for (std::size_t i = 0; i < shared::kRangers; ++i) {
    range_m[i] = range_raw_from_um(ranges_um[i]) == shared::kNoEcho ? std::numeric_limits<float>::quiet_NaN()
                                                                    : static_cast<float>(ranges_um[i]) * 1.0e-6f;
  }
  if (core::fit_range_plane(plane_model_, range_m, plane_) != core::PlaneStatus::ok) {
    note(shared::MeasureStatus::kNoTarget);
    return false;
  }
  have_plane_ = true;
  return true;
}

void MeasurementPipeline::report_blobs(shared::MeasurementReport& report, std::uint32_t blob_count) const noexcept {
  const std::size_t n = blob_count < kMaxBlobsOut ? blob_count : kMaxBlobsOut;
  for (std::size_t i = 0; i < n; ++i) {
    const core::Blob& b = blobs_[i];
    shared::Blob& out = report.blobs[i];
    out.x_q6 = pixel_q6(b.x_px);
    out.y_q6 = pixel_q6(b.y_px);
    out.area_px = static_cast<std::uint16_t>(b.area_px > 0xFFFFu ? 0xFFFFu : b.area_px);
    out.colour_class = 0;
    out.peak_dn = 0;
  }
  report.blob_count = static_cast<std::uint8_t>(n);
  report.sections |= shared::section::kBlobs;
}

void MeasurementPipeline::compute_fiducials_and_pose(shared::MeasurementReport& report) noexcept {
  if ((request_.sections & shared::section::kFiducials) != 0) {
    for (std::size_t i = 0; i < fid_.count; ++i) {
      const core::IdentifiedFiducial& f = fid_.fiducials[i];
      report.fiducials[i] = {f.id, pixel_q6(f.x_px), pixel_q6(f.y_px)};
    }
    report.fiducial_count = fid_.count;
    report.sections |= shared::section::kFiducials;
  }
  if ((request_.sections & shared::section::kPose) == 0 || !has_intrinsics_ || !square_is_planar_ ||
      intrinsics_.width_px != width_px_ || intrinsics_.height_px != height_px_)
    return;  // why not was noted by finish()
  if (!compute_pose() || !encode_pose(report)) note(shared::MeasureStatus::kNoTarget);
}

bool MeasurementPipeline::compute_pose() noexcept {
  const std::size_t square_points = collect_correspondences();
  if (!solve_pose(square_points)) return false;
  pose_squares_ = 1;
  const std::size_t all_points = match_strip(square_points);
  if (all_points > square_points) {
    // The square's own pose stands if the points found do not fit together (a wrong match).
    square_pose_ = pose_;
    if (solve_pose(all_points) && pose_.reprojection_rms_px <= kMaxReprojectionRmsPx)
      pose_squares_ = static_cast<std::uint8_t>(1 + strip_squares_matched_);
    else
      pose_ = square_pose_;
  }
  return true;
}

core::Vector2<float> MeasurementPipeline::fiducial_half_size_m(std::uint8_t id) const noexcept {
  // Doty's rectangles: s x s, the centre p4 s x 2s with its long side along y.
  const float half_m = 0.5f * fiducial_side_m_;
  return {half_m, id == kCentreFiducialId ? 2.0f * half_m : half_m};
}

std::size_t MeasurementPipeline::collect_correspondences() noexcept {
  std::size_t n = 0;
  for (std::size_t i = 0; i < fid_.count; ++i) {
    const core::IdentifiedFiducial& f = fid_.fiducials[i];
    if (f.id < 1 || f.id > geometry_.fiducial_count) continue;
    const auto& s = geometry_.fiducial_square_m[f.id - 1u];
    core::PlanarCorrespondence& c = correspondences_[n++];
    c.pixel_px = core::Vector2<float>(f.x_px.to_float(), f.y_px.to_float());
    c.target_m = core::Vector2<float>(s[0], s[1]);
    c.fiducial_half_size_m = fiducial_half_size_m(f.id);
  }
  return n;
}

std::size_t MeasurementPipeline::match_strip(std::size_t square_points) noexcept {
  const std::size_t fiducials = geometry_.fiducial_count < pattern_.size() ? geometry_.fiducial_count : pattern_.size();
  for (std::size_t k = 0; k < fiducials; ++k) {
    const auto& s = geometry_.fiducial_square_m[k];
    pattern_[k].centre_m = core::Vector2<float>(s[0], s[1]);
    pattern_[k].half_size_m = fiducial_half_size_m(static_cast<std::uint8_t>(k + 1));
  }
  // The square's fiducials in the pose are found; their blobs are theirs.
  std::uint8_t found = 0;
  for (std::size_t i = 0; i < blob_count_; ++i) blob_taken_[i] = 0;
  for (std::size_t i = 0; i < fid_.count; ++i) {
    const core::IdentifiedFiducial& f = fid_.fiducials[i];
    if (f.id < 1 || f.id > fiducials) continue;
    found = static_cast<std::uint8_t>(found | 1u << (f.id - 1));
    if (f.blob_index < blob_count_) blob_taken_[f.blob_index] = 1;
  }
  core::StripMatch match;
  if (core::match_strip_fiducials(camera_, width_px_, height_px_, pose_.camera_T_target,
                                  std::span<const core::StripFiducial>(pattern_.data(), fiducials), found,
                                  geometry_.square_pitch_m, std::span<const core::Blob>(blobs_.data(), blob_count_),
                                  std::span<std::uint8_t>(blob_taken_.data(), blob_count_), core::StripMatchOptions{},
                                  correspondences_, square_points, match) != core::StripMatchStatus::ok)
    return square_points;
  strip_squares_matched_ = match.squares_matched;
  return square_points + match.points_added;
}

bool MeasurementPipeline::prepare_prior() noexcept {
  if (!have_plane_ ||
      core::range_plane_covariance(plane_model_, plane_, kRangeSigmaM, prior_.covariance) != core::PlaneStatus::ok)
    return false;
  prior_.plane = plane_;
  return true;
}

bool MeasurementPipeline::solve_pose(std::size_t point_count) noexcept {
  const core::PlanePrior* prior = prepare_prior() ? &prior_ : nullptr;
  return core::planar_pose(camera_, std::span<const core::PlanarCorrespondence>(correspondences_.data(), point_count),
                           prior, pose_options_, pose_workspace_, pose_) == core::PlanarPoseStatus::ok;
}

bool MeasurementPipeline::encode_pose(shared::MeasurementReport& report) noexcept {
  square_T_camera_ = pose_.camera_T_target.inverse();
  const core::Vector3<float> rotation = rotation_vector(square_T_camera_.rotation);
  std::array<std::int32_t, 3> translation_raw{}, rotation_raw{};
  for (int k = 0; k < 3; ++k) {
    const auto i = static_cast<std::size_t>(k);
    if (!to_raw(square_T_camera_.translation(k), 262144.0f, (1 << 19) - 1, translation_raw[i]) ||
        !to_raw(rotation(k), 32768.0f, (1 << 17) - 1, rotation_raw[i]))
      return false;
  }
  report.translation_raw = translation_raw;
  report.rotation_raw = rotation_raw;
  report.pose_squares = pose_squares_;
  report_covariance(pose_, report_covariance_);
  shared::set_pose_covariance(report_covariance_, report);
  report.sections |= shared::section::kPose;
  return true;
}

void MeasurementPipeline::finish(CaptureStatus camera, bool labelled, RangerStatus rangers,
                                 const std::array<std::uint32_t, shared::kRangers>& ranges_um,
                                 std::uint32_t timestamp_us, shared::MeasurementReport& report) noexcept {
  report = shared::MeasurementReport{};
  report.sequence = request_.sequence;
  report.timestamp_us = timestamp_us;
  status_ = shared::MeasureStatus::kOk;
  const std::uint8_t s = request_.sections;

  bool ranges_ok = false;
  if (needs_rangers_) {
    if (rangers != RangerStatus::kOk) {
      note(shared::MeasureStatus::kRangerFailure);
    } else {
      ranges_ok = true;
      if ((s & shared::section::kRanges) != 0) {
        for (std::size_t i = 0; i < shared::kRangers; ++i) report.range_raw[i] = range_raw_from_um(ranges_um[i]);
        report.sections |= shared::section::kRanges;
      }
    }
  }

  if ((s & (shared::section::kPlane | shared::section::kPose)) != 0) {
    if (!has_geometry_) {
      note(shared::MeasureStatus::kNoParameters);
    } else if (ranges_ok && compute_plane(ranges_um) && (s & shared::section::kPlane) != 0) {
      // The report's normal points at the camera: range_plane's, negated.
      std::int32_t nx = 0, ny = 0, distance = 0;
      if (to_raw(-plane_.normal.x(), 32768.0f, 32767, nx) && to_raw(-plane_.normal.y(), 32768.0f, 32767, ny) &&
          to_raw(plane_.distance_m, 65536.0f, 65535, distance) && distance < shared::kNoEcho) {
        report.plane_normal_x_raw = static_cast<std::int16_t>(nx);
        report.plane_normal_y_raw = static_cast<std::int16_t>(ny);
        report.plane_distance_raw = static_cast<std::uint16_t>(distance);
        report.sections |= shared::section::kPlane;
      } else {
        note(shared::MeasureStatus::kNoTarget);
      }
    }
  }
  // Intrinsics calibrated for another frame size do not describe this camera's pixels.
  const bool intrinsics_fit =
      has_intrinsics_ && intrinsics_.width_px == width_px_ && intrinsics_.height_px == height_px_;
  if ((s & shared::section::kPose) != 0 && (!intrinsics_fit || !square_is_planar_))
    note(shared::MeasureStatus::kNoParameters);

  if (needs_camera_) {
    core::FrameSummary& summary = summary_;
    if (camera != CaptureStatus::kOk) {
      note(shared::MeasureStatus::kCameraFailure);
    } else if (!labelled) {
      note(shared::MeasureStatus::kNoTarget);
    } else if (labeler_.end_frame(summary) != core::LabelStatus::kOk) {
      note(shared::MeasureStatus::kCameraFailure);
    } else {
      if ((s & shared::section::kBlobs) != 0) report_blobs(report, summary.blobs);
      if ((s & (shared::section::kFiducials | shared::section::kPose)) != 0) {
        const std::size_t n = summary.blobs < kMaxBlobsOut ? summary.blobs : kMaxBlobsOut;
        blob_count_ = n;
        if (core::identify_fiducials(core::FidModel{}, std::span<const core::Blob>(blobs_.data(), n), verdicts_,
                                     fid_) == core::FidStatus::kOk) {
          compute_fiducials_and_pose(report);
        } else {
          note(shared::MeasureStatus::kNoTarget);
        }
      }
    }
  }
  if ((s & shared::section::kPoint) != 0) note(shared::MeasureStatus::kNotAvailable);
  report.status = status_;
}

}  // namespace kincal::app

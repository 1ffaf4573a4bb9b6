// The sensor platform's measurement step (Doty's ARID platform: a camera and four rangers in a +
// pattern around it), over a CameraPort and a RangerPort (ports.hpp): the MeasurementStep of the
// STM32 image and of the native platform.
//
// Per trigger, for the sections it asks for (shared/measurement_report.hpp):
//   ranges     the four rangers once: LSB 2^-16 m; kNoEcho for a sensor without a valid reading
//              or one outside the report's [0, 1) m.
//   plane      the calibration plane from the four ranges (core::fit_range_plane, least squares,
//              along-beam model) with the PlatformGeometry block's beams, which must leave the
//              sensors parallel to the optical axis (within 1e-3 in each direction component)
//              from a common z (within 0.1 mm); otherwise the block counts as missing. All four
//              readings are needed (no three-point plane: it could not be checked for
//              flatness); a missing one, or a least-squares residual above 2 mm (not flat: the
//              beams are not all on the square), gives kNoTarget and no plane. Reported in the
//              report's convention: normal pointing at the camera (the negated range_plane
//              normal), distance from the camera centre.
//   fiducials  Doty's FID (core::identify_fiducials) on the frame's dark blobs: id = Doty's
//              p1..p6 (fiducial_id.hpp), centre = the blob's best centroid (uq10.6 px, pixel
//              (0, 0) the centre of the top-left pixel). Fewer than three non-collinear
//              fiducials: kNoTarget and no section.
//   pose       square_T_camera: the camera frame (OpenCV: x right, y down, z along the optical
//              axis) in the square's frame (fiducial_id.hpp: x to p5, y to p2, origin at the
//              centre fiducial p4 as the geometry block places it, z out of the printed side).
//              Translation = the camera centre in square coordinates (LSB 2^-18 m); rotation =
//              the rotation vector of square_R_camera (axis * angle, LSB 2^-15 rad), so that
//              p_square = exp(rotation) p_camera + translation. How (camera first, issue #13):
//              core::planar_pose (planar_pose.hpp) on the identified fiducials p_k (k = 1..6,
//              k <= fiducial_count), each pixel paired with PlatformGeometry::fiducial_square_m
//              [k - 1] (its z must be 0 within 0.1 mm: the square is planar; else the block
//              counts as missing): homography start, Gauss-Newton through the full lens model
//              (CameraIntrinsics, with distortion; each coordinate kPixelSigmaPx), and the ranger
//              plane (when the rangers gave one) as a prior with its covariance from
//              kRangeSigmaM per reading (core::range_plane_covariance). Fiducial centres, not
//              blob centroids: one pass corrects each fiducial's perspective bias with the pose
//              of the first (the rectangles s x s, p4 s x 2s, with s the perimeter fiducials'
//              mean distance from p4 / 7 in the geometry block; no correction if the block has
//              no p4 or no perimeter fiducial). Needs three fiducials with the plane prior, or
//              four without it (then the rangers' failure is still the report's status); else
//              kNoTarget and no section, as for a pose beyond the report's range (+-2 m).
//              Then the fiducials that pose predicts (core::match_strip_fiducials,
//              strip_fiducials.hpp): the square's own that FID missed and, with the geometry
//              block's square_pitch_m (> 0), every square of the strip in view, whole or cut by the
//              frame's edge. The FID's square stays the reference (its frame is the pose's, its
//              fiducials the report's fiducials section); planar_pose runs again on all the points
//              (at most kPlanarPoseMaxPoints), and that pose is kept only if its reprojection RMS
//              is at most kMaxReprojectionRmsPx, else the square's own stands (a blob taken for a
//              fiducial that is not one, a wrong pitch). pose_squares: how many squares it used.
//              Its covariance (report_covariance below): planar_pose's, of its camera-frame
//              twist, carried to the reported (t, delta) of measurement_report.hpp; it trusts
//              kPixelSigmaPx and kRangeSigmaM as given.
//   blobs      the labeler's blobs (at most 64, in completion order): centroid uq10.6 px, area
//              (saturating at 65535 px), colour class 0 (grey rows: no colour classes) and
//              peak_dn 0 (not measured: the streaming labeler keeps no per-blob extreme).
//   point      a stereo triangulation: not this platform's (one camera): kNotAvailable.
// Polarity, chosen by the request: dark blobs (fiducials on light vellum) when fiducials or
// pose are asked for, bright blobs (the Kapucu & Baysec beacon) otherwise; the blob section lists
// the blobs of that polarity.
// Threshold, automatic: each measurement first streams a metering frame (FrameUse::kMetering)
// into a grey-level histogram (every 4th pixel) and labels the measurement frame of the same scene
// with Otsu's threshold of it (auto_threshold.hpp). A uniform frame (one grey level) has no
// threshold: kNoTarget for the camera sections.
// Time stamp: the measurement frame's mid-exposure (CameraPort), when the camera is used; else
// the rangers' reading time. The rangers are read right after the measurement frame is
// requested, so both see the same scene. The report's sequence is the request's.
// Status, one per report, the first that applies in this order: kRangerFailure, kCameraFailure
// (begin_frame or read_row failed, a row did not come within kFrameTimeoutUs, the camera's frame
// is wider than kMaxWidthPx or taller than 4096 rows, or the labeler refused a row),
// kNoParameters (a block a requested section needs is missing or unusable; intrinsics for
// another frame size than the camera's count as missing), kNoTarget, kNotAvailable. Sections
// that could be produced are present whatever the status; nothing is ever invented.
//
// Memory: everything inside the object, about 25.2 KB on the M4 (the VGA labeler workspace of
// 16 KiB, 64 blobs, the histogram, the range-plane matrices, the planar pose's workspace and
// correspondences, the strip's pattern and a second pose, copies of the two parameter blocks):
// construct it statically, never on the stack; the deepest call (finish) needs 1000 bytes of
// stack (m4.kincal_app.stack). Cost: poll() handles at most kRowsPerPoll rows per call, a bounded
// slice (16 VGA rows are ~35k instructions on the M4), so the correction stream keeps running
// between slices; the final call runs FID, the plane fit and the pose (about 60k instructions;
// twice that and the strip's matching when other squares are in view). Measured on a VGA strip
// frame (tests/bench/measurement_m4_bench.cpp): 0.66M instructions for the metering frame,
// 1.18M for the measurement frame including FID, plane, pose and the strip's pose.
// Thread/ISR safety: main loop only. One measurement at a time (start() while one runs: kBusy).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "firmware/app/ports.hpp"
#include "firmware/core/auto_threshold.hpp"
#include "firmware/core/blob_labeler.hpp"
#include "firmware/core/camera_model.hpp"
#include "firmware/core/fiducial_id.hpp"
#include "firmware/core/planar_pose.hpp"
#include "firmware/core/range_plane.hpp"
#include "firmware/core/strip_fiducials.hpp"
#include "shared/measurement_report.hpp"

namespace kincal::app {

// Micrometres to the report's LSB of 2^-16 m, rounded to nearest; out of [0, 1) m -> kNoEcho.
constexpr std::uint16_t range_raw_from_um(std::uint32_t range_um) {
  if (range_um == kNoEchoUm) return shared::kNoEcho;
  const std::uint64_t raw = (std::uint64_t{range_um} * 65536u + 500000u) / 1000000u;
  return raw >= shared::kNoEcho ? shared::kNoEcho : static_cast<std::uint16_t>(raw);
}

// What the plane fit needs of the geometry block's rangers (the `plane` section above), checked
// here for the platform and for the host that writes the block (host/session/platform_setup.hpp).
inline constexpr float kBeamAxisTolerance = 1.0e-3f;      // each direction's x and y, off the optical axis
inline constexpr float kBeamOriginZToleranceM = 1.0e-4f;  // each origin's z from the first ranger's
enum class RangerLayoutStatus : std::uint8_t {
  kOk,
  kBeamOffAxis,  // a direction's x or y beyond kBeamAxisTolerance, or z not positive
  kOriginZ,      // an origin's z more than kBeamOriginZToleranceM from the first ranger's
  kNoPlane,      // the origins give no least-squares plane (three on one line in x, y)
};
struct RangerLayoutCheck {
  RangerLayoutStatus status = RangerLayoutStatus::kOk;
  std::uint8_t ranger = 0;  // the first ranger that fails (kBeamOffAxis, kOriginZ)
};
// The rangers checked in order (each beam's direction, then its origin's z), then the along-beam
// plane model prepared (core::prepare_range_plane, no three-point fit); `model` is usable on kOk.
RangerLayoutCheck prepare_ranger_plane(const shared::PlatformGeometry& geometry, core::RangePlaneModel& model) noexcept;

// The fiducials' side s in the geometry block: the perimeter fiducials p2, p3, p5, p6 are
// FidModel::perimeter_distance_sides s from the centre p4 (fiducial_id.hpp); their mean distance.
// 0 when the block has not the centre and at least one of them.
float fiducial_side_m(const shared::PlatformGeometry& geometry) noexcept;

// The covariance of the reported pose (measurement_report.hpp: square_T_camera's translation and
// its rotation error delta, row-major 6 x 6) from planar_pose's covariance of its camera-frame
// twist: first order, exact for the twist's definition. Plain float loops (the same bits on both
// targets).
void report_covariance(const core::PlanarPose& pose, std::array<float, 36>& covariance) noexcept;

// The port-independent half of the step: the pixel path and the geometry, compiled once in
// platform_measurement.cpp (where the stack and heap checks see it). PlatformMeasurement below
// drives it from the ports.
class MeasurementPipeline {
 public:
  static constexpr std::uint16_t kMaxWidthPx = 640;
  static constexpr std::size_t kMaxBlobsOut = shared::kMaxBlobs;
  static constexpr std::uint32_t kHistogramStep = 4;
  // The noise the pose's weights and covariance assume: each fiducial centre coordinate, and each
  // range reading (the ARID platform's rangers; host/sim/rangers.hpp simulates the same).
  static constexpr float kPixelSigmaPx = 0.1f;
  static constexpr float kRangeSigmaM = 0.5e-3f;
  // The strip's pose is kept only if its reprojection RMS is at most this (5 kPixelSigmaPx): a
  // larger one means a blob taken for a fiducial is not that fiducial, and the square's own pose
  // stands.
  static constexpr float kMaxReprojectionRmsPx = 0.5f;

  MeasurementPipeline() noexcept : labeler_(buffers_.memory()) {}

  // The next measurement: what it needs, from the request and the blocks present.
  void begin(const MeasureRequest& request, const ParameterSet& parameters) noexcept;
  bool needs_camera() const noexcept { return needs_camera_; }
  bool needs_rangers() const noexcept { return needs_rangers_; }
  // False for a frame size the step cannot label (then kCameraFailure).
  bool accept_frame_size(std::uint16_t width_px, std::uint16_t height_px) noexcept;

  // The row the camera port writes into: the labeler's next ring slot (also the metering scratch).
  std::span<std::uint8_t> row() noexcept { return labeler_.row_buffer().first(width_px_); }
  void meter_row() noexcept;
  // Otsu's threshold of the metering frame, and the labeler's frame; false: no threshold (uniform).
  bool begin_labelling() noexcept;
  // The row() just written; false: the labeler refused it (kCameraFailure).
  bool label_row() noexcept;

  // Fills the report from what was gathered: camera kOk when the measurement frame was read
  // completely (kFailed: lost; ignored unless needs_camera()), labelled when it was labelled (a
  // threshold existed), the rangers' status and reading (ignored unless needs_rangers()).
  void finish(CaptureStatus camera, bool labelled, RangerStatus rangers,
              const std::array<std::uint32_t, shared::kRangers>& ranges_um, std::uint32_t timestamp_us,
              shared::MeasurementReport& report) noexcept;

 private:
  void note(shared::MeasureStatus status) noexcept;
  [[gnu::noinline]] bool compute_plane(const std::array<std::uint32_t, shared::kRangers>& ranges_um) noexcept;
  void compute_fiducials_and_pose(shared::MeasurementReport& report) noexcept;
  core::Vector2<float> fiducial_half_size_m(std::uint8_t id) const noexcept;
  // The reference square's pose, then the strip's (pose_, pose_squares_); false: no pose. Inline
  // in compute_fiducials_and_pose: one frame less under planar_pose.
  [[gnu::always_inline]] inline bool compute_pose() noexcept;
  // The pose in steps, kept out of line so that their locals do not stack up under planar_pose
  // (the app's stack budget, m4.kincal_app.stack).
  [[gnu::noinline]] std::size_t collect_correspondences() noexcept;
  // The fiducials the square's pose predicts (core::match_strip_fiducials: the square's own that
  // FID missed, the strip's other squares' in view) appended to its points; the points in all.
  // The squares it matched go to strip_squares_matched_, not a returned struct: 16 bytes less of
  // stack under planar_pose (m4.kincal_app.stack).
  [[gnu::noinline]] std::size_t match_strip(std::size_t square_points) noexcept;
  [[gnu::noinline]] bool prepare_prior() noexcept;  // the plane prior, if there is a plane
  [[gnu::noinline]] bool solve_pose(std::size_t point_count) noexcept;
  [[gnu::noinline]] bool encode_pose(shared::MeasurementReport& report) noexcept;
  void report_blobs(shared::MeasurementReport& report, std::uint32_t blob_count) const noexcept;

  MeasureRequest request_{};
  bool has_geometry_ = false, has_intrinsics_ = false;
  shared::PlatformGeometry geometry_{};
  shared::CameraIntrinsics intrinsics_{};
  bool needs_camera_ = false, needs_rangers_ = false;
  std::uint16_t width_px_ = 0, height_px_ = 0;
  shared::MeasureStatus status_ = shared::MeasureStatus::kOk;

  core::VgaLabelerBuffers buffers_{};
  core::BlobLabeler labeler_;
  core::LabelerConfig labeler_config_{};
  core::GreyHistogram histogram_{};
  core::FrameSummary summary_{};
  std::array<core::Blob, kMaxBlobsOut> blobs_{};
  std::array<core::FidVerdict, kMaxBlobsOut> verdicts_{};
  std::size_t blob_count_ = 0;
  core::FidResult fid_{};
  core::RangePlaneModel plane_model_{};
  core::CalibrationPlane plane_{};
  bool have_plane_ = false;
  core::CameraIntrinsics camera_{};
  float fiducial_side_m_ = 0.0f;
  bool square_is_planar_ = true;
  std::array<core::PlanarCorrespondence, core::kPlanarPoseMaxPoints> correspondences_{};
  core::PlanePrior prior_{};
  core::PlanarPoseOptions pose_options_{};  // a member, not a local: the stack under planar_pose
  core::PlanarPoseWorkspace pose_workspace_{};
  core::PlanarPose pose_{};
  std::array<core::StripFiducial, shared::kMaxFiducials> pattern_{};
  std::array<std::uint8_t, kMaxBlobsOut> blob_taken_{};
  core::PlanarPose square_pose_{};  // the reference square's alone, while the strip's is tried
  std::uint8_t strip_squares_matched_ = 0;
  std::uint8_t pose_squares_ = 1;
  std::array<float, 36> report_covariance_{};
  core::RigidTransform<float> square_T_camera_{};
};

template <CameraPort Camera, RangerPort Rangers>
class PlatformMeasurement {
 public:
  static constexpr int kRowsPerPoll = 16;
  static constexpr std::uint64_t kFrameTimeoutUs = 1000000;  // per frame, from begin_frame

  PlatformMeasurement(Camera& camera, Rangers& rangers) noexcept : camera_(camera), rangers_(rangers) {}

  MeasureStart start(const MeasureRequest& request, const ParameterSet& parameters, std::uint64_t now_us) noexcept {
    if (phase_ != Phase::kIdle) return MeasureStart::kBusy;
    pipeline_.begin(request, parameters);
    phase_ = Phase::kStarting;
    timestamp_us_ = now_us;
    return MeasureStart::kStarted;
  }

  bool poll(std::uint64_t now_us, shared::MeasurementReport& report) noexcept {
    switch (phase_) {
      case Phase::kIdle:
        return false;
      case Phase::kStarting:
        if (!pipeline_.needs_camera()) {
          read_rangers();
          return finish(report, CaptureStatus::kOk, false);
        }
        if (!pipeline_.accept_frame_size(camera_.width_px(), camera_.height_px()))
          return finish(report, CaptureStatus::kFailed, false);
        return begin(FrameUse::kMetering, now_us, report);
      case Phase::kMetering:
      case Phase::kLabelling:
        return stream_rows(now_us, report);
    }
    return false;
  }

 private:
  enum class Phase : std::uint8_t { kIdle, kStarting, kMetering, kLabelling };

  bool begin(FrameUse use, std::uint64_t now_us, shared::MeasurementReport& report) noexcept {
    std::uint64_t exposure_us = now_us;
    if (camera_.begin_frame(use, exposure_us) != CaptureStatus::kOk)
      return finish(report, CaptureStatus::kFailed, false);
    row_ = 0;
    deadline_us_ = now_us + kFrameTimeoutUs;
    if (use == FrameUse::kMetering) {
      phase_ = Phase::kMetering;
      return false;
    }
    timestamp_us_ = exposure_us;
    read_rangers();
    // Without a threshold (a uniform metering frame) the frame is still read out, unlabelled:
    // a port need not support abandoning a frame halfway.
    labelled_ = pipeline_.begin_labelling();
    phase_ = Phase::kLabelling;
    return false;
  }

  bool stream_rows(std::uint64_t now_us, shared::MeasurementReport& report) noexcept {
    for (int i = 0; i < kRowsPerPoll; ++i) {
      const CaptureStatus status = camera_.read_row(pipeline_.row());
      if (status == CaptureStatus::kFailed) return finish(report, CaptureStatus::kFailed, false);
      if (status == CaptureStatus::kPending) {
        if (now_us >= deadline_us_) return finish(report, CaptureStatus::kFailed, false);
        return false;
      }
      if (phase_ == Phase::kMetering) {
        pipeline_.meter_row();
      } else if (labelled_ && !pipeline_.label_row()) {
        return finish(report, CaptureStatus::kFailed, false);
      }
      if (++row_ < camera_.height_px()) continue;
      if (phase_ == Phase::kMetering) return begin(FrameUse::kMeasurement, now_us, report);
      return finish(report, CaptureStatus::kOk, labelled_);
    }
    return false;
  }

  void read_rangers() noexcept {
    if (!pipeline_.needs_rangers() || rangers_read_) return;
    std::uint64_t time_us = timestamp_us_;
    ranger_status_ = rangers_.read(ranges_um_, time_us);
    rangers_read_ = true;
    if (!pipeline_.needs_camera()) timestamp_us_ = time_us;
  }

  // A camera that failed before the measurement frame still leaves the rangers to read.
  bool finish(shared::MeasurementReport& report, CaptureStatus camera, bool labelled) noexcept {
    read_rangers();
    pipeline_.finish(camera, labelled, ranger_status_, ranges_um_, static_cast<std::uint32_t>(timestamp_us_), report);
    phase_ = Phase::kIdle;
    rangers_read_ = false;
    return true;
  }

  Camera& camera_;
  Rangers& rangers_;
  MeasurementPipeline pipeline_;
  Phase phase_ = Phase::kIdle;
  std::uint16_t row_ = 0;
  bool labelled_ = false;
  std::uint64_t deadline_us_ = 0;
  std::uint64_t timestamp_us_ = 0;
  bool rangers_read_ = false;
  RangerStatus ranger_status_ = RangerStatus::kFailed;
  std::array<std::uint32_t, shared::kRangers> ranges_um_{};
};

}  // namespace kincal::app

// The fiducials of the strip's squares, found where the reference square's pose puts them (issue
// #13: every square in view, also partly visible ones): the reference square's own that its FID
// did not give, and, with the strip's pitch, every fiducial of its neighbours.
//
// Why: one 4-inch square at 0.2-0.45 m spans a small part of the image, so its pose is weak in
// tilt (1.7 mrad RMS on the simulated ARID rig); the strip's neighbouring squares in the same
// frame widen the baseline several times. Doty's FID (fiducial_id.hpp) needs a square's centre
// fiducial and finds one square at a time; run again on leftover blobs it also "finds" squares
// in unrelated blobs. Here every fiducial of every neighbouring square is predicted from the
// reference square's pose and the strip's layout, and taken only where a blob of the right size
// lies at the predicted place: a square cut by the image edge still contributes what is visible,
// and a blob that is not where the strip says cannot be taken. The reference square's own
// fiducials that FID missed (beyond its search radius under strong perspective) are found the
// same way.
//
// The strip (host/sim/strip.hpp): identical squares in a row along the square frame's x axis,
// axes parallel, centres pitch_m apart; square n (n = +-1 .. +-kStripMaxOffset from the
// reference) has fiducial k at pattern[k].centre_m + (n pitch_m, 0). pitch_m = 0: the reference
// square alone.
//
// Matching, per predicted fiducial (the reference square's fiducials whose bit in
// reference_found is clear, then the offsets in order -1, +1, -2, +2, ...; fiducials in pattern
// order): its centre projected through the full lens model (camera_model.hpp) and its rectangle's
// image area A from the four projected corners (shoelace). Skipped if a corner is behind the
// camera or outside the model's domain, or the centre is not inside the frame. The candidate is
// the nearest blob (best centroid) that is not taken, is complete and does not touch the border
// (Blob::flags), whose area is within [options.area_ratio_min, options.area_ratio_max] x A, and
// lies within options.gate_sides x sqrt(A) of the prediction (the strip's fiducials are at least
// 2 sides apart, a square's p5 and the next one's p3, so one side around a correct prediction
// reaches no other fiducial's blob). It is taken (its flag set in blob_taken) and appended to
// `points` as the fiducial's correspondence in the REFERENCE square's frame: target (centre +
// (n pitch, 0)), half size, and the blob's centroid. The caller solves planar_pose on them with
// the reference square's own points.
//
// Bounds: at most (2 kStripMaxOffset + 1) x pattern.size() predictions (at most
// kStripMaxPatternFiducials per square) against blobs.size() blobs; output stops when `points`
// is full. Cost on the M4: one projection per prediction plus four per one in the frame, and a
// pass over the blobs for each. Numerics: float, fixed order: the same bits natively and on the
// M4. No heap; pure.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "firmware/core/blob_labeler.hpp"
#include "firmware/core/camera_model.hpp"
#include "firmware/core/planar_pose.hpp"
#include "firmware/core/rigid_transform.hpp"

namespace kincal::core {

inline constexpr int kStripMaxOffset = 4;  // squares searched on each side of the reference
inline constexpr std::size_t kStripMaxPatternFiducials = 8;

// One fiducial of a square: its centre and half sides in the square frame (z = 0), metres.
struct StripFiducial {
  Vector2<float> centre_m = Vector2<float>::Zero();
  Vector2<float> half_size_m = Vector2<float>::Zero();
};

struct StripMatchOptions {
  float gate_sides = 1.0f;  // search radius, in sqrt(predicted area) (one side of a small fiducial)
  float area_ratio_min = 0.5f, area_ratio_max = 2.0f;  // blob area over the predicted image area
};

struct StripMatch {
  std::uint8_t points_added = 0;     // correspondences appended, in all
  std::uint8_t reference_added = 0;  // of them the reference square's own
  std::uint8_t squares_matched = 0;  // neighbouring squares with at least one fiducial taken
};

enum class [[nodiscard]] StripMatchStatus : std::uint8_t{
    ok,
    bad_arguments,  // pitch negative or not finite, too large a pattern, blob_taken shorter than blobs,
                    // frame size zero, or point_count beyond points
};

// Appends the fiducials found in `blobs` to points[point_count ..], taking each blob at most once
// (blob_taken: non-zero = already used, e.g. by the reference square's FID). reference_found: bit
// k set if the reference square's pattern[k] is among the caller's points already.
StripMatchStatus match_strip_fiducials(const CameraIntrinsics& camera, std::uint16_t width_px, std::uint16_t height_px,
                                       const RigidTransform<float>& camera_T_square,
                                       std::span<const StripFiducial> pattern, std::uint8_t reference_found,
                                       float pitch_m, std::span<const Blob> blobs, std::span<std::uint8_t> blob_taken,
                                       const StripMatchOptions& options, std::span<PlanarCorrespondence> points,
                                       std::size_t point_count, StripMatch& out) noexcept;

}  // namespace kincal::core

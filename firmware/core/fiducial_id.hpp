// Doty's fiducial identification (FID, ARID report section 5.4): which blob of a frame is which
// fiducial of a calibration square, and the square's axes in the image.
//
// The square (Doty Fig. 5.1 / 7.3), in units of the small fiducial's side s (1/4 inch; n pixels
// per inch means s = n/4 px): the centre fiducial p4 is 2s x s (twice the area of the others;
// its long side is the square's y axis); four perimeter fiducials s x s at 7s (1.75 inch) from
// the centre along the axes — p2 at +y, p6 at -y, p5 at +x, p3 at -x (eq. 7-33); and the corner
// marker p1 in quadrant two (-x, +y), the "upper left-hand corner", at (-7s, +7s): it removes
// the 180-degree ambiguity that the centre fiducial's shape leaves. The square is seen from its
// printed side, so its frame is not mirrored in the image: x = (-y_image_y, y_image_x) for the
// image vectors of the unit axes (image x right, y down), i.e. paper upright gives x right, y up.
//
// The algorithm, on the labeler's blob list (dark blobs on light vellum):
//   1. centre candidates: blobs (complete, not on the border) whose second moments are
//      elongated (eigenvalue ratio in [centre_ratio_min, centre_ratio_max]; a 2:1 rectangle has
//      4); s = sqrt(area / 2); y axis along the major axis, first toward increasing image y
//      (Doty's prior), x axis perpendicular;
//   2. perimeter and corner candidates: compact blobs (ratio <= perimeter_ratio_max) with area
//      within [area_ratio_min, area_ratio_max] x s^2, within search_radius_fraction x 7s of each
//      predicted position (7s along +-x, +-y; the corner at (-7s, +7s) and, for the flipped
//      hypothesis, (7s, -7s)): room for perspective. The nearest to the prediction wins, but on
//      the x axis the nearest to the centre: on Doty's strip the next squares' p3 and p5 lie 2s
//      beyond this square's p5 and p3, and a centre blob enlarged by blur and threshold puts
//      the 7s prediction nearer to them (21 of the 200 strip views of platform_pose_bench
//      failed so before);
//   3. the corner marker decides the orientation: found only at the flipped position, both axes
//      flip (and p2/p6, p3/p5 swap); found at neither, the prior stands (orientation_from_marker
//      false); found at both, the prior stands and both are rejected as ambiguous;
//   4. the candidate with the most fiducials wins (ties: the first in raster order, Doty's
//      scan); its axes are re-measured on the longest available vectors p6->p2 (or p6->p4,
//      p4->p2) and p3->p5 ("compute the longest vector along each axis");
//   5. at least three identified, non-collinear points (triangle area > 0.1 (7s)^2), else an
//      error status: three non-collinear points fix the square's pose (section 5.3).
// Every blob gets a verdict: what it was identified as, or why it was rejected.
//
// Image points are the blobs' best centroids (Blob::x_px, y_px), unchanged.
//
// Arithmetic: integers (positions in q8 px, unit vectors in q14, 64-bit products): the same bits
// natively and on the M4. Cost: O(blobs x centre candidates), a few thousand instructions for a
// typical frame; at most kFidMaxBlobs blobs. Memory: the caller's verdict span and result; no
// heap; the stack check reports its worst case (under the core's 512-byte budget).
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include "firmware/core/blob_labeler.hpp"
#include "firmware/core/fixed_point.hpp"

namespace kincal::core {

inline constexpr std::size_t kFidMaxBlobs = 256;

enum class [[nodiscard]] FidStatus : std::uint8_t{
    kOk,
    kNoCentre,          // no blob looks like the centre fiducial
    kTooFewFiducials,   // fewer than three identified points
    kCollinear,         // three or more, but on one line: the pose is not determined
    kTooManyBlobs,      // more than kFidMaxBlobs blobs
    kVerdictsTooShort,  // verdicts.size() < blobs.size()
};

enum class FidVerdict : std::uint8_t {
  kUnused,                // not examined (an error status ended the search)
  kCentre,                // p4
  kPerimeter,             // p2, p3, p5 or p6
  kCorner,                // p1
  kRejectedIncomplete,    // the labeler lost pixels of it (capacity)
  kRejectedBorder,        // cut by the frame: its centroid is biased
  kRejectedArea,          // not the size of a fiducial of the chosen square
  kRejectedShape,         // the right size but too elongated for a perimeter fiducial
  kRejectedPosition,      // the right size and shape, but not where a fiducial should be
  kRejectedAmbiguous,     // a corner marker at both orientations' positions
  kRejectedWeakerCentre,  // centre-like, but another centre had more support
};

struct FidModel {
  std::int32_t perimeter_distance_sides = 7;  // 1.75 inch / (1/4 inch)
  // Eigenvalue ratios (major / minor variance) of the shapes: 4 for the 2:1 centre, 1 for squares.
  q24_8 centre_ratio_min = q24_8::from_int(2), centre_ratio_max = q24_8::from_int(10);
  q24_8 perimeter_ratio_max = q24_8::from_int(2);
  // Area of a perimeter fiducial relative to s^2 (perspective and threshold change it).
  q24_8 area_ratio_min = q24_8::from_double(0.35), area_ratio_max = q24_8::from_double(2.5);
  q24_8 search_radius_fraction = q24_8::from_double(0.35);  // of the 7s distance
};

struct IdentifiedFiducial {
  std::uint8_t id = 0;           // Doty's p1..p6
  std::uint16_t blob_index = 0;  // into the blob span
  q16_16 x_px, y_px;
};

struct FidResult {
  std::array<IdentifiedFiducial, 6> fiducials{};  // the first `count`, in id order
  std::uint8_t count = 0;
  // The square's axes in the image: unit vectors (image x right, y down), q16_16.
  q16_16 x_axis_x, x_axis_y, y_axis_x, y_axis_y;
  q16_16 fiducial_side_px;  // s; n = 4 s pixels per inch
  bool orientation_from_marker = false;
  std::uint16_t centre_blob = 0;
};

FidStatus identify_fiducials(const FidModel& model, std::span<const Blob> blobs, std::span<FidVerdict> verdicts,
                             FidResult& result) noexcept;

}  // namespace kincal::core

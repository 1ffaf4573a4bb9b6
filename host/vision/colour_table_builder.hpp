// Builds the platform's colour-class table (firmware/core/colour_class.hpp) from sample pixels:
// pixels of the beacon under the rig's lighting (positives) and, optionally, of the scene
// around it (negatives).
//
// Model: the positives, converted to the table's colour space (RGB565 as the camera packs it,
// or BT.601 YUV), in cell units (16 levels per channel), get a mean and a covariance (plus a
// quarter cell squared on the diagonal for the quantization). The class is the ellipsoid
// d < max_distance of the cell centre's Mahalanobis distance d. Its core, d <= max_distance - 1,
// scores 255; from there the score falls linearly to 0 at max_distance (every cell of the class
// keeps at least threshold + 1, the threshold is kColourTableThreshold). A cell that holds at
// least as many negatives as positives is cleared: the scene's colours never count.
// Why flat, not 255 exp(-d^2 / 2) (issue #22): the scores weight the centroid, and the samples'
// spread is mostly the beacon's brightness over the image. A score peaked at the mean colour
// made the disc's weights follow the lighting across it: vignetting tilted them toward the image
// centre, by a different amount in the two cameras of a stereo pair (the beacon sits a disparity
// apart), and biased the triangulated depth (tests/bench/stereo_colour_bias_bench.cpp). On
// that bench's frames at k1 = 0 (800 centroids, a one-off run) the centroid error against
// column was -1.1e-4 px/px (+-0.3e-4) with the peaked score, -0.2e-4 (+-0.2e-4) flat, and the
// centroid's spread 1.6 times smaller. The ramp keeps sub-pixel weights on the
// rim, whose pixels mix the beacon with the background (all 255, a binary class: -0.3e-4 px/px,
// spread 1.2 times the ramp's).
// The rim, with negatives given: a pixel on the beacon's edge mixes the beacon's colour with the
// scene's behind it, c = a beacon + (1 - a) partner. Each colour the scene shows often (a cell
// holding at least one in a thousand of the negatives, and 2) is a partner; a cell near the way
// from a partner to the positives' mean (the nearest partner's way, Mahalanobis distance below
// max_distance with the covariance a^2 Sigma + (1 - a)^2 (a cell)^2 + the quantization) scores
// 255 a, its share of the beacon, when a is at least kMinRimShare (background noise must not
// join the class) -- inside the ellipsoid too, since samples of a beacon hold its rim pixels.
// The centroid then weighs each rim pixel by the beacon's share in it, as the grey path weighs
// intensity. Without it a rim pixel left the class a quarter of the way to the background: the
// weights were nearly binary and the centroid locked to the pixel grid. One camera's centroid
// against the true projection on stereo_colour_bias_bench's frames (284 points, k1 = 0, a one-off
// run): the per-pair disparity error's spread 0.080 -> 0.049 px rendered without noise
// (the grey path: 0.026), 0.096 -> 0.056 px with the bench's noise and vignetting (grey: 0.059);
// tests/host/vision: a disc's centroid over 25 sub-pixel positions, 0.124 -> 0.020 px RMS.
// Errors: std::runtime_error (fewer than 8 positive samples; a degenerate covariance is
// regularized, not an error).
#pragma once

#include <opencv2/core.hpp>

#include <vector>

#include "firmware/core/colour_class.hpp"

namespace kincal::vision {

inline constexpr std::uint8_t kColourTableThreshold = 3;
inline constexpr double kMinRimShare = 0.25;  // the least share of the beacon a rim cell scores (see above)

struct ColourTableSamples {
  std::vector<cv::Vec3b> positive_bgr, negative_bgr;
};

core::ColourClassTable build_colour_table(const ColourTableSamples& samples, core::ColourSpace space,
                                          double max_distance = 3.0);

// The cell (c0, c1, c2), each 0..15, of a BGR pixel in the table's colour space.
void colour_cell(const cv::Vec3b& bgr, core::ColourSpace space, int cell[3]);

}  // namespace kincal::vision

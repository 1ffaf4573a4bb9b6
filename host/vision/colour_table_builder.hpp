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
// Errors: std::runtime_error (fewer than 8 positive samples; a degenerate covariance is
// regularized, not an error).
#pragma once

#include <opencv2/core.hpp>

#include <vector>

#include "firmware/core/colour_class.hpp"

namespace kincal::vision {

inline constexpr std::uint8_t kColourTableThreshold = 3;

struct ColourTableSamples {
  std::vector<cv::Vec3b> positive_bgr, negative_bgr;
};

core::ColourClassTable build_colour_table(const ColourTableSamples& samples, core::ColourSpace space,
                                          double max_distance = 3.0);

// The cell (c0, c1, c2), each 0..15, of a BGR pixel in the table's colour space.
void colour_cell(const cv::Vec3b& bgr, core::ColourSpace space, int cell[3]);

}  // namespace kincal::vision

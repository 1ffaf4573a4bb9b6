// Builds the platform's colour-class table (firmware/core/colour_class.hpp) from sample pixels:
// pixels of the beacon under the rig's lighting (positives) and, optionally, of the scene
// around it (negatives).
//
// Model: the positives, converted to the table's colour space (RGB565 as the camera packs it,
// or BT.601 YUV), in cell units (16 levels per channel), get a mean and a covariance (plus a
// quarter cell squared on the diagonal for the quantization). A cell scores
// 255 exp(-d^2 / 2) of its centre's Mahalanobis distance d; scores of cells beyond
// d = max_distance are 0, and the table's threshold is the score at max_distance, so the class
// is the ellipsoid d < max_distance with soft weights falling off toward its rim. A cell that
// holds at least as many negatives as positives is cleared: the scene's colours never count.
//
// Errors: std::runtime_error (fewer than 8 positive samples; a degenerate covariance is
// regularized, not an error).
#pragma once

#include <opencv2/core.hpp>

#include <vector>

#include "firmware/core/colour_class.hpp"

namespace kincal::vision {

struct ColourTableSamples {
  std::vector<cv::Vec3b> positive_bgr, negative_bgr;
};

core::ColourClassTable build_colour_table(const ColourTableSamples& samples, core::ColourSpace space,
                                          double max_distance = 3.0);

// The cell (c0, c1, c2), each 0..15, of a BGR pixel in the table's colour space.
void colour_cell(const cv::Vec3b& bgr, core::ColourSpace space, int cell[3]);

}  // namespace kincal::vision

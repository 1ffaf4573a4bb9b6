// JSON for the labeler's blobs and frame summary (nlohmann::ordered_json), as `kincal blobs` prints
// them. Units: pixels (px), square pixels (px2), grey levels (dn), radians (rad); pixel (0, 0)
// is the centre of the top-left pixel, y grows downward.
//
// Per blob: x, y (the best centroid: refined when "refined" is true), area, bbox {x_min,
// y_min, x_max, y_max} (inclusive), weighted {x, y}, binary {x, y}, moments {mu20, mu11, mu02
// (weighted central, px2), orientation_rad (major axis from +x toward +y), elongation (ratio
// of the axes' standard deviations, >= 1)}, background_dn, weight_sum_dn, and the flags
// touches_border, incomplete, refined, weight_invalid, background_default.
#pragma once

#include <nlohmann/json.hpp>

#include "firmware/core/blob_labeler.hpp"

namespace kincal::vision {

nlohmann::ordered_json blob_to_json(const core::Blob& blob);
nlohmann::ordered_json summary_to_json(const core::FrameSummary& summary);

// Orientation (rad) and elongation of a blob's second moments.
void blob_shape(const core::Blob& blob, double& orientation_rad, double& elongation);

}  // namespace kincal::vision

#include "host/vision/blob_json.hpp"

#include <cmath>
#include <limits>

namespace kincal::vision {

void blob_shape(const core::Blob& blob, double& orientation_rad, double& elongation) {
  const double a = blob.mu20_px2.to_double(), b = blob.mu11_px2.to_double(), c = blob.mu02_px2.to_double();
  orientation_rad = 0.5 * std::atan2(2 * b, a - c);
  const double mean = 0.5 * (a + c), half = std::sqrt(0.25 * (a - c) * (a - c) + b * b);
  const double major = mean + half, minor = mean - half;
  elongation = minor > 0 ? std::sqrt(major / minor) : (major > 0 ? std::numeric_limits<double>::infinity() : 1.0);
}

nlohmann::ordered_json blob_to_json(const core::Blob& blob) {
  double orientation = 0, elongation = 1;
  blob_shape(blob, orientation, elongation);
  nlohmann::ordered_json j;
  j["x"] = blob.x_px.to_double();
  j["y"] = blob.y_px.to_double();
  j["area"] = blob.area_px;
  j["bbox"] = {{"x_min", blob.x_min_px}, {"y_min", blob.y_min_px}, {"x_max", blob.x_max_px}, {"y_max", blob.y_max_px}};
  j["weighted"] = {{"x", blob.weighted_x_px.to_double()}, {"y", blob.weighted_y_px.to_double()}};
  j["binary"] = {{"x", blob.binary_x_px.to_double()}, {"y", blob.binary_y_px.to_double()}};
  j["moments"] = {
      {"mu20", blob.mu20_px2.to_double()},
      {"mu11", blob.mu11_px2.to_double()},
      {"mu02", blob.mu02_px2.to_double()},
      {"orientation_rad", orientation},
      {"elongation", std::isfinite(elongation) ? nlohmann::ordered_json(elongation) : nlohmann::ordered_json(nullptr)}};
  j["background_dn"] = blob.background_dn.to_double();
  j["weight_sum_dn"] = blob.weight_sum_dn;
  j["touches_border"] = (blob.flags & core::kTouchesBorder) != 0;
  j["incomplete"] = (blob.flags & core::kIncomplete) != 0;
  j["refined"] = (blob.flags & core::kRefined) != 0;
  j["weight_invalid"] = (blob.flags & core::kWeightInvalid) != 0;
  j["background_default"] = (blob.flags & core::kBackgroundDefault) != 0;
  return j;
}

nlohmann::ordered_json summary_to_json(const core::FrameSummary& s) {
  return {{"width", s.width_px},
          {"height", s.rows},
          {"blobs", s.blobs},
          {"blobs_dropped_output_full", s.blobs_dropped_output_full},
          {"blobs_dropped_small", s.blobs_dropped_small},
          {"runs_untracked", s.runs_untracked},
          {"refinements", s.refinements},
          {"refinements_skipped", s.refinements_skipped}};
}

}  // namespace kincal::vision

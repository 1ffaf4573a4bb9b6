#include "host/vision/colour_table_builder.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "host/vision/image_labeling.hpp"

namespace kincal::vision {

void colour_cell(const cv::Vec3b& bgr, core::ColourSpace space, int cell[3]) {
  std::size_t index = 0;
  if (space == core::ColourSpace::kRgb565) {
    index = core::rgb565_cell(bgr_to_rgb565(bgr[0], bgr[1], bgr[2]));
  } else {
    std::uint8_t y, u, v;
    bgr_to_yuv(bgr[0], bgr[1], bgr[2], y, u, v);
    index = core::yuv_cell(y, u, v);
  }
  cell[0] = static_cast<int>(index >> 8);
  cell[1] = static_cast<int>((index >> 4) & 0xF);
  cell[2] = static_cast<int>(index & 0xF);
}

namespace {

cv::Matx31d cell_centre(int c0, int c1, int c2) { return {c0 + 0.5, c1 + 0.5, c2 + 0.5}; }

double mahalanobis(const cv::Matx31d& d, const cv::Matx33d& covariance) {
  return std::sqrt((d.t() * covariance.inv(cv::DECOMP_CHOLESKY) * d)(0, 0));
}

}  // namespace

core::ColourClassTable build_colour_table(const ColourTableSamples& samples, core::ColourSpace space,
                                          double max_distance) {
  if (samples.positive_bgr.size() < 8) throw std::runtime_error("colour table: fewer than 8 positive samples");
  std::vector<int> positives(core::kColourCells, 0), negatives(core::kColourCells, 0);
  cv::Matx31d mean = cv::Matx31d::zeros();
  std::vector<cv::Matx31d> points;
  for (const cv::Vec3b& p : samples.positive_bgr) {
    int c[3];
    colour_cell(p, space, c);
    ++positives[static_cast<std::size_t>(c[0] << 8 | c[1] << 4 | c[2])];
    points.push_back(cell_centre(c[0], c[1], c[2]));
    mean += points.back();
  }
  mean *= 1.0 / static_cast<double>(points.size());
  const cv::Matx33d quantization = cv::Matx33d::eye() * (0.25 * 0.25);
  cv::Matx33d cov = quantization;
  for (const cv::Matx31d& q : points) cov += (q - mean) * (q - mean).t() * (1.0 / static_cast<double>(points.size()));
  for (const cv::Vec3b& p : samples.negative_bgr) {
    int c[3];
    colour_cell(p, space, c);
    ++negatives[static_cast<std::size_t>(c[0] << 8 | c[1] << 4 | c[2])];
  }
  // The rim's partners: the scene's colours seen often enough to stand behind the beacon.
  const int partner_count = std::max(2, static_cast<int>(samples.negative_bgr.size() / 1000));
  std::vector<cv::Matx31d> partners;
  for (std::size_t index = 0; index < negatives.size(); ++index) {
    if (negatives[index] >= partner_count)
      partners.push_back(cell_centre(static_cast<int>(index >> 8), static_cast<int>((index >> 4) & 0xF),
                                     static_cast<int>(index & 0xF)));
  }
  const cv::Matx33d partner_spread = cv::Matx33d::eye();  // a partner cell's own spread: a cell
  core::ColourClassTable table;
  table.space = space;
  table.threshold = kColourTableThreshold;
  for (int c0 = 0; c0 < 16; ++c0)
    for (int c1 = 0; c1 < 16; ++c1)
      for (int c2 = 0; c2 < 16; ++c2) {
        const auto index = static_cast<std::size_t>(c0 << 8 | c1 << 4 | c2);
        const cv::Matx31d cell = cell_centre(c0, c1, c2);
        const double distance = mahalanobis(cell - mean, cov);
        double score = distance < max_distance ? 255.0 * std::min(1.0, max_distance - distance) : 0.0;
        // A rim pixel: the beacon's share a of it along the way to the nearest partner colour.
        double rim_distance = max_distance, share = 0.0;
        for (const cv::Matx31d& partner : partners) {
          const cv::Matx31d axis = mean - partner;
          const double a = std::clamp((cell - partner).dot(axis) / axis.dot(axis), 0.0, 1.0);
          const double d =
              mahalanobis(cell - (partner + a * axis), a * a * cov + (1 - a) * (1 - a) * partner_spread + quantization);
          if (d < rim_distance) {
            rim_distance = d;
            share = a;
          }
        }
        // The rim's score holds inside the ellipsoid too: the samples of a beacon hold its rim pixels.
        if (share >= kMinRimShare) score = 255.0 * share;
        if (negatives[index] > 0 && negatives[index] >= positives[index]) score = 0;
        // Inside the ellipsoid every cell is above the threshold, however small its weight.
        table.score[index] =
            static_cast<std::uint8_t>(score > 0 ? std::max<long>(std::lround(score), table.threshold + 1L) : 0);
      }
  return table;
}

}  // namespace kincal::vision

// Centroid accuracy of the streaming labeler on synthetic Gaussian spots against the
// Cramér–Rao bound of the same spot and noise.
//
// Spots: pixel-integrated 2-D Gaussians (sigma 1, 1.5, 2 px), amplitude 160 DN on a 40 DN
// background, white Gaussian noise sigma_n 2, 4, 8, 16 DN (peak SNR about 80 down to 10 — the
// pixel-integrated peak is lower), rounded to 8 bits. Sub-pixel phases on a 4x4 grid, 1000 noise
// draws each. The bound: the Fisher matrix of (x0, y0, amplitude, background, sigma) for the
// pixel-integrated model, inverted, with noise variance sigma_n^2 + 1/12 (the rounding).
//
// Figures: the worst over the 12 (sigma, SNR) conditions of RMS error / CRLB for the labeler's
// best centroid (refined) and, for comparison, its first-pass weighted and binary centroids;
// the worst |bias| (mean error at one sub-pixel phase, over its noise draws; the standard error
// of that mean is printed beside it) and the worst noise-free error.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include "firmware/core/blob_labeler.hpp"

using namespace kincal::core;

namespace {

constexpr int kSize = 32;
constexpr double kAmplitude = 160, kBackground = 40;
constexpr int kPhases = 4, kDraws = 1000;

double pixel_fraction(int i, double centre, double sigma) {
  const double s = std::sqrt(2.0) * sigma;
  return 0.5 * (std::erf((i + 0.5 - centre) / s) - std::erf((i - 0.5 - centre) / s));
}

// Expected pixel values of the model at parameters p = (x0, y0, A, B, sigma); A is the peak of
// the continuous Gaussian (its flux is 2 pi sigma^2 A).
void model(const double p[5], std::vector<double>& mu) {
  mu.resize(kSize * kSize);
  double fx[kSize], fy[kSize];
  for (int i = 0; i < kSize; ++i) {
    fx[i] = pixel_fraction(i, p[0], p[4]);
    fy[i] = pixel_fraction(i, p[1], p[4]);
  }
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x)
      mu[static_cast<std::size_t>(y * kSize + x)] = p[3] + p[2] * 2 * M_PI * p[4] * p[4] * fx[x] * fy[y];
}

// Cramér–Rao bound of x0 and y0 (the mean of the two variances, as a standard deviation).
double crlb_px(double x0, double y0, double sigma, double noise_variance) {
  const double p0[5] = {x0, y0, kAmplitude, kBackground, sigma};
  std::vector<double> d[5], plus, minus;
  for (int k = 0; k < 5; ++k) {
    double pp[5], pm[5];
    for (int j = 0; j < 5; ++j) pp[j] = pm[j] = p0[j];
    const double h = 1e-4 * (k < 2 || k == 4 ? 1.0 : 100.0);
    pp[k] += h;
    pm[k] -= h;
    model(pp, plus);
    model(pm, minus);
    d[k].resize(plus.size());
    for (std::size_t i = 0; i < plus.size(); ++i) d[k][i] = (plus[i] - minus[i]) / (2 * h);
  }
  double f[5][5];
  for (int a = 0; a < 5; ++a)
    for (int b = 0; b < 5; ++b) {
      double s = 0;
      for (std::size_t i = 0; i < d[a].size(); ++i) s += d[a][i] * d[b][i];
      f[a][b] = s / noise_variance;
    }
  // Invert the 5x5 Fisher matrix (Gauss–Jordan; it is symmetric positive definite).
  double inv[5][5] = {};
  for (int i = 0; i < 5; ++i) inv[i][i] = 1;
  for (int c = 0; c < 5; ++c) {
    const double pivot = f[c][c];
    for (int j = 0; j < 5; ++j) {
      f[c][j] /= pivot;
      inv[c][j] /= pivot;
    }
    for (int r = 0; r < 5; ++r) {
      if (r == c) continue;
      const double factor = f[r][c];
      for (int j = 0; j < 5; ++j) {
        f[r][j] -= factor * f[c][j];
        inv[r][j] -= factor * inv[c][j];
      }
    }
  }
  return std::sqrt(0.5 * (inv[0][0] + inv[1][1]));
}

struct Estimates {
  double x[3], y[3];  // best, weighted, binary
  bool found = false, refined = false;
};

Estimates measure(const std::vector<std::uint8_t>& image, std::uint8_t threshold) {
  static LabelerBuffers<kSize, 32, 13, 8> buffers;
  static Blob blobs[64];
  BlobLabeler labeler(buffers.memory());
  LabelerConfig config;
  config.threshold = threshold;
  config.min_area_px = 3;
  Estimates e;
  if (labeler.begin_frame(config, blobs) != LabelStatus::kOk) return e;
  for (int y = 0; y < kSize; ++y) {
    if (labeler.push_row({image.data() + y * kSize, kSize}) != LabelStatus::kOk) return e;
  }
  FrameSummary summary;
  if (labeler.end_frame(summary) != LabelStatus::kOk || summary.blobs == 0) return e;
  const Blob* best = &blobs[0];  // the spot: the blob with the largest weight (noise blobs are tiny)
  for (std::uint32_t i = 1; i < summary.blobs; ++i)
    if (blobs[i].weight_sum_dn > best->weight_sum_dn) best = &blobs[i];
  e.found = true;
  e.refined = (best->flags & kRefined) != 0;
  e.x[0] = best->x_px.to_double();
  e.y[0] = best->y_px.to_double();
  e.x[1] = best->weighted_x_px.to_double();
  e.y[1] = best->weighted_y_px.to_double();
  e.x[2] = best->binary_x_px.to_double();
  e.y[2] = best->binary_y_px.to_double();
  return e;
}

std::vector<std::uint8_t> render(const std::vector<double>& mu, double noise_sigma, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, noise_sigma);
  std::vector<std::uint8_t> img(mu.size());
  for (std::size_t i = 0; i < mu.size(); ++i) {
    const double v = std::nearbyint(mu[i] + (noise_sigma > 0 ? noise(rng) : 0.0));
    img[i] = static_cast<std::uint8_t>(v < 0 ? 0 : (v > 255 ? 255 : v));
  }
  return img;
}

}  // namespace

int main() {
  const double sigmas[] = {1.0, 1.5, 2.0};
  const double noises[] = {2, 4, 8, 16};
  const char* names[] = {"refined", "weighted", "binary"};
  const auto threshold = static_cast<std::uint8_t>(kBackground + kAmplitude / 3);
  std::mt19937_64 rng(20261121);
  double worst_ratio[3] = {0, 0, 0};
  double worst_bias = 0, worst_bias_se = 0, worst_noise_free = 0;
  int missed = 0, unrefined = 0, trials = 0;
  std::vector<double> mu;

  for (const double sigma : sigmas) {
    for (const double noise : noises) {
      double sq[3] = {0, 0, 0}, crlb_sq = 0;
      int n = 0;
      for (int py = 0; py < kPhases; ++py) {
        for (int px = 0; px < kPhases; ++px) {
          const double x0 = kSize / 2 + (px + 0.5) / kPhases - 0.5, y0 = kSize / 2 + (py + 0.5) / kPhases - 0.5;
          const double p[5] = {x0, y0, kAmplitude, kBackground, sigma};
          model(p, mu);
          const double bound = crlb_px(x0, y0, sigma, noise * noise + 1.0 / 12);
          const Estimates clean = measure(render(mu, 0, rng), threshold);
          if (clean.found) {
            worst_noise_free =
                std::fmax(worst_noise_free, std::fmax(std::fabs(clean.x[0] - x0), std::fabs(clean.y[0] - y0)));
          }
          double mean_x = 0, mean_y = 0, spread = 0;
          int m = 0;
          for (int draw = 0; draw < kDraws; ++draw) {
            const Estimates e = measure(render(mu, noise, rng), threshold);
            ++trials;
            if (!e.found) {
              ++missed;
              continue;
            }
            unrefined += e.refined ? 0 : 1;
            for (int k = 0; k < 3; ++k) sq[k] += 0.5 * ((e.x[k] - x0) * (e.x[k] - x0) + (e.y[k] - y0) * (e.y[k] - y0));
            mean_x += e.x[0] - x0;
            mean_y += e.y[0] - y0;
            spread += 0.5 * ((e.x[0] - x0) * (e.x[0] - x0) + (e.y[0] - y0) * (e.y[0] - y0));
            crlb_sq += bound * bound;
            ++m;
            ++n;
          }
          mean_x /= m;
          mean_y /= m;
          const double bias = std::fmax(std::fabs(mean_x), std::fabs(mean_y));
          if (bias > worst_bias) {
            worst_bias = bias;
            worst_bias_se = std::sqrt(spread / m / m);
          }
        }
      }
      const double crlb = std::sqrt(crlb_sq / n);
      std::printf(
          "sigma %.1f px, noise %4.1f DN, peak SNR %5.1f: CRLB %.4f px; RMS/CRLB", sigma, noise,
          kAmplitude * 2 * M_PI * sigma * sigma * pixel_fraction(0, 0, sigma) * pixel_fraction(0, 0, sigma) / noise,
          crlb);
      for (int k = 0; k < 3; ++k) {
        const double ratio = std::sqrt(sq[k] / n) / crlb;
        worst_ratio[k] = std::fmax(worst_ratio[k], ratio);
        std::printf(" %s %.3f", names[k], ratio);
      }
      std::printf("\n");
    }
  }
  std::printf("trials %d, spot not found %d, not refined %d; worst bias %.4f px (standard error %.4f px)\n", trials,
              missed, unrefined, worst_bias, worst_bias_se);
  std::printf("FIGURE centroid_rms_over_crlb %.3f ratio\n", worst_ratio[0]);
  std::printf("FIGURE centroid_weighted_rms_over_crlb %.3f ratio\n", worst_ratio[1]);
  std::printf("FIGURE centroid_binary_rms_over_crlb %.3f ratio\n", worst_ratio[2]);
  std::printf("FIGURE centroid_bias_px %.4f px\n", worst_bias);
  std::printf("FIGURE centroid_noise_free_error_px %.4f px\n", worst_noise_free);
  return missed == 0 ? 0 : 1;
}

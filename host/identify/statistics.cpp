#include "host/identify/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace kincal::identify {

namespace {

constexpr double kEpsilon = 1e-15;
constexpr int kIterations = 500;

// Regularized lower incomplete gamma P(a, x).
double gamma_p(double a, double x) {
  if (x <= 0.0) return 0.0;
  const double log_prefix = a * std::log(x) - x - std::lgamma(a);
  if (x < a + 1.0) {  // series
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < kIterations; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::abs(term) < std::abs(sum) * kEpsilon) break;
    }
    return sum * std::exp(log_prefix);
  }
  // Continued fraction for Q(a, x) (modified Lentz).
  const double tiny = std::numeric_limits<double>::min() / kEpsilon;
  double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int i = 1; i < kIterations; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < kEpsilon) break;
  }
  return 1.0 - std::exp(log_prefix) * h;
}

double beta_continued_fraction(double a, double b, double x) {
  const double tiny = std::numeric_limits<double>::min() / kEpsilon;
  const double qab = a + b, qap = a + 1.0, qam = a - 1.0;
  double c = 1.0, d = 1.0 - qab * x / qap;
  if (std::abs(d) < tiny) d = tiny;
  d = 1.0 / d;
  double h = d;
  for (int m = 1; m < kIterations; ++m) {
    const int m2 = 2 * m;
    double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
    d = 1.0 + aa * d;
    if (std::abs(d) < tiny) d = tiny;
    c = 1.0 + aa / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    h *= d * c;
    aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
    d = 1.0 + aa * d;
    if (std::abs(d) < tiny) d = tiny;
    c = 1.0 + aa / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < kEpsilon) break;
  }
  return h;
}

// Regularized incomplete beta I_x(a, b).
double beta_i(double a, double b, double x) {
  if (x <= 0.0) return 0.0;
  if (x >= 1.0) return 1.0;
  const double front =
      std::exp(std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x));
  if (x < (a + 1.0) / (a + b + 2.0)) return front * beta_continued_fraction(a, b, x) / a;
  return 1.0 - front * beta_continued_fraction(b, a, 1.0 - x) / b;
}

}  // namespace

double chi_square_cdf(double x, double k) { return gamma_p(0.5 * k, 0.5 * x); }

double chi_square_quantile(double p, double k) {
  if (!(p > 0.0 && p < 1.0) || !(k > 0.0)) throw std::invalid_argument("chi_square_quantile: p in (0, 1), k > 0");
  double lo = 0.0, hi = std::max(1.0, k);
  while (chi_square_cdf(hi, k) < p) hi *= 2.0;
  for (int i = 0; i < 200 && hi - lo > 1e-13 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (chi_square_cdf(mid, k) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double fisher_cdf(double x, double d1, double d2) {
  if (x <= 0.0) return 0.0;
  return beta_i(0.5 * d1, 0.5 * d2, d1 * x / (d1 * x + d2));
}

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  if (values.size() % 2 == 1) return *mid;
  return 0.5 * (*mid + *std::max_element(values.begin(), mid));
}

double paired_t(const std::vector<double>& a2, const std::vector<double>& b2) {
  std::vector<double> d;
  for (std::size_t i = 0; i < a2.size(); ++i) d.push_back(std::sqrt(a2[i]) - std::sqrt(b2[i]));
  return paired_t(d);
}

double paired_t(const std::vector<double>& d) {
  const auto n = static_cast<double>(d.size());
  double mean = 0.0, variance = 0.0;
  for (const double x : d) mean += x / n;
  for (const double x : d) variance += (x - mean) * (x - mean) / (n - 1.0);
  return variance > 0.0 ? mean / std::sqrt(variance / n) : 0.0;
}

}  // namespace kincal::identify

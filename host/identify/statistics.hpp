// The few distribution functions the identification's tests and thresholds need: chi-square
// and Fisher F, by the regularized incomplete gamma and beta functions (series and Lentz
// continued fractions, relative accuracy about 1e-12 over the ranges used here; checked against
// tabulated quantiles in tests/host/identify), and a robust scale.
#pragma once

#include <vector>

namespace kincal::identify {

// P(X <= x) for X ~ chi-square with k degrees of freedom (k > 0).
double chi_square_cdf(double x, double k);
// The x with chi_square_cdf(x, k) = p, 0 < p < 1.
double chi_square_quantile(double p, double k);
// P(X <= x) for X ~ F(d1, d2).
double fisher_cdf(double x, double d1, double d2);

// Median of the values (copied; empty -> 0).
double median(std::vector<double> values);

}  // namespace kincal::identify

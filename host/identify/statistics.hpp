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

// The paired t statistic of the position errors' differences sqrt(a2_i) - sqrt(b2_i), from
// squared errors of the same rows (a2.size() == b2.size() >= 2): their mean over its standard
// error, 0 when they are all equal. Negative: `a` predicts better. Errors, not squared errors: a
// blunder in a held-out row moves its own squared error by 2 b delta, its size times the models'
// difference, and would drown what the models do to the other rows. What the rejection gate
// (identify.hpp) and model selection (model_selection.hpp) compare models by.
double paired_t(const std::vector<double>& a2, const std::vector<double>& b2);
// The t statistic of paired differences (size >= 2): their mean over its standard error, 0 when
// they are all equal.
double paired_t(const std::vector<double>& differences);

}  // namespace kincal::identify

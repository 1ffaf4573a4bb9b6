#include "host/identify/identifiability.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <Eigen/SVD>

namespace kincal::identify {

namespace {

// Jacobi's SVD, after the column-pivoting QR the rank test below already instantiates: as accurate
// as an SVD gets, and on these tall Jacobians of a few dozen columns its cost is the QR's. (BDCSVD,
// used before, took most of this file's compile time and gains only on wide matrices.)
Eigen::VectorXd singular_values(const Eigen::MatrixXd& m) {
  return Eigen::JacobiSVD<Eigen::MatrixXd>(m).singularValues();
}

}  // namespace

Identifiability analyze_identifiability(const Eigen::MatrixXd& jacobian, const ParameterIds& candidates,
                                        double tolerance) {
  Identifiability out;
  const Eigen::Index rows = jacobian.rows();
  Eigen::MatrixXd scaled = jacobian;
  // A column that is zero up to rounding (1e-10 of the largest) is a parameter without effect.
  std::vector<bool> zero(candidates.size(), false);
  double largest = 0.0;
  for (Eigen::Index c = 0; c < scaled.cols(); ++c) largest = std::max(largest, scaled.col(c).norm());
  for (Eigen::Index c = 0; c < scaled.cols(); ++c) {
    const double norm = scaled.col(c).norm();
    zero[static_cast<std::size_t>(c)] = !(norm > 1e-10 * largest);
    if (zero[static_cast<std::size_t>(c)]) {
      scaled.col(c).setZero();
    } else {
      scaled.col(c) /= norm;
    }
  }
  Eigen::MatrixXd basis(rows, 0);
  std::vector<Eigen::Index> kept;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    const auto c = static_cast<Eigen::Index>(k);
    if (zero[k]) {
      out.held_fixed.push_back({candidates[k], "does not change the measured quantities"});
      continue;
    }
    Eigen::VectorXd r = scaled.col(c);
    for (int pass = 0; pass < 2 && basis.cols() > 0; ++pass) r -= basis * (basis.transpose() * r);
    const double residual = r.norm();
    if (residual > tolerance) {
      basis.conservativeResize(Eigen::NoChange, basis.cols() + 1);
      basis.col(basis.cols() - 1) = r / residual;
      kept.push_back(c);
      out.identified.push_back(candidates[k]);
      continue;
    }
    // Name what it is a combination of: the largest coefficients in the kept columns.
    Eigen::MatrixXd a(rows, static_cast<Eigen::Index>(kept.size()));
    for (std::size_t i = 0; i < kept.size(); ++i) a.col(static_cast<Eigen::Index>(i)) = scaled.col(kept[i]);
    const Eigen::VectorXd coefficients = a.colPivHouseholderQr().solve(scaled.col(c));
    std::vector<std::size_t> order(kept.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
      return std::abs(coefficients(static_cast<Eigen::Index>(x))) >
             std::abs(coefficients(static_cast<Eigen::Index>(y)));
    });
    std::string names;
    for (std::size_t i = 0; i < order.size() && i < 3; ++i) {
      if (std::abs(coefficients(static_cast<Eigen::Index>(order[i]))) < 1e-3) break;
      names += (names.empty() ? "" : ", ") + model::parameter_name(out.identified[order[i]]);
    }
    out.held_fixed.push_back(
        {candidates[k], "not separable from " + (names.empty() ? std::string("the others") : names)});
  }
  if (scaled.cols() > 0 && rows > 0) {
    out.singular_values = singular_values(scaled);
    const double top = out.singular_values(0);
    for (Eigen::Index i = 0; i < out.singular_values.size(); ++i)
      out.rank += out.singular_values(i) > top * tolerance ? 1 : 0;
  }
  if (!kept.empty()) {
    Eigen::MatrixXd a(rows, static_cast<Eigen::Index>(kept.size()));
    for (std::size_t i = 0; i < kept.size(); ++i) a.col(static_cast<Eigen::Index>(i)) = scaled.col(kept[i]);
    const Eigen::VectorXd s = singular_values(a);
    out.condition = s(0) / s(s.size() - 1);
  }
  return out;
}

}  // namespace kincal::identify

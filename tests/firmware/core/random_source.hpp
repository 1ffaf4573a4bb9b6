// Deterministic random inputs for the geometry tests: the same sequence natively and on the
// M4 (splitmix64, as in fixed_point_test.cpp), so a failure reproduces on both.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>

#include "tests/firmware/core/splitmix64.hpp"

namespace kincal::test {

class RandomSource {
 public:
  explicit RandomSource(std::uint64_t seed) : bits_(seed) {}

  std::uint64_t next() { return bits_.next(); }
  // Uniform in [0, 1) with 53 random bits.
  double unit() { return bits_.unit(); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  double sign() { return (next() & 1u) != 0 ? 1.0 : -1.0; }
  int index(int count) { return static_cast<int>(next() % static_cast<std::uint64_t>(count)); }
  Eigen::Vector3d unit_vector() {
    for (;;) {
      const Eigen::Vector3d v(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
      const double n = v.norm();
      if (n > 0.1 && n <= 1.0) return v / n;
    }
  }
  // Uniformly distributed rotation (normalized random quaternion).
  Eigen::Matrix3d rotation() {
    for (;;) {
      const Eigen::Vector4d q(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
      const double n = q.norm();
      if (n > 0.1 && n <= 1.0) return Eigen::Quaterniond(q(0), q(1), q(2), q(3)).normalized().toRotationMatrix();
    }
  }
  Eigen::Matrix3d rotation_up_to(double max_angle_rad) {
    return Eigen::AngleAxisd(uniform(0, max_angle_rad), unit_vector()).toRotationMatrix();
  }

 private:
  Splitmix64 bits_;
};

}  // namespace kincal::test

// Deterministic random inputs for the geometry tests: the same sequence natively and on the
// M4 (splitmix64, as in fixed_point_test.cpp), so a failure reproduces on both.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>

namespace kincal::test {

class RandomSource {
 public:
  explicit RandomSource(std::uint64_t seed) : state_(seed) {}

  std::uint64_t next() {
    state_ += 0x9E3779B97F4A7C15u;
    std::uint64_t z = state_;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9u;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBu;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1) with 53 random bits.
  double unit() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
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
  std::uint64_t state_;
};

}  // namespace kincal::test

// Kapucu & Baysec's rig as the benchmarks simulate it (tests/bench/kapucu_bench.cpp says where
// each number comes from): a parallel stereo pair 4.54 m from a Stanford-type RRP arm, f = 1 cm,
// 11 um pixels, 12.6 cm baseline; the beacon's pixel centroids get Gaussian noise of sigma_px in u
// and v in both images and are triangulated, with the first-order covariance of the point (depth
// about 18 cm per pixel of disparity) recorded in the dataset. 10 readings per joint, one joint
// swept at a time around kHome.
#pragma once

#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "host/model/dataset.hpp"
#include "host/model/robot_model.hpp"

namespace kincal::kapucu {

constexpr double kFocal = 0.01, kPixel = 11e-6, kBaseline = 0.126;
constexpr double kDeg = std::numbers::pi / 180.0;
inline const std::vector<double> kHome = {0.0, 100 * kDeg, 0.9};

// Triangulated point and its covariance from noisy pixel coordinates.
struct Stereo {
  model::Vector3 point;
  Eigen::Matrix3d covariance;
};

inline Stereo observe(const model::Vector3& p, double sigma_px, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, sigma_px);
  const double ur = kFocal * p.x() / p.z() / kPixel + noise(rng);
  const double vr = kFocal * p.y() / p.z() / kPixel + noise(rng);
  const double ul = kFocal * (p.x() + kBaseline) / p.z() / kPixel + noise(rng);
  const double vl = kFocal * p.y() / p.z() / kPixel + noise(rng);
  const double disparity = ul - ur;
  const double z = kFocal * kBaseline / (disparity * kPixel);
  const double k = kPixel / kFocal;
  Stereo s;
  s.point = model::Vector3(ur * k * z, 0.5 * (vr + vl) * k * z, z);
  // d(x, y, z)/d(ur, vr, ul, vl)
  const double dz_dd = -z / disparity;  // dz/d(disparity)
  Eigen::Matrix<double, 3, 4> j;
  j.row(2) << -dz_dd, 0, dz_dd, 0;
  j.row(0) << ur * k * (-dz_dd) + k * z, 0, ur * k * dz_dd, 0;
  const double v = 0.5 * (vr + vl);
  j.row(1) << v * k * (-dz_dd), 0.5 * k * z, v * k * dz_dd, 0.5 * k * z;
  s.covariance = j * j.transpose() * (sigma_px * sigma_px);
  return s;
}

// 10 readings per joint over 90 deg, 60 deg and 0.7 m, centred on kHome.
inline std::vector<std::vector<double>> sweep_configurations() {
  const double spans[3] = {90 * kDeg, 60 * kDeg, 0.7};
  std::vector<std::vector<double>> qs;
  for (std::size_t j = 0; j < 3; ++j)
    for (int k = 0; k < 10; ++k) {
      std::vector<double> q = kHome;
      q[j] += spans[j] * (k / 9.0 - 0.5);
      qs.push_back(q);
    }
  return qs;
}

// The rig's measurements of `truth` at the configurations.
inline model::Dataset measure(const model::RobotModel& truth, const std::vector<std::vector<double>>& qs,
                              double sigma_px, std::mt19937_64& rng) {
  model::Dataset d;
  d.source = "rig";
  d.joint_count = truth.joint_count();
  d.noise = model::NoiseColumns::covariance;
  int line = 2;
  for (const auto& q : qs) {
    const Stereo s = observe(model::forward_kinematics(truth, q).translation, sigma_px, rng);
    model::Measurement m;
    m.q = q;
    m.position = s.point;
    m.covariance = s.covariance;
    m.line = line++;
    d.rows.push_back(m);
  }
  return d;
}

}  // namespace kincal::kapucu

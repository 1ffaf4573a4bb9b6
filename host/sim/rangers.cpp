#include "host/sim/rangers.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace kincal::sim {

namespace {

void validate(const RangerSpec& s) {
  const auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v)) {
      throw std::invalid_argument(std::string("RangerSpec.") + name + " must be positive and finite");
    }
  };
  positive(s.spacing_m, "spacing_m");
  positive(s.max_range_m, "max_range_m");
  positive(s.max_incidence_rad, "max_incidence_rad");
  if (!std::isfinite(s.origin_z_m)) throw std::invalid_argument("RangerSpec.origin_z_m is not finite");
  if (!(s.sigma_m >= 0) || !std::isfinite(s.sigma_m)) {
    throw std::invalid_argument("RangerSpec.sigma_m must be non-negative and finite");
  }
}

}  // namespace

std::array<Beam, kRangerCount> ranger_beams(const RangerSpec& spec) {
  validate(spec);
  const double h = spec.spacing_m / 2, z = spec.origin_z_m;
  const Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  return {{{{h, 0, z}, axis}, {{0, h, z}, axis}, {{-h, 0, z}, axis}, {{0, -h, z}, axis}}};
}

std::array<double, kRangerCount> simulate_ranges(const RangerSpec& spec, const Eigen::Isometry3d& camera_T_target,
                                                 std::mt19937_64& rng) {
  const std::array<Beam, kRangerCount> beams = ranger_beams(spec);
  if (!camera_T_target.matrix().allFinite())
    throw std::invalid_argument("simulate_ranges: camera_T_target is not finite");
  // The plane n . p = n . c in the camera frame: n the target's z axis, c its origin.
  const Eigen::Vector3d n = camera_T_target.linear().col(2);
  const double n_dot_c = n.dot(camera_T_target.translation());
  std::normal_distribution<double> unit(0.0, 1.0);
  std::array<double, kRangerCount> ranges_m{};
  for (std::size_t i = 0; i < beams.size(); ++i) {
    const double noise_m = spec.sigma_m * unit(rng);
    const double n_dot_d = n.dot(beams[i].direction);
    const double t_m = (n_dot_c - n.dot(beams[i].origin_m)) / n_dot_d;
    const double incidence_rad = std::acos(std::min(1.0, std::abs(n_dot_d)));
    const bool echo =
        std::isfinite(t_m) && t_m >= 0 && t_m <= spec.max_range_m && incidence_rad <= spec.max_incidence_rad;
    ranges_m[i] = echo ? t_m + noise_m : std::numeric_limits<double>::quiet_NaN();
  }
  return ranges_m;
}

}  // namespace kincal::sim

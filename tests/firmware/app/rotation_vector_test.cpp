// Rotation vectors: exp against Eigen's angle-axis in double, and the float log against the
// exact vector, over random rotations up to pi - 1e-3 rad. Natively and on the M4.
#include "firmware/app/rotation_vector.hpp"

#include <doctest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>

using namespace kincal;

TEST_CASE("rotation vectors: exp matches angle-axis, log inverts it within 2e-6 rad") {
  std::uint64_t state = 12345;
  auto uniform = [&state](double lo, double hi) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return lo + (hi - lo) * static_cast<double>(state >> 11) / 9007199254740992.0;
  };
  double worst_log = 0, worst_exp = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Eigen::Vector3d axis(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
    if (axis.norm() < 1e-3) continue;
    axis.normalize();
    // Small angles (the series), ordinary ones, and up to just short of pi.
    const double angle = trial % 4 == 0 ? uniform(0, 2e-4) : uniform(0, 3.14059);
    const Eigen::Vector3d r = axis * angle;
    const Eigen::Matrix3d exact = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    worst_exp = std::fmax(worst_exp, (app::rotation_from_vector<double>(r) - exact).cwiseAbs().maxCoeff());
    const core::Vector3<float> log = app::rotation_vector(exact.cast<float>());
    worst_log = std::fmax(worst_log, (log.cast<double>() - r).norm());
  }
  MESSAGE("worst exp error " << worst_exp << ", worst log error " << worst_log << " rad");
  CHECK(worst_exp < 1e-12);
  CHECK(worst_log < 2e-6);
  // The float exp agrees with the double one to float rounding.
  const core::Vector3<float> r(0.3f, -0.2f, 0.9f);
  CHECK((app::rotation_from_vector(r).cast<double>() - app::rotation_from_vector<double>(r.cast<double>()))
            .cwiseAbs()
            .maxCoeff() < 1e-6);
}

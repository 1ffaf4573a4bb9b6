#include "host/target/doty_square.hpp"

#include <cmath>
#include <stdexcept>

namespace kincal::target {

std::array<FiducialRect, 6> doty_square_fiducials(double fiducial_side_m) {
  if (!(fiducial_side_m > 0) || !std::isfinite(fiducial_side_m))
    throw std::invalid_argument("fiducial side must be positive and finite");
  const double s = fiducial_side_m, far = kDotyFarSides * s;
  const Eigen::Vector2d small(s, s);
  return {{{1, {-far, far}, small},
           {2, {0, far}, small},
           {3, {-far, 0}, small},
           {4, {0, 0}, {s, 2 * s}},
           {5, {far, 0}, small},
           {6, {0, -far}, small}}};
}

}  // namespace kincal::target

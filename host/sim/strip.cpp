#include "host/sim/strip.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace kincal::sim {

namespace {

void validate(const StripSpec& s) {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("StripSpec." + what); };
  if (s.squares < 1 || s.squares > 64) fail("squares " + std::to_string(s.squares) + " outside 1..64");
  if (!(s.square_m > 0) || !std::isfinite(s.square_m)) fail("square_m must be positive and finite");
  if (!(s.fiducial_side_m > 0) || !std::isfinite(s.fiducial_side_m)) {
    fail("fiducial_side_m must be positive and finite");
  }
  // The outermost fiducial edges lie 7.5 s from the centre.
  if (7.5 * s.fiducial_side_m >= s.square_m / 2) fail("fiducial_side_m too large: the fiducials leave the square");
  for (const auto& [value, name] : {std::pair{s.paper, "paper"}, {s.ink, "ink"}, {s.surround, "surround"}}) {
    if (!(value >= 0 && value <= 1)) fail(std::string(name) + " outside [0, 1]");
  }
}

}  // namespace

std::array<FiducialRect, 6> square_fiducials(const StripSpec& spec) {
  validate(spec);
  return target::doty_square_fiducials(spec.fiducial_side_m);
}

PlanarTarget strip_target(const StripSpec& spec) {
  const std::array<FiducialRect, 6> fiducials = square_fiducials(spec);
  return PlanarTarget{[spec, fiducials](double x_m, double y_m) {
    const double half = spec.square_m / 2;
    if (std::abs(y_m) > half || x_m < -half || x_m > (spec.squares - 0.5) * spec.square_m) return spec.surround;
    const double k = std::min(std::floor(x_m / spec.square_m + 0.5), spec.squares - 1.0);
    const double x = x_m - k * spec.square_m;
    for (const FiducialRect& f : fiducials) {
      if (std::abs(x - f.centre_m.x()) <= f.size_m.x() / 2 && std::abs(y_m - f.centre_m.y()) <= f.size_m.y() / 2) {
        return spec.ink;
      }
    }
    return spec.paper;
  }};
}

Eigen::Isometry3d strip_T_square(const StripSpec& spec, int index) {
  validate(spec);
  if (index < 0 || index >= spec.squares) {
    throw std::invalid_argument("strip_T_square: index " + std::to_string(index) + " outside 0.." +
                                std::to_string(spec.squares - 1));
  }
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(index * spec.square_m, 0, 0);
  return t;
}

}  // namespace kincal::sim

// sin_cos(float) against double precision: the bound of sin_cos.hpp over random angles, the
// quadrant boundaries, and the refusal of arguments outside the range.
#include "firmware/core/sin_cos.hpp"

#include <doctest.h>

#include <cmath>

#include "tests/firmware/core/random_source.hpp"

using kincal::core::kSinCosMaxAbsError;
using kincal::core::kSinCosMaxArgumentRad;
using kincal::core::sin_cos;

namespace {

struct WorstError {
  double sin = 0.0, cos = 0.0, pythagoras = 0.0;
  void add(float angle) {
    const auto sc = sin_cos(angle);
    const double a = static_cast<double>(angle);
    sin = std::fmax(sin, std::fabs(static_cast<double>(sc.sin) - std::sin(a)));
    cos = std::fmax(cos, std::fabs(static_cast<double>(sc.cos) - std::cos(a)));
    const double s = static_cast<double>(sc.sin), c = static_cast<double>(sc.cos);
    pythagoras = std::fmax(pythagoras, std::fabs(s * s + c * c - 1.0));
  }
};

}  // namespace

TEST_CASE("sin_cos(float) is within its bound of the exact values over the whole range") {
  kincal::test::RandomSource random(0x51C05);
  WorstError small, large;
  for (int i = 0; i < 20000; ++i) small.add(static_cast<float>(random.uniform(-8.0, 8.0)));
  for (int i = 0; i < 5000; ++i) {
    const double bound = static_cast<double>(kSinCosMaxArgumentRad);
    large.add(static_cast<float>(random.uniform(-bound, bound)));
  }
  // Near every quadrant boundary k pi/2 up to |k| = 64, where the reduction cancels most.
  for (int k = -64; k <= 64; ++k) {
    const float centre = static_cast<float>(k * 1.5707963267948966);
    float below = centre, above = centre;
    for (int step = 0; step < 8; ++step) {
      small.add(below);
      small.add(above);
      below = std::nextafter(below, -1e9f);
      above = std::nextafter(above, 1e9f);
    }
  }
  const double bound = static_cast<double>(kSinCosMaxAbsError);
  CHECK(small.sin <= bound);
  CHECK(small.cos <= bound);
  CHECK(large.sin <= bound);
  CHECK(large.cos <= bound);
  CHECK(small.pythagoras <= 3e-7);
  CHECK(large.pythagoras <= 3e-7);
  MESSAGE("sin_cos worst |error|: |x|<=8 sin ", small.sin, " cos ", small.cos, "; |x|<=8192 sin ", large.sin, " cos ",
          large.cos);
}

TEST_CASE("sin_cos is exact at zero, odd in sine, even in cosine") {
  const auto zero = sin_cos(0.0f);
  CHECK(zero.sin == 0.0f);
  CHECK(zero.cos == 1.0f);
  kincal::test::RandomSource random(7);
  for (int i = 0; i < 1000; ++i) {
    const auto x = static_cast<float>(random.uniform(0.0, 100.0));
    const auto p = sin_cos(x), n = sin_cos(-x);
    CHECK(p.sin == -n.sin);
    CHECK(p.cos == n.cos);
  }
}

TEST_CASE("sin_cos refuses arguments outside its range with NaN") {
  const float nan = std::nanf("");
  CHECK(std::isnan(sin_cos(nan).sin));
  CHECK(std::isnan(sin_cos(2.0f * kSinCosMaxArgumentRad).cos));
  CHECK(std::isnan(sin_cos(-INFINITY).sin));
  CHECK(!std::isnan(sin_cos(kSinCosMaxArgumentRad).sin));
}

TEST_CASE("the generic sin_cos and angle_sum serve double") {
  const auto a = sin_cos(0.3), b = sin_cos(1.1);
  const auto sum = kincal::core::angle_sum(a, b);
  CHECK(std::fabs(sum.sin - std::sin(1.4)) < 1e-15);
  CHECK(std::fabs(sum.cos - std::cos(1.4)) < 1e-15);
}

TEST_CASE("small_angle_sin_cos is within the sin_cos bound over its range") {
  kincal::test::RandomSource random(0x5A11);
  double worst = 0.0;
  const double limit = static_cast<double>(kincal::core::kSmallAngleMaxRad);
  for (int i = 0; i < 20000; ++i) {
    const auto x = static_cast<float>(random.uniform(-limit, limit));
    const auto sc = kincal::core::small_angle_sin_cos(x);
    const double xd = static_cast<double>(x);
    worst = std::fmax(worst, std::fabs(static_cast<double>(sc.sin) - std::sin(xd)));
    worst = std::fmax(worst, std::fabs(static_cast<double>(sc.cos) - std::cos(xd)));
  }
  CHECK(worst <= static_cast<double>(kSinCosMaxAbsError));
  MESSAGE("small_angle_sin_cos worst |error| ", worst);
}

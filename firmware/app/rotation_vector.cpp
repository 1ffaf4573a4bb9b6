#include "firmware/app/rotation_vector.hpp"

#include <cmath>

namespace kincal::app {

namespace {

constexpr float kHalfPi = 1.57079632679f;

// atan(t) for t in [0, 1], within 5e-3 rad: the first guess of the Newton steps.
float atan_first_guess(float t) { return t * (0.78539816f + 0.273f * (1.0f - t)); }

// sqrt(max(v, 0)): rounding can take 1 + trace a hair below zero for a half-turn.
float root_of_positive(float v) { return v > 0.0f ? std::sqrt(v) : 0.0f; }

}  // namespace

core::Vector3<float> rotation_vector(const core::Matrix3<float>& r) noexcept {
  // Shepperd: the largest of 4w^2, 4x^2, 4y^2, 4z^2 gives the best-conditioned square root.
  const float trace = r(0, 0) + r(1, 1) + r(2, 2);
  float w, x, y, z;
  if (trace >= r(0, 0) && trace >= r(1, 1) && trace >= r(2, 2)) {
    const float s = 2.0f * root_of_positive(1.0f + trace);
    w = 0.25f * s;
    x = (r(2, 1) - r(1, 2)) / s;
    y = (r(0, 2) - r(2, 0)) / s;
    z = (r(1, 0) - r(0, 1)) / s;
  } else if (r(0, 0) >= r(1, 1) && r(0, 0) >= r(2, 2)) {
    const float s = 2.0f * root_of_positive(1.0f + r(0, 0) - r(1, 1) - r(2, 2));
    w = (r(2, 1) - r(1, 2)) / s;
    x = 0.25f * s;
    y = (r(0, 1) + r(1, 0)) / s;
    z = (r(0, 2) + r(2, 0)) / s;
  } else if (r(1, 1) >= r(2, 2)) {
    const float s = 2.0f * root_of_positive(1.0f + r(1, 1) - r(0, 0) - r(2, 2));
    w = (r(0, 2) - r(2, 0)) / s;
    x = (r(0, 1) + r(1, 0)) / s;
    y = 0.25f * s;
    z = (r(1, 2) + r(2, 1)) / s;
  } else {
    const float s = 2.0f * root_of_positive(1.0f + r(2, 2) - r(0, 0) - r(1, 1));
    w = (r(1, 0) - r(0, 1)) / s;
    x = (r(0, 2) + r(2, 0)) / s;
    y = (r(1, 2) + r(2, 1)) / s;
    z = 0.25f * s;
  }
  core::Vector3<float> v(x, y, z);
  if (w < 0.0f) {  // the angle in [0, pi]
    w = -w;
    v = -v;
  }
  const float sine = v.norm();                // sin(angle / 2) times |q|
  if (sine < 1.0e-4f) return v * (2.0f / w);  // angle / sin(angle / 2) = 2 / cos(angle / 2) to 1e-8
  // half = atan2(sine, w) in [0, pi/2]: a first guess, then Newton on sine cos(a) - w sin(a) = 0,
  // whose step is tan(half - a): each step cubes the error.
  float half = sine <= w ? atan_first_guess(sine / w) : kHalfPi - atan_first_guess(w / sine);
  for (int step = 0; step < 2; ++step) {
    const core::SinCos<float> sc = core::sin_cos(half);
    half += (sine * sc.cos - w * sc.sin) / (sine * sc.sin + w * sc.cos);
  }
  return v * (2.0f * half / sine);
}

}  // namespace kincal::app

// The correction tests' arm: a PUMA 560 in Craig's modified DH (link i holds alpha_{i-1},
// a_{i-1}; {a, alpha, d, theta, beta}), revolute joints, no errors and no tool: each test adds
// its own. (host/can/scenario.cpp has the same arm on the host side, where this header's M4
// build cannot reach.) Its singularities: elbow at tan q3 = d4 / a3 (q3 = 1.524 or -1.618 rad),
// wrist at q5 = 0 or pi.
#pragma once

#include "shared/parameters.hpp"

namespace kincal::test {

inline shared::CorrectionParameters puma560_block() {
  shared::CorrectionParameters c;
  c.joint_count = 6;
  const float half_pi = 1.5707964f;
  const shared::DhValues puma[6] = {
      {0, 0, 0, 0, 0},       {0, -half_pi, 0, 0, 0}, {0.4318f, 0, 0.15005f, 0, 0}, {0.0203f, -half_pi, 0.4318f, 0, 0},
      {0, half_pi, 0, 0, 0}, {0, -half_pi, 0, 0, 0}};
  for (std::size_t j = 0; j < 6; ++j) {
    c.joints[j].type = shared::JointKind::kRevolute;
    c.joints[j].convention = shared::LinkKind::kModifiedDh;
    c.joints[j].nominal = puma[j];
  }
  return c;
}

}  // namespace kincal::test

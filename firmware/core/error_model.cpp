#include "firmware/core/error_model.hpp"

namespace kincal::core {

template ParameterSet full_parameter_set(const ChainModel<float>&, bool, bool) noexcept;
template ErrorModelStatus apply_parameter_errors(const ChainModel<float>&, const ParameterSet&,
                                                 const ErrorVector<float>&, ChainModel<float>&) noexcept;
template ErrorModelStatus parameter_jacobian(const PreparedChain<float>&, const JointVector<float>&, const JointTrig&,
                                             const ChainFrames<float>&, const ParameterSet&,
                                             ErrorMatrix<float>&) noexcept;
template void joint_jacobian(const PreparedChain<float>&, const ChainFrames<float>&, JointJacobian<float>&) noexcept;

void doty_arid_error_matrix(const std::array<float, 4>& theta_rad, const std::array<float, 3>& a_m,
                            AridErrorMatrix& e) noexcept {
  const float t1 = theta_rad[0], t2 = theta_rad[1], t3 = theta_rad[2], t4 = theta_rad[3];
  const float a1 = a_m[0], a2 = a_m[1], a3 = a_m[2];
  // Partial sums of the joint angles: c_1, c_12, c_123, c_1234 and c_2, c_23, c_234, c_3, c_34, c_4.
  const SinCos<float> s1 = sin_cos(t1), s12 = sin_cos(t1 + t2), s123 = sin_cos(t1 + t2 + t3),
                      s1234 = sin_cos(t1 + t2 + t3 + t4), s2 = sin_cos(t2), s23 = sin_cos(t2 + t3),
                      s234 = sin_cos(t2 + t3 + t4), s3 = sin_cos(t3), s34 = sin_cos(t3 + t4), s4 = sin_cos(t4);
  // Columns: beta1 beta2 beta3 beta4 | alpha1 alpha2 alpha3 alpha4.
  e << s1.cos, s12.cos, s123.cos, s1234.cos, s1.sin, s12.sin, s123.sin, s1234.sin,                 // 3-11a
      s1.sin, s12.sin, s123.sin, s1234.sin, -s1.cos, -s12.cos, -s123.cos, -s1234.cos,              // 3-11b
      -s234.cos, -s34.cos, -s4.cos, -1.0f, s234.sin, s34.sin, s4.sin, 0.0f,                        // 3-11c
      s234.sin, s34.sin, s4.sin, 0.0f, s234.cos, s34.cos, s4.cos, 1.0f,                            // 3-11d
      -a1 - a2 * s2.cos - a3 * s23.cos, -a2 - a3 * s3.cos, -a3, 0.0f, a2 * s2.sin + a3 * s23.sin,  // 3-11e
      a3 * s3.sin, 0.0f, 0.0f;
}

}  // namespace kincal::core

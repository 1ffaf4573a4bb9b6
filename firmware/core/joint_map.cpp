#include "firmware/core/joint_map.hpp"

namespace kincal::core {

template void coupled_values(const JointMap<float>&, const JointVector<float>&, JointVector<float>&) noexcept;
template bool invert_coupling(const JointMap<float>&, CouplingMatrix<float>&, CouplingMatrix<float>&) noexcept;
template void readings_from_coupled(const JointMap<float>&, const CouplingMatrix<float>&, const JointVector<float>&,
                                    JointVector<float>&) noexcept;
template void gravity_forces(const PreparedChain<float>&, const ChainFrames<float>&, const MassModel<float>&,
                             JointVector<float>&) noexcept;
template void deflect(const PreparedChain<float>&, const MassModel<float>&, const JointVector<float>&,
                      const JointVector<float>&, DeflectionWorkspace<float>&, JointVector<float>&) noexcept;
template void undeflect(const PreparedChain<float>&, const MassModel<float>&, const JointVector<float>&,
                        const JointVector<float>&, int, DeflectionWorkspace<float>&, JointVector<float>&) noexcept;

}  // namespace kincal::core

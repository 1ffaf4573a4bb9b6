#include "firmware/core/link_model.hpp"

namespace kincal::core {

// The float instantiations the firmware runs (declared extern in the header).
template RigidTransform<float> link_transform(LinkConvention, const float&, const float&, const SinCos<float>&,
                                              const SinCos<float>&, const SinCos<float>&) noexcept;
template RigidTransform<float> link_transform(const Link<float>&, const float&) noexcept;
template void prepare_chain(const ChainModel<float>&, PreparedChain<float>&) noexcept;
template void joint_trig(const PreparedChain<float>&, const JointVector<float>&, JointTrig&) noexcept;
template void forward_kinematics(const PreparedChain<float>&, const JointVector<float>&, const JointTrig&,
                                 ChainFrames<float>&) noexcept;
template void tool_pose(const PreparedChain<float>&, const JointVector<float>&, const JointTrig&,
                        RigidTransform<float>&) noexcept;
template RigidTransform<float> forward_kinematics(const ChainModel<float>&, const JointVector<float>&) noexcept;

}  // namespace kincal::core

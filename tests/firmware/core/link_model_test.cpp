// link_model.hpp against an independent double forward kinematics (tests/firmware/core/
// chain_fixtures.hpp): every convention, both joint types, up to 8 joints; the float bound, the
// double instantiation, the prepared and direct paths, and Doty's 3-2/3-3.
#include "firmware/core/link_model.hpp"

#include <doctest.h>

#include <cmath>

#include "tests/firmware/core/chain_fixtures.hpp"

using namespace kincal::core;
using namespace kincal::test;

TEST_CASE("forward kinematics in float is within its bound of the double reference") {
  RandomSource random(0x11A4);
  double worst_position = 0.0, worst_rotation = 0.0, worst_double = 0.0, worst_paths = 0.0;
  for (int trial = 0; trial < 1500; ++trial) {
    const int n = 1 + trial % kMaxJoints;
    const ChainModel<double> chain_d = random_chain(random, n);
    const ChainModel<float> chain = to_float(chain_d);
    const Eigen::VectorXd q = random_joints(random, chain_d);
    const JointVector<float> q_f = to_joint_vector<float>(q);
    // The reference sees the float parameters and joint values.
    const Eigen::Affine3d reference = reference_fk(chain, q_f.head(n).cast<double>());

    PreparedChain<float> prepared;
    prepare_chain(chain, prepared);
    JointTrig trig;
    joint_trig(prepared, q_f, trig);
    ChainFrames<float> frames;
    forward_kinematics(prepared, q_f, trig, frames);
    const Eigen::Affine3d fk = to_affine(frames.base_T_tool);
    const double length = chain_length(chain_d, q) + 1.0;
    worst_position = std::fmax(worst_position, (fk.translation() - reference.translation()).norm() / length);
    worst_rotation = std::fmax(worst_rotation, rotation_angle(fk.linear(), reference.linear()) / n);

    const Eigen::Affine3d direct = to_affine(forward_kinematics(chain, q_f));
    worst_paths = std::fmax(worst_paths, (direct.matrix() - fk.matrix()).cwiseAbs().maxCoeff() / length);

    // The same template in double agrees with the reference to double rounding.
    const Eigen::Affine3d fk_d = to_affine(forward_kinematics(chain_d, to_joint_vector<double>(q)));
    const Eigen::Affine3d reference_d = reference_fk(chain_d, q);
    worst_double = std::fmax(worst_double, (fk_d.matrix() - reference_d.matrix()).cwiseAbs().maxCoeff() / length);
  }
  CHECK(worst_position <= static_cast<double>(kFkPositionErrorPerM));
  CHECK(worst_rotation <= static_cast<double>(kFkRotationErrorRad));
  CHECK(worst_paths <= 2.0 * static_cast<double>(kFkPositionErrorPerM));
  CHECK(worst_double <= 1e-14);
  MESSAGE("fk worst position / length ", worst_position, ", rotation / joint ", worst_rotation, " rad, paths ",
          worst_paths, ", double ", worst_double);
}

TEST_CASE("frames: each frame is the product of the links before it") {
  RandomSource random(0xF2A3);
  const ChainModel<double> chain_d = random_chain(random, 6);
  const ChainModel<float> chain = to_float(chain_d);
  const Eigen::VectorXd q = random_joints(random, chain_d);
  PreparedChain<float> prepared;
  prepare_chain(chain, prepared);
  JointTrig trig;
  const JointVector<float> q_f = to_joint_vector<float>(q);
  joint_trig(prepared, q_f, trig);
  ChainFrames<float> frames;
  forward_kinematics(prepared, q_f, trig, frames);
  CHECK(frames.joint_count == 6);
  for (int i = 0; i < 6; ++i) {
    ChainModel<float> head = chain;
    head.joint_count = i + 1;
    head.flange_T_tool = RigidTransform<float>{};
    const Eigen::Affine3d expected = reference_fk(head, q_f.head(i + 1).cast<double>());
    CHECK((to_affine(frames.base_T_frame[static_cast<std::size_t>(i + 1)]).matrix() - expected.matrix())
              .cwiseAbs()
              .maxCoeff() < 5e-6);
  }
}

TEST_CASE("Doty's link transform is his 3-2 and 3-3, and reduces to DH when beta is zero") {
  RandomSource random(0xD0D0);
  for (int i = 0; i < 200; ++i) {
    const double d = random.uniform(-1, 1), theta = random.uniform(-3, 3), a = random.uniform(-1, 1),
                 alpha = random.uniform(-3, 3), beta = random.uniform(-1, 1);
    Link<double> link;
    link.convention = LinkConvention::doty;
    link.parameters = {d, theta, a, alpha, beta};
    const RigidTransform<double> t = link_transform(link, 0.0);
    const double ct = std::cos(theta), st = std::sin(theta), ca = std::cos(alpha), sa = std::sin(alpha),
                 cb = std::cos(beta), sb = std::sin(beta);
    // Doty 3-2, entry by entry as printed, and 3-3.
    Eigen::Matrix3d r;
    r << cb * ct, ct * sa * sb - ca * st, ca * ct * sb + sa * st, cb * st, ca * ct + sa * sb * st,
        -ct * sa + ca * sb * st, -sb, cb * sa, ca * cb;
    CHECK((t.rotation - r).cwiseAbs().maxCoeff() < 1e-15);
    CHECK((t.translation - Eigen::Vector3d(a * cb * ct, a * cb * st, d - a * sb)).cwiseAbs().maxCoeff() < 1e-15);
    // beta = 0: the same frame as standard DH.
    link.parameters.beta_rad = 0.0;
    Link<double> dh = link;
    dh.convention = LinkConvention::standard_dh;
    const RigidTransform<double> a_t = link_transform(link, 0.3), b_t = link_transform(dh, 0.3);
    CHECK((a_t.rotation - b_t.rotation).cwiseAbs().maxCoeff() < 1e-15);
    CHECK((a_t.translation - b_t.translation).cwiseAbs().maxCoeff() < 1e-15);
  }
}

TEST_CASE("prismatic joints move along their axis; joint counts are clamped") {
  ChainModel<float> chain;
  chain.joint_count = 1;
  chain.links[0].joint = JointType::prismatic;
  chain.links[0].convention = LinkConvention::standard_dh;
  JointVector<float> q = JointVector<float>::Zero();
  q(0) = 0.25f;
  const RigidTransform<float> t = forward_kinematics(chain, q);
  CHECK(t.translation.isApprox(Vector3<float>(0.0f, 0.0f, 0.25f)));
  chain.joint_count = 99;  // a malformed count must not read past the arrays
  PreparedChain<float> prepared;
  prepare_chain(chain, prepared);
  CHECK(prepared.joint_count == kMaxJoints);
  chain.joint_count = -3;
  prepare_chain(chain, prepared);
  CHECK(prepared.joint_count == 0);
}

#include "host/model/robot_model.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numbers>

#include "firmware/core/joint_map.hpp"

namespace kincal::model {

namespace {

// Whether link parameter `kind` of a revolute joint's link acts after the joint's motion in the
// link transform (firmware/core/link_model.hpp's conventions): it places the next axis on the
// body the joint turns, and that body's mass stays where it is (carry_centres_of_mass).
bool beyond_motion(core::LinkConvention convention, core::ParameterKind kind) {
  using K = core::ParameterKind;
  switch (convention) {
    case core::LinkConvention::standard_dh:  // Rz(theta) | Tz(d) Tx(a) Rx(alpha)
      return kind == K::link_d || kind == K::link_a || kind == K::link_alpha;
    case core::LinkConvention::doty:  // Tz(d) Rz(theta) | Ry(beta) Tx(a) Rx(alpha)
      return kind == K::link_beta || kind == K::link_a || kind == K::link_alpha;
    case core::LinkConvention::modified_dh:  // Rx(alpha) Tx(a) Rz(theta) | Tz(d)
      return kind == K::link_d;
  }
  return false;
}

// A revolute joint's link with a mass given (a URDF's, a model file's), not identified: its centre
// is kept on the body (carry_centres_of_mass). An identified centre (geometry+sag's) has no given
// place, and carried it let 10 rows of the zoo's SIA10F run off (131 mm out of range).
bool carries_given_mass(const Joint& j) {
  return j.type == core::JointType::revolute && j.mass_kg != 0.0 && !j.identify_mass;
}

// That part of a link's transform: frame i in the frame that turns with joint i.
Eigen::Isometry3d beyond_motion_transform(const core::Link<double>& link) {
  const core::LinkParameters<double>& p = link.parameters;
  const Eigen::Isometry3d tz(Eigen::Translation3d(0.0, 0.0, p.d_m)), tx(Eigen::Translation3d(p.a_m, 0.0, 0.0));
  const Eigen::Isometry3d rx(Eigen::AngleAxisd(p.alpha_rad, Vector3::UnitX()));
  switch (link.convention) {
    case core::LinkConvention::standard_dh:
      return tz * tx * rx;
    case core::LinkConvention::doty:
      return Eigen::Isometry3d(Eigen::AngleAxisd(p.beta_rad, Vector3::UnitY())) * tx * rx;
    case core::LinkConvention::modified_dh:
      return tz;
  }
  return Eigen::Isometry3d::Identity();
}

double& variable_parameter(core::LinkParameters<double>& p, core::JointType type) {
  return type == core::JointType::revolute ? p.theta_rad : p.d_m;
}
double variable_parameter(const core::LinkParameters<double>& p, core::JointType type) {
  return type == core::JointType::revolute ? p.theta_rad : p.d_m;
}

core::ParameterSet to_set(std::span<const core::ParameterId> ids) {
  if (ids.size() > static_cast<std::size_t>(core::kMaxErrorParameters))
    throw std::invalid_argument("more parameters than core::kMaxErrorParameters");
  core::ParameterSet set;
  set.count = static_cast<int>(ids.size());
  std::copy(ids.begin(), ids.end(), set.ids.begin());
  return set;
}

struct KindName {
  core::ParameterKind kind;
  const char* name;
};
constexpr KindName kIndexedNames[] = {{core::ParameterKind::link_theta, "theta"},
                                      {core::ParameterKind::link_alpha, "alpha"},
                                      {core::ParameterKind::link_beta, "beta"},
                                      {core::ParameterKind::link_d, "d"},
                                      {core::ParameterKind::link_a, "a"},
                                      {kJointScale, "scale"},
                                      {kJointCompliance, "compliance"},
                                      {kLinkMass, "mass"},
                                      {kLinkCentreX, "com_x"},
                                      {kLinkCentreY, "com_y"},
                                      {kLinkCentreZ, "com_z"}};
constexpr const char* kMotionNames[] = {"base_x", "base_y", "base_z", "base_rx", "base_ry", "base_rz",
                                        "tool_x", "tool_y", "tool_z", "tool_rx", "tool_ry", "tool_rz"};

// The core's kinds of ids (joint-map kinds left out), and where each id's column comes from.
core::ParameterSet geometric_set(std::span<const core::ParameterId> ids) {
  std::vector<core::ParameterId> geometric;
  for (const core::ParameterId& id : ids)
    if (!is_joint_map_parameter(id.kind)) geometric.push_back(id);
  return to_set(geometric);
}

// "coupling<i>_<k>": joint i's share of reading k; only k = i - 1 is a parameter (the top of
// robot_model.hpp). nullopt when the name is not of that form.
std::optional<core::ParameterId> parse_coupling_name(const std::string& name, int joint_count) {
  const std::string prefix = "coupling";
  if (name.compare(0, prefix.size(), prefix) != 0) return std::nullopt;
  const char* last = name.data() + name.size();
  int joint = 0, reading = 0;
  const auto [sep, ec] = std::from_chars(name.data() + prefix.size(), last, joint);
  if (ec != std::errc() || sep == last || *sep != '_') return std::nullopt;
  const auto [end, ec2] = std::from_chars(sep + 1, last, reading);
  if (ec2 != std::errc() || end != last) return std::nullopt;
  if (joint < 2 || joint > joint_count)
    throw InputError("parameter '" + name + "': joint " + std::to_string(joint) +
                     " has no upstream neighbour to share a reading of (the model has " + std::to_string(joint_count) +
                     " joints; couplings are coupling2_1 .. coupling" + std::to_string(joint_count) + "_" +
                     std::to_string(joint_count - 1) + ")");
  if (reading != joint - 1)
    throw InputError("parameter '" + name +
                     "': only a joint's share of its upstream neighbour's reading is a "
                     "parameter (coupling" +
                     std::to_string(joint) + "_" + std::to_string(joint - 1) +
                     "); other coupling coefficients are the model file's inputs");
  return core::ParameterId{kJointCoupling, static_cast<std::uint8_t>(joint - 1)};
}

bool is_plain(const RobotModel& model) { return !has_joint_map(model) && !has_compliance(model); }

// Readings -> chain variables before the deflection (offsets are in the chain): scale, coupling.
core::JointVector<double> coupled_values(const RobotModel& model, std::span<const double> q) {
  if (!has_joint_map(model)) return joint_vector(q);
  core::JointVector<double> u = joint_vector(q), v = core::JointVector<double>::Zero();
  for (std::size_t k = 0; k < model.joints.size(); ++k)
    u(static_cast<Eigen::Index>(k)) *= model.joints[k].scale.value_or(1.0);
  for (std::size_t i = 0; i < model.joints.size(); ++i) {
    const std::vector<double>& c = model.joints[i].coupling;
    const auto row = static_cast<Eigen::Index>(i);
    if (c.empty()) {
      v(row) = u(row);
      continue;
    }
    for (std::size_t k = 0; k < c.size() && k < model.joints.size(); ++k)
      v(row) += c[k] * u(static_cast<Eigen::Index>(k));
  }
  return v;
}

// The coupling coefficients (n x n; identity rows where a joint has none), without the scales.
Eigen::MatrixXd coupling_matrix(const RobotModel& model) {
  const auto n = static_cast<Eigen::Index>(model.joints.size());
  Eigen::MatrixXd c = Eigen::MatrixXd::Identity(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const std::vector<double>& row = model.joints[static_cast<std::size_t>(i)].coupling;
    if (row.empty()) continue;
    for (Eigen::Index k = 0; k < n; ++k)
      c(i, k) = static_cast<std::size_t>(k) < row.size() ? row[static_cast<std::size_t>(k)] : 0.0;
  }
  return c;
}

Eigen::VectorXd scales(const RobotModel& model) {
  Eigen::VectorXd s(static_cast<Eigen::Index>(model.joints.size()));
  for (std::size_t i = 0; i < model.joints.size(); ++i)
    s(static_cast<Eigen::Index>(i)) = model.joints[i].scale.value_or(1.0);
  return s;
}

Eigen::VectorXd compliances(const RobotModel& model) {
  Eigen::VectorXd k(static_cast<Eigen::Index>(model.joints.size()));
  for (std::size_t i = 0; i < model.joints.size(); ++i)
    k(static_cast<Eigen::Index>(i)) = model.joints[i].compliance.value_or(0.0);
  return k;
}

// The firmware core's mass model (joint_map.hpp) of the model's links, payload and gravity.
core::MassModel<double> mass_model(const RobotModel& model) {
  core::MassModel<double> masses;
  for (std::size_t b = 0; b < model.joints.size() && b < static_cast<std::size_t>(core::kMaxJoints); ++b) {
    masses.link_mass_kg[b] = model.joints[b].mass_kg;
    for (int k = 0; k < 3; ++k)
      masses.link_centre_of_mass_m[b][static_cast<std::size_t>(k)] = model.joints[b].centre_of_mass_m(k);
  }
  masses.payload_mass_kg = model.payload.mass_kg;
  for (int k = 0; k < 3; ++k) {
    masses.payload_centre_of_mass_m[static_cast<std::size_t>(k)] = model.payload.centre_of_mass_m(k);
    masses.gravity_mps2[static_cast<std::size_t>(k)] = model.gravity_mps2(k);
  }
  return masses;
}

// G at chain variables v and its derivatives, from one forward kinematics pass at v. G is linear
// in the masses, their centres (a mass held) and gravity, so a unit step's difference is the
// derivative exactly. A link parameter or a chain variable moves every frame beyond its link
// rigidly, by a twist: a point x moves by w x x + v0, gravity stays, so joint j's force changes as
//   revolute, its axis z_j moved:  (w x z_j) . (P_j x g) + z_j . ((w x P_j) x g)
//   revolute, z_j not moved:       z_j . ((w x D + m_D v0) x g)
//   prismatic, moved:              m_j (w x z_j) . g   (not moved: 0)
// with P_j = (sum m c over the bodies j moves) - m_j o_j, m_j their mass, and D, m_D the first
// moment and mass of the bodies beyond the link (all that j moves there, the payload included).
class GravityDerivatives {
 public:
  GravityDerivatives(const RobotModel& model, const core::PreparedChain<double>& chain,
                     const core::JointVector<double>& v)
      : chain_(chain), masses_(mass_model(model)), n_(static_cast<int>(model.joints.size())) {
    core::joint_trig(chain, v, trig_);
    core::forward_kinematics(chain, v, trig_, frames_);
    core::gravity_forces(chain, frames_, masses_, forces_);
    const Eigen::Map<const Vector3> g0(masses_.gravity_mps2.data());
    g_ = frames_.base_T_frame[0].rotation * g0;
    const auto place = [&](int frame, const std::array<double, 3>& c) {
      return Vector3(frames_.base_T_frame[static_cast<std::size_t>(frame)] * Eigen::Map<const Vector3>(c.data()));
    };
    double mass = masses_.payload_mass_kg;
    Vector3 moment = mass * place(n_, masses_.payload_centre_of_mass_m);
    for (int b = n_ - 1; b >= 0; --b) {
      const auto k = static_cast<std::size_t>(b);
      own_moment_[k] = masses_.link_mass_kg[k] * place(b + 1, masses_.link_centre_of_mass_m[k]);
      mass += masses_.link_mass_kg[k];
      moment += own_moment_[k];
      mass_[k] = mass;
      moment_[k] = moment;
    }
  }
  // The frames at v (the tool point the twists are given at).
  const core::ChainFrames<double>& frames() const { return frames_; }
  const std::array<core::SinCos<double>, core::kMaxJoints>& trig() const { return trig_; }
  const core::JointVector<double>& forces() const { return forces_; }

  // dG/d(id) for a mass, centre or gravity-direction parameter.
  core::JointVector<double> by_mass_parameter(core::ParameterId id) const {
    core::MassModel<double> stepped = masses_;
    core::JointVector<double> out;
    if (is_gravity_direction_parameter(id.kind)) {
      const Vector3 g = (id.kind == kGravityRx ? Vector3::UnitX() : Vector3::UnitY())
                            .cross(Eigen::Map<const Vector3>(masses_.gravity_mps2.data()));
      std::copy(g.data(), g.data() + 3, stepped.gravity_mps2.begin());
      core::gravity_forces(chain_, frames_, stepped, out);
      return out;
    }
    if (id.kind == kLinkMass) {
      stepped.link_mass_kg[id.link] += 1.0;
    } else {
      const auto axis = static_cast<std::size_t>(id.kind) - static_cast<std::size_t>(kLinkCentreX);
      stepped.link_centre_of_mass_m[id.link][axis] += 1.0;
    }
    core::gravity_forces(chain_, frames_, stepped, out);
    return out - forces_;
  }

  // dG for the rigid motion of every frame beyond link `link` by `twist`: [w x (p - o); w] at the
  // tool point p of frames(), as the core's Jacobian columns are; the link's own mass moves too
  // unless `own_mass_stays` (a parameter beyond its joint's motion: carry_centres_of_mass).
  core::JointVector<double> by_motion(std::size_t link, const Eigen::Matrix<double, 6, 1>& twist,
                                      bool own_mass_stays = false) const {
    const Vector3 w = twist.tail<3>();
    const Vector3 v0 = twist.head<3>() - w.cross(frames_.base_T_tool.translation);
    const Vector3 moment = moment_[link] - (own_mass_stays ? own_moment_[link] : Vector3::Zero());
    const double mass = mass_[link] - (own_mass_stays ? masses_.link_mass_kg[link] : 0.0);
    const Vector3 beyond = w.cross(moment) + mass * v0;  // w x D + m_D v0
    core::JointVector<double> d = core::JointVector<double>::Zero();
    for (int j = 0; j < n_; ++j) {
      const auto k = static_cast<std::size_t>(j);
      const core::PreparedLink<double>& joint = chain_.links[k];
      const std::size_t f = joint.convention == core::LinkConvention::modified_dh ? k + 1 : k;
      const Transform& frame = frames_.base_T_frame[f];
      const Vector3 z = frame.rotation.col(2);
      const bool moved = f > link;
      if (joint.joint == core::JointType::revolute) {
        if (moved) {
          const Vector3 p = moment_[k] - mass_[k] * frame.translation;
          d(j) = w.cross(z).dot(p.cross(g_)) + z.dot(w.cross(p).cross(g_));
        } else {
          d(j) = z.dot(beyond.cross(g_));
        }
      } else if (moved) {
        d(j) = mass_[k] * w.cross(z).dot(g_);
      }
    }
    return d;
  }

  // d(deflection)/d(v) at v: n x n, compliance_i dG_i/dv_k (a chain variable moves the frames
  // beyond its link by its joint Jacobian column).
  Eigen::MatrixXd deflection_by_values(const Eigen::VectorXd& compliance) const {
    core::JointJacobian<double> joints;
    core::joint_jacobian(chain_, frames_, joints);
    Eigen::MatrixXd d(n_, n_);
    for (int k = 0; k < n_; ++k)
      d.col(k) = by_motion(static_cast<std::size_t>(k), joints.col(k)).head(n_).cwiseProduct(compliance);
    return d;
  }

 private:
  const core::PreparedChain<double>& chain_;
  core::MassModel<double> masses_;
  int n_;
  std::array<core::SinCos<double>, core::kMaxJoints> trig_{};
  core::ChainFrames<double> frames_;
  core::JointVector<double> forces_ = core::JointVector<double>::Zero();
  Vector3 g_ = Vector3::Zero();
  std::array<double, core::kMaxJoints> mass_{};  // of the bodies joint j moves, payload included
  std::array<Vector3, core::kMaxJoints> moment_{};
  std::array<Vector3, core::kMaxJoints> own_moment_{};  // link j's own m c
};

}  // namespace

Transform flange_T_measured(const RobotModel& model) { return model.frame_n_T_flange.inverse() * model.flange_T_tool; }

RobotModel tool_at_tcp(const RobotModel& model) {
  if (!model.flange_T_tcp) return model;
  RobotModel out = model;
  out.flange_T_tool = model.frame_n_T_flange * *model.flange_T_tcp;
  out.tool = ToolKind::frame;
  return out;
}

std::string flange_name(const RobotModel& model) {
  return model.flange_link.empty() ? "frame n (the last joint's frame)" : "link '" + model.flange_link + "'";
}

bool has_joint_map(const RobotModel& model) {
  return std::any_of(model.joints.begin(), model.joints.end(),
                     [](const Joint& j) { return !j.coupling.empty() || j.scale.has_value(); });
}

bool has_compliance(const RobotModel& model) {
  return std::any_of(model.joints.begin(), model.joints.end(), [](const Joint& j) { return j.compliance.has_value(); });
}

bool is_joint_map_parameter(core::ParameterKind kind) {
  return kind == kJointScale || kind == kJointCompliance || kind == kJointCoupling || is_mass_parameter(kind) ||
         is_gravity_direction_parameter(kind);
}

bool is_gravity_direction_parameter(core::ParameterKind kind) { return kind == kGravityRx || kind == kGravityRy; }

bool is_mass_parameter(core::ParameterKind kind) {
  return kind == kLinkMass || kind == kLinkCentreX || kind == kLinkCentreY || kind == kLinkCentreZ;
}

bool is_motion_parameter(core::ParameterKind kind) {
  return !is_joint_map_parameter(kind) && kind >= core::ParameterKind::base_x;
}

bool is_base_parameter(core::ParameterKind kind) {
  return kind >= core::ParameterKind::base_x && kind <= core::ParameterKind::base_rz;
}

bool is_angle_parameter(core::ParameterKind kind) {
  using K = core::ParameterKind;
  return kind == K::link_theta || kind == K::link_alpha || kind == K::link_beta ||
         (kind >= K::base_rx && kind <= K::base_rz) || (kind >= K::tool_rx && kind <= K::tool_rz) ||
         is_gravity_direction_parameter(kind);
}

DisplayUnit display_unit(const RobotModel& model, core::ParameterId id) {
  using K = core::ParameterKind;
  if (id.kind == kJointScale || id.kind == kJointCoupling) return {1e6, "ppm"};
  if (id.kind == kLinkMass) return {1.0, "kg"};
  if (is_gravity_direction_parameter(id.kind)) return {180.0 / std::numbers::pi, "deg"};
  if (is_mass_parameter(id.kind)) return {1e3, "mm"};
  if (id.kind == kJointCompliance) {
    const bool prismatic = id.link < model.joints.size() && model.joints[id.link].type == core::JointType::prismatic;
    return {1e6, prismatic ? "um/N" : "urad/Nm"};
  }
  const bool angle = id.kind == K::link_theta || id.kind == K::link_alpha || id.kind == K::link_beta ||
                     (id.kind >= K::base_rx && id.kind <= K::base_rz) || id.kind >= K::tool_rx;
  return angle ? DisplayUnit{180.0 / std::numbers::pi, "deg"} : DisplayUnit{1e3, "mm"};
}

core::ChainModel<double> to_chain(const RobotModel& model) {
  core::ChainModel<double> chain;
  chain.joint_count = model.joint_count();
  for (std::size_t i = 0; i < model.joints.size() && i < static_cast<std::size_t>(core::kMaxJoints); ++i) {
    const Joint& j = model.joints[i];
    core::Link<double>& link = chain.links[i];
    link.convention = j.convention;
    link.joint = j.type;
    link.parameters = j.parameters;
    variable_parameter(link.parameters, j.type) += j.offset;
  }
  chain.base_T_frame0 = model.base_T_frame0;
  chain.flange_T_tool = model.flange_T_tool;
  return chain;
}

RobotModel from_chain(const RobotModel& like, const core::ChainModel<double>& chain) {
  RobotModel out = like;
  for (std::size_t i = 0; i < out.joints.size(); ++i) {
    Joint& j = out.joints[i];
    const core::Link<double>& link = chain.links[i];
    const double nominal = variable_parameter(j.parameters, j.type);
    j.convention = link.convention;
    j.parameters = link.parameters;
    variable_parameter(j.parameters, j.type) = nominal;
    j.offset = variable_parameter(link.parameters, j.type) - nominal;
  }
  out.base_T_frame0 = chain.base_T_frame0;
  out.flange_T_tool = chain.flange_T_tool;
  return out;
}

core::JointVector<double> joint_vector(std::span<const double> q) {
  core::JointVector<double> v = core::JointVector<double>::Zero();
  for (std::size_t i = 0; i < q.size() && i < static_cast<std::size_t>(core::kMaxJoints); ++i)
    v(static_cast<Eigen::Index>(i)) = q[i];
  return v;
}

Transform forward_kinematics(const RobotModel& model, std::span<const double> q) {
  if (is_plain(model)) return core::forward_kinematics(to_chain(model), joint_vector(q));
  return chain_at_joints(model, q).frames.base_T_tool;
}

ChainAtJoints evaluate_chain(const RobotModel& model, const core::ChainModel<double>& chain,
                             std::span<const double> q) {
  ChainAtJoints at;
  core::prepare_chain(chain, at.chain);
  at.coupled = coupled_values(model, q);
  at.q = at.coupled;
  if (has_compliance(model)) {
    const core::JointVector<double> g = gravity_forces(model, at.chain, at.coupled);
    for (std::size_t i = 0; i < model.joints.size(); ++i)
      at.q(static_cast<Eigen::Index>(i)) += model.joints[i].compliance.value_or(0.0) * g(static_cast<Eigen::Index>(i));
  }
  core::joint_trig(at.chain, at.q, at.trig);
  core::forward_kinematics(at.chain, at.q, at.trig, at.frames);
  return at;
}

ChainAtJoints chain_at_joints(const RobotModel& model, std::span<const double> q) {
  return evaluate_chain(model, to_chain(model), q);
}

core::JointVector<double> gravity_forces(const RobotModel& model, const core::PreparedChain<double>& chain,
                                         const core::JointVector<double>& v) {
  // The firmware core's definition (joint_map.hpp), which the platform's correction runs in float.
  const core::MassModel<double> masses = mass_model(model);
  core::DeflectionWorkspace<double> ws;
  core::joint_trig(chain, v, ws.trig);
  core::forward_kinematics(chain, v, ws.trig, ws.frames);
  core::gravity_forces(chain, ws.frames, masses, ws.forces);
  return ws.forces;
}

Eigen::MatrixXd joint_jacobian(const RobotModel& model, std::span<const double> q) {
  const ChainAtJoints at = chain_at_joints(model, q);
  core::JointJacobian<double> j;
  core::joint_jacobian(at.chain, at.frames, j);
  const auto n = static_cast<Eigen::Index>(model.joint_count());
  if (is_plain(model)) return j.leftCols(n);
  Eigen::MatrixXd by_values = Eigen::MatrixXd::Identity(n, n);
  if (has_compliance(model))
    by_values += GravityDerivatives(model, at.chain, at.coupled).deflection_by_values(compliances(model));
  return j.leftCols(n) * by_values * coupling_matrix(model) * scales(model).asDiagonal();
}

std::string parameter_name(core::ParameterId id) {
  const int kind = static_cast<int>(id.kind);
  if (is_motion_parameter(id.kind)) return kMotionNames[kind - static_cast<int>(core::ParameterKind::base_x)];
  if (id.kind == kJointCoupling) return "coupling" + std::to_string(id.link + 1) + "_" + std::to_string(id.link);
  if (is_gravity_direction_parameter(id.kind)) return id.kind == kGravityRx ? "gravity_rx" : "gravity_ry";
  for (const KindName& k : kIndexedNames)
    if (k.kind == id.kind) return std::string(k.name) + std::to_string(id.link + 1);
  return "?";
}

core::ParameterId parse_parameter_name(const std::string& name, int joint_count) {
  for (int k = 0; k < 12; ++k)
    if (name == kMotionNames[k])
      return {static_cast<core::ParameterKind>(static_cast<int>(core::ParameterKind::base_x) + k), 0};
  if (const std::optional<core::ParameterId> coupling = parse_coupling_name(name, joint_count)) return *coupling;
  if (name == "gravity_rx" || name == "gravity_ry") return {name == "gravity_rx" ? kGravityRx : kGravityRy, 0};
  for (const KindName& k : kIndexedNames) {
    const std::string prefix = k.name;
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    int joint = 0;
    const char* first = name.data() + prefix.size();
    const char* last = name.data() + name.size();
    const auto [end, ec] = std::from_chars(first, last, joint);
    if (ec != std::errc() || end != last) continue;
    if (joint < 1 || joint > joint_count)
      throw InputError("parameter '" + name + "': joint " + std::to_string(joint) + " does not exist (the model has " +
                       std::to_string(joint_count) + " joints)");
    return {k.kind, static_cast<std::uint8_t>(joint - 1)};
  }
  throw InputError("unknown parameter name '" + name +
                   "' (expected d<i>, theta<i>, a<i>, alpha<i>, beta<i>, scale<i>, compliance<i>, coupling<i>_<i-1>, "
                   "base_x..base_rz, tool_x..tool_rz or gravity_rx, gravity_ry)");
}

std::vector<core::ParameterId> all_parameters(const RobotModel& model) {
  std::vector<core::ParameterId> ids;
  for (int i = 0; i < model.joint_count(); ++i) {
    const auto link = static_cast<std::uint8_t>(i);
    ids.push_back({core::ParameterKind::link_theta, link});
    ids.push_back({core::ParameterKind::link_d, link});
    ids.push_back({core::ParameterKind::link_a, link});
    ids.push_back({core::ParameterKind::link_alpha, link});
    if (model.joints[static_cast<std::size_t>(i)].convention == core::LinkConvention::doty)
      ids.push_back({core::ParameterKind::link_beta, link});
  }
  const int tool_count = model.tool == ToolKind::point ? 3 : 6;
  for (int k = 0; k < 6; ++k)
    ids.push_back({static_cast<core::ParameterKind>(static_cast<int>(core::ParameterKind::base_x) + k), 0});
  for (int k = 0; k < tool_count; ++k)
    ids.push_back({static_cast<core::ParameterKind>(static_cast<int>(core::ParameterKind::tool_x) + k), 0});
  for (std::size_t i = 0; i < model.joints.size(); ++i)
    if (model.joints[i].scale) ids.push_back({kJointScale, static_cast<std::uint8_t>(i)});
  for (std::size_t i = 0; i < model.joints.size(); ++i)
    if (model.joints[i].compliance) ids.push_back({kJointCompliance, static_cast<std::uint8_t>(i)});
  for (std::size_t i = 0; i < model.joints.size(); ++i)
    if (model.joints[i].identify_coupling) ids.push_back({kJointCoupling, static_cast<std::uint8_t>(i)});
  for (std::size_t i = 0; i < model.joints.size(); ++i)
    if (model.joints[i].identify_mass)
      for (const core::ParameterKind kind : {kLinkMass, kLinkCentreX, kLinkCentreY, kLinkCentreZ})
        ids.push_back({kind, static_cast<std::uint8_t>(i)});
    else if (model.joints[i].identify_centre)
      for (const core::ParameterKind kind : {kLinkCentreX, kLinkCentreY, kLinkCentreZ})
        ids.push_back({kind, static_cast<std::uint8_t>(i)});
  if (model.identify_gravity_direction && has_compliance(model) && !model.joints.empty())
    for (const core::ParameterKind kind : {kGravityRx, kGravityRy}) ids.push_back({kind, 0});
  return ids;
}

bool can_identify_coupling(const RobotModel& model, std::size_t i) {
  return i >= 1 && i < model.joints.size() && model.joints[i].type == core::JointType::revolute &&
         model.joints[i - 1].type == core::JointType::revolute;
}

Eigen::MatrixXd parameter_jacobian(const RobotModel& model, std::span<const double> q,
                                   std::span<const core::ParameterId> ids) {
  return parameter_jacobian(model, chain_at_joints(model, q), q, ids);
}

Eigen::MatrixXd parameter_jacobian(const RobotModel& model, const ChainAtJoints& at, std::span<const double> q,
                                   std::span<const core::ParameterId> ids) {
  const core::ParameterSet set = geometric_set(ids);
  core::ErrorMatrix<double> e = core::ErrorMatrix<double>::Zero();
  if (core::parameter_jacobian(at.chain, at.q, at.trig, at.frames, set, e) != core::ErrorModelStatus::ok)
    throw std::invalid_argument("parameter_jacobian: a parameter names a joint the model does not have");
  if (is_plain(model) && static_cast<std::size_t>(set.count) == ids.size()) return e.leftCols(set.count);
  // The joint map: columns through the chain's joint Jacobian at the deflected values.
  core::JointJacobian<double> joints;
  core::joint_jacobian(at.chain, at.frames, joints);
  const auto n = static_cast<Eigen::Index>(model.joints.size());
  // With a compliance, G and its derivatives at the values before the deflection, and the link
  // parameters' motions of the chain there (their columns at those frames).
  const std::optional<GravityDerivatives> gravity =
      has_compliance(model) ? std::optional<GravityDerivatives>(std::in_place, model, at.chain, at.coupled)
                            : std::nullopt;
  core::ErrorMatrix<double> motions = core::ErrorMatrix<double>::Zero();
  if (gravity && core::parameter_jacobian(at.chain, at.coupled, gravity->trig(), gravity->frames(), set, motions) !=
                     core::ErrorModelStatus::ok)
    throw std::invalid_argument("parameter_jacobian: a parameter names a joint the model does not have");
  const Eigen::VectorXd k = compliances(model);
  Eigen::MatrixXd by_values = Eigen::MatrixXd::Identity(n, n);
  bool by_values_ready = !gravity;
  Eigen::MatrixXd out(6, static_cast<Eigen::Index>(ids.size()));
  int geometric = 0;
  for (std::size_t c = 0; c < ids.size(); ++c) {
    const core::ParameterId id = ids[c];
    const auto col = static_cast<Eigen::Index>(c);
    if ((id.link >= model.joints.size() &&
         (is_joint_map_parameter(id.kind) || id.kind <= core::ParameterKind::link_beta)) ||
        (id.kind == kJointCoupling && id.link < 1))
      throw std::invalid_argument("parameter_jacobian: a parameter names a joint the model does not have");
    const auto link = static_cast<Eigen::Index>(id.link);
    if (id.kind == kJointCompliance || is_mass_parameter(id.kind) || is_gravity_direction_parameter(id.kind)) {
      // A model without a compliance does not deflect: these columns are zero.
      if (!gravity)
        out.col(col).setZero();
      else if (id.kind == kJointCompliance)
        out.col(col) = joints.col(link) * gravity->forces()(link);
      else
        out.col(col) = joints.leftCols(n) * gravity->by_mass_parameter(id).head(n).cwiseProduct(k);
      continue;
    }
    if (id.kind == kJointScale || id.kind == kJointCoupling) {
      if (!by_values_ready) by_values += gravity->deflection_by_values(k);
      by_values_ready = true;
      // A scale moves every variable reading k reaches; a coupling moves joint i by u_{i-1}.
      Eigen::VectorXd dv = Eigen::VectorXd::Zero(n);
      if (id.kind == kJointScale) {
        dv = coupling_matrix(model).col(link) * q[static_cast<std::size_t>(id.link)];
      } else {
        const std::size_t from = id.link - 1U;
        dv(link) = model.joints[from].scale.value_or(1.0) * q[from];
      }
      out.col(col) = joints.leftCols(n) * (by_values * dv);
      continue;
    }
    const int g = geometric++;
    out.col(col) = e.col(g);
    // A link parameter moves the deflection too (base and tool motions do not: gravity is given
    // in frame 0 and the payload in the flange frame).
    if (gravity && id.kind <= core::ParameterKind::link_beta) {
      const model::Joint& joint = model.joints[id.link];
      const bool stays = carries_given_mass(joint) && beyond_motion(joint.convention, id.kind);
      out.col(col) += joints.leftCols(n) * gravity->by_motion(id.link, motions.col(g), stays).head(n).cwiseProduct(k);
    }
  }
  return out;
}

RobotModel apply_parameter_errors(const RobotModel& model, std::span<const core::ParameterId> ids,
                                  const Eigen::VectorXd& errors) {
  std::vector<core::ParameterId> geometric;
  std::vector<double> geometric_errors;
  RobotModel out = model;
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const double e = errors(static_cast<Eigen::Index>(k));
    if (!is_joint_map_parameter(ids[k].kind)) {
      geometric.push_back(ids[k]);
      geometric_errors.push_back(e);
      continue;
    }
    add_joint_map_error(out, ids[k], e);
  }
  const core::ParameterSet set = to_set(geometric);
  core::ErrorVector<double> e = core::ErrorVector<double>::Zero();
  for (int k = 0; k < set.count; ++k) e(k) = geometric_errors[static_cast<std::size_t>(k)];
  core::ChainModel<double> actual;
  const core::ChainModel<double> before = to_chain(model);
  if (core::apply_parameter_errors(before, set, e, actual) != core::ErrorModelStatus::ok)
    throw std::invalid_argument("apply_parameter_errors: a parameter names a joint the model does not have");
  out = from_chain(out, actual);
  carry_centres_of_mass(out, before, actual);
  return out;
}

void carry_centres_of_mass(RobotModel& model, const core::ChainModel<double>& before,
                           const core::ChainModel<double>& after) {
  for (std::size_t i = 0; i < model.joints.size() && i < static_cast<std::size_t>(core::kMaxJoints); ++i) {
    Joint& j = model.joints[i];
    if (!carries_given_mass(j)) continue;
    j.centre_of_mass_m = beyond_motion_transform(after.links[i]).inverse() *
                         (beyond_motion_transform(before.links[i]) * j.centre_of_mass_m);
  }
}

void add_joint_map_error(RobotModel& model, core::ParameterId id, double error) {
  if (id.link >= model.joints.size() || (id.kind == kJointCoupling && id.link < 1))
    throw std::invalid_argument("add_joint_map_error: a parameter names a joint the model does not have");
  Joint& j = model.joints[id.link];
  if (id.kind == kJointScale) {
    j.scale = j.scale.value_or(1.0) + error;
  } else if (id.kind == kJointCompliance) {
    j.compliance = j.compliance.value_or(0.0) + error;
  } else if (id.kind == kJointCoupling) {
    if (j.coupling.empty()) {
      j.coupling.assign(model.joints.size(), 0.0);
      j.coupling[id.link] = 1.0;
    }
    j.coupling.at(id.link - 1U) += error;
  } else if (id.kind == kLinkMass) {
    j.mass_kg += error;
  } else if (is_mass_parameter(id.kind)) {
    j.centre_of_mass_m(static_cast<int>(id.kind) - static_cast<int>(kLinkCentreX)) += error;
  } else if (is_gravity_direction_parameter(id.kind)) {
    model.gravity_mps2 =
        Eigen::AngleAxisd(error, id.kind == kGravityRx ? Vector3::UnitX() : Vector3::UnitY()) * model.gravity_mps2;
  } else {
    throw std::invalid_argument("add_joint_map_error: " + parameter_name(id) + " is not a joint-map parameter");
  }
}

Matrix3 rotation_from_rpy(const Vector3& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Vector3::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Vector3::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Vector3::UnitX()))
      .toRotationMatrix();
}

Vector3 rpy_from_rotation(const Matrix3& r) {
  // R = Rz(y) Ry(p) Rx(r); its first column is (cos y cos p, sin y cos p, -sin p). Pitch and yaw
  // come from that column, roll from the whole matrix once they are known:
  // Rx(roll) = (Rz(y) Ry(p))^T R. Near p = +-pi/2 yaw is ill-determined (the column's xy part is
  // tiny), but roll absorbs its error through entries of size 1, so R(rpy) equals R to rounding
  // (no division by cos p; at p = +-pi/2 exactly, roll takes whatever turn the yaw leaves).
  const double pitch = std::atan2(-r(2, 0), std::hypot(r(0, 0), r(1, 0)));
  const double yaw = std::atan2(r(1, 0), r(0, 0));
  const Matrix3 roll_only = (Eigen::AngleAxisd(yaw, Vector3::UnitZ()) * Eigen::AngleAxisd(pitch, Vector3::UnitY()))
                                .toRotationMatrix()
                                .transpose() *
                            r;
  return {std::atan2(roll_only(2, 1) - roll_only(1, 2), roll_only(1, 1) + roll_only(2, 2)), pitch, yaw};
}

void CalibrationRecord::erase_parameter(std::size_t k) {
  if (!correlations.empty()) {
    // Parameter j > 0 has row j - 1; its entry for parameter k < j is at k.
    for (std::size_t j = k + 1; j < parameters.size(); ++j)
      correlations[j - 1].erase(correlations[j - 1].begin() + static_cast<std::ptrdiff_t>(k));
    correlations.erase(correlations.begin() + static_cast<std::ptrdiff_t>(k > 0 ? k - 1 : 0));
  }
  parameters.erase(parameters.begin() + static_cast<std::ptrdiff_t>(k));
}

void CalibrationRecord::add_parameter(const ParameterReport& p) {
  if (!correlations.empty()) correlations.emplace_back(parameters.size(), 0.0);
  parameters.push_back(p);
}

}  // namespace kincal::model

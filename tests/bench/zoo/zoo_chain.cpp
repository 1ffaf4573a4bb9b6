#include "zoo_chain.hpp"

#include <fstream>
#include <functional>
#include <set>
#include <sstream>
#include <stdexcept>

#include <urdf_parser/urdf_parser.h>

namespace zoo {

namespace {

Pose pose_of(const urdf::Pose& p) {
  Pose t = Pose::Identity();
  t.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  t.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).toRotationMatrix();
  return t;
}

urdf::ModelInterfaceSharedPtr parse(const std::string& text, const std::string& what) {
  urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(text);
  if (!model) throw std::runtime_error(what + ": urdfdom cannot read it");
  return model;
}

bool moving(const urdf::Joint& j) {
  return j.type == urdf::Joint::REVOLUTE || j.type == urdf::Joint::CONTINUOUS || j.type == urdf::Joint::PRISMATIC;
}

int moving_joints_to_root(urdf::LinkConstSharedPtr link) {
  int n = 0;
  for (; link->parent_joint; link = link->getParent()) n += moving(*link->parent_joint) ? 1 : 0;
  return n;
}

// The chain's last link: `tip` when named, else tool0, else flange, else the leaf with the most
// moving joints above it.
urdf::LinkConstSharedPtr flange_link(const urdf::ModelInterface& model, const std::string& tip,
                                     const std::string& urdf_path) {
  if (!tip.empty()) {
    if (urdf::LinkConstSharedPtr link = model.getLink(tip)) return link;
    throw std::runtime_error(urdf_path + ": no link named " + tip);
  }
  for (const char* name : {"tool0", "flange"})
    if (urdf::LinkConstSharedPtr link = model.getLink(name)) return link;
  urdf::LinkConstSharedPtr best;
  for (const auto& [name, link] : model.links_)
    if (link->child_links.empty() && (!best || moving_joints_to_root(link) > moving_joints_to_root(best))) best = link;
  return best;
}

// Adds `link`'s mass (at joint_T_link) and that of every link hanging off it outside the chain --
// a gripper, a camera, a tool beyond the flange, their own joints at zero -- to joint c.
void add_hanging_masses(ChainJoint& c, const urdf::Link& link, const Pose& joint_T_link,
                        const std::set<std::string>& on_path, bool& any) {
  if (link.inertial && link.inertial->mass > 0.0) {
    const Eigen::Vector3d com = joint_T_link * pose_of(link.inertial->origin).translation();
    const double m = link.inertial->mass;
    c.com_m = (c.com_m * c.mass_kg + com * m) / (c.mass_kg + m);
    c.mass_kg += m;
    any = true;
  }
  for (const urdf::LinkSharedPtr& child : link.child_links)
    if (!on_path.count(child->name))
      add_hanging_masses(c, *child, joint_T_link * pose_of(child->parent_joint->parent_to_joint_origin_transform),
                         on_path, any);
}

// Lumps the links that move with each joint: its child, the fixed joints' children after it on the
// chain, and what hangs off those outside the chain (a real arm carries its gripper's weight).
void add_masses(Chain& chain, const std::vector<urdf::JointConstSharedPtr>& path, const urdf::ModelInterface& model) {
  std::set<std::string> on_path;
  for (const urdf::JointConstSharedPtr& j : path) on_path.insert(j->child_link_name);
  int joint = -1;
  Pose joint_T_link = Pose::Identity();
  for (const urdf::JointConstSharedPtr& j : path) {
    if (moving(*j)) {
      ++joint;
      joint_T_link = Pose::Identity();
    } else {
      joint_T_link = joint_T_link * pose_of(j->parent_to_joint_origin_transform);
    }
    if (joint < 0) continue;
    add_hanging_masses(chain.joints[static_cast<std::size_t>(joint)], *model.getLink(j->child_link_name), joint_T_link,
                       on_path, chain.masses_from_urdf);
  }
  if (chain.masses_from_urdf) return;
  for (std::size_t i = 0; i < chain.joints.size(); ++i) {
    const Pose& next = i + 1 < chain.joints.size() ? chain.joints[i + 1].parent_T_joint : chain.last_T_flange;
    chain.joints[i].mass_kg = 8.0;
    chain.joints[i].com_m = 0.5 * next.translation();
  }
}

Pose motion(const ChainJoint& j, double theta) {
  Pose t = Pose::Identity();
  if (j.prismatic)
    t.translation() = j.axis * theta;
  else
    t.linear() = Eigen::AngleAxisd(theta, j.axis).toRotationMatrix();
  return t;
}

std::vector<double> joint_values(const ChainErrors& e, const std::vector<double>& q) {
  std::vector<double> theta(q.size());
  for (std::size_t i = 0; i < q.size(); ++i) theta[i] = q[i] * (1.0 + e.scale[i]) + e.zero[i];
  if (e.coupled_to >= 0)
    theta[static_cast<std::size_t>(e.coupled_to)] += e.coupling * q[static_cast<std::size_t>(e.coupled_from)];
  return theta;
}

}  // namespace

std::vector<Pose> joint_frames(const Chain& chain, const ChainErrors& e, const std::vector<double>& theta) {
  std::vector<Pose> frames(chain.joints.size());
  Pose t = Pose::Identity();
  for (std::size_t i = 0; i < chain.joints.size(); ++i) {
    const ChainJoint& j = chain.joints[i];
    t = t * j.parent_T_joint * small_motion(e.origin[i]) * motion(j, theta[i]);
    frames[i] = t;
  }
  return frames;
}

Pose small_motion(const Vector6& t_r) {
  Pose t = Pose::Identity();
  t.translation() = t_r.head<3>();
  const double angle = t_r.tail<3>().norm();
  if (angle > 0.0) t.linear() = Eigen::AngleAxisd(angle, t_r.tail<3>() / angle).toRotationMatrix();
  return t;
}

ChainErrors::ChainErrors(std::size_t joints)
    : origin(joints, Vector6::Zero()), zero(joints, 0.0), scale(joints, 0.0), compliance_rad_per_nm(joints, 0.0) {}

Chain read_chain(const std::string& urdf_path, const std::string& tip_link) {
  Chain chain;
  chain.urdf_path = urdf_path;
  std::ifstream in(urdf_path);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) throw std::runtime_error(urdf_path + ": cannot read it");
  chain.urdf_text = text.str();
  const urdf::ModelInterfaceSharedPtr model = parse(chain.urdf_text, urdf_path);
  chain.root_link = model->getRoot()->name;
  urdf::LinkConstSharedPtr tip = flange_link(*model, tip_link, urdf_path);
  chain.flange_link = tip->name;
  std::vector<urdf::JointConstSharedPtr> path;
  for (urdf::LinkConstSharedPtr link = tip; link->parent_joint; link = link->getParent())
    path.insert(path.begin(), link->parent_joint);
  Pose pending = Pose::Identity();
  for (const urdf::JointConstSharedPtr& j : path) {
    if (j->mimic) throw std::runtime_error(urdf_path + ": joint " + j->name + " is a mimic joint");
    if (j->type == urdf::Joint::FIXED) {
      pending = pending * pose_of(j->parent_to_joint_origin_transform);
      continue;
    }
    if (!moving(*j)) throw std::runtime_error(urdf_path + ": joint " + j->name + " is neither moving nor fixed");
    ChainJoint c;
    c.name = j->name;
    c.parent_T_joint = pending * pose_of(j->parent_to_joint_origin_transform);
    c.axis = Eigen::Vector3d(j->axis.x, j->axis.y, j->axis.z).normalized();
    c.prismatic = j->type == urdf::Joint::PRISMATIC;
    c.lower = j->type == urdf::Joint::CONTINUOUS ? -M_PI : j->limits->lower;
    c.upper = j->type == urdf::Joint::CONTINUOUS ? M_PI : j->limits->upper;
    chain.joints.push_back(c);
    pending = Pose::Identity();
  }
  if (chain.joints.empty()) throw std::runtime_error(urdf_path + ": no moving joint between the root and " + tip->name);
  chain.last_T_flange = pending;
  add_masses(chain, path, *model);
  return chain;
}

std::vector<double> gravity_torques(const Chain& chain, const ChainErrors& errors, const std::vector<double>& theta) {
  const std::vector<Pose> frames = joint_frames(chain, errors, theta);
  const Eigen::Vector3d gravity(0.0, 0.0, -9.81);
  std::vector<double> torque(chain.joints.size(), 0.0);
  Eigen::Vector3d moment_about_origin = Eigen::Vector3d::Zero();  // sum of c_k x m_k g beyond joint i
  Eigen::Vector3d force = Eigen::Vector3d::Zero();                // sum of m_k g beyond joint i
  for (std::size_t i = chain.joints.size(); i-- > 0;) {
    const ChainJoint& j = chain.joints[i];
    const Eigen::Vector3d com = frames[i] * j.com_m;
    moment_about_origin += com.cross(j.mass_kg * gravity);
    force += j.mass_kg * gravity;
    if (j.prismatic) continue;
    const Eigen::Vector3d p = frames[i].translation();
    torque[i] = (frames[i].linear() * j.axis).dot(moment_about_origin - p.cross(force));
  }
  return torque;
}

Pose forward(const Chain& chain, const ChainErrors& errors, const std::vector<double>& q) {
  std::vector<double> theta = joint_values(errors, q);
  bool compliant = false;
  for (double c : errors.compliance_rad_per_nm) compliant = compliant || c != 0.0;
  if (compliant) {
    const std::vector<double> torque = gravity_torques(chain, errors, theta);
    for (std::size_t i = 0; i < theta.size(); ++i) theta[i] += errors.compliance_rad_per_nm[i] * torque[i];
  }
  return joint_frames(chain, errors, theta).back() * chain.last_T_flange;
}

std::vector<std::pair<std::string, Pose>> fixed_joints_beyond_chain(const std::string& urdf_text,
                                                                    const std::string& last_moving_joint) {
  const urdf::ModelInterfaceSharedPtr model = parse(urdf_text, "a written URDF");
  const urdf::JointConstSharedPtr last = model->getJoint(last_moving_joint);
  if (!last) throw std::runtime_error("a written URDF has no joint " + last_moving_joint);
  std::vector<std::pair<std::string, Pose>> out;
  const std::function<void(const urdf::Link&)> visit = [&](const urdf::Link& link) {
    for (const urdf::JointSharedPtr& j : link.child_joints) {
      if (j->type == urdf::Joint::FIXED) out.emplace_back(j->name, pose_of(j->parent_to_joint_origin_transform));
      visit(*model->getLink(j->child_link_name));
    }
  };
  visit(*model->getLink(last->child_link_name));
  return out;
}

}  // namespace zoo

#include "host/model/urdf_chain.hpp"

#include <tinyxml2.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <map>
#include <set>
#include <unordered_map>

#include "host/files/input_file.hpp"
#include "host/model/axes.hpp"
#include "host/model/number_text.hpp"
#include "host/model/urdf_text.hpp"

namespace kincal::model {

namespace {

// Three numbers separated by white space ("0 0.1 -2e-3").
Vector3 parse_triple(const char* text, const std::string& source, int line, const std::string& what) {
  Vector3 v = Vector3::Zero();
  const char* p = text;
  const char* end = text + std::char_traits<char>::length(text);
  for (int i = 0; i < 3; ++i) {
    while (p != end && std::isspace(static_cast<unsigned char>(*p))) ++p;
    if (p != end && *p == '+') ++p;
    double value = 0.0;
    const auto [next, ec] = std::from_chars(p, end, value);
    if (ec != std::errc() || !std::isfinite(value))
      fail_at(source, line, what + " '" + text + "' is not three finite numbers");
    v[i] = value;
    p = next;
  }
  while (p != end && std::isspace(static_cast<unsigned char>(*p))) ++p;
  if (p != end) fail_at(source, line, what + " '" + text + "' is not three finite numbers");
  return v;
}

double parse_number(const char* text, const std::string& source, int line, const std::string& what) {
  const char* end = text + std::char_traits<char>::length(text);
  const char* p = text;
  while (p != end && std::isspace(static_cast<unsigned char>(*p))) ++p;
  if (p != end && *p == '+') ++p;
  double value = 0.0;
  const auto [next, ec] = std::from_chars(p, end, value);
  const char* rest = next;
  while (rest != end && std::isspace(static_cast<unsigned char>(*rest))) ++rest;
  if (ec != std::errc() || rest != end || !std::isfinite(value))
    fail_at(source, line, what + " '" + text + "' is not a finite number");
  return value;
}

std::string required_attribute(const tinyxml2::XMLElement& e, const char* name, const std::string& source) {
  const char* value = e.Attribute(name);
  if (value == nullptr || *value == '\0')
    fail_at(source, e.GetLineNum(), std::string("<") + e.Name() + "> without a '" + name + "' attribute");
  return value;
}

// A name (of the robot, a link, a joint; a link a joint names), as required_attribute, holding
// no control character: tinyxml2 reads one raw or as "&#1;", where XML 1.0 takes neither, and
// kincal writes these names into the URDFs it makes.
std::string required_name(const tinyxml2::XMLElement& e, const char* attribute, const std::string& source) {
  const std::string value = required_attribute(e, attribute, source);
  if (const std::size_t i = files::first_control_character(value); i != std::string::npos)
    fail_at(source, e.GetLineNum(),
            std::string("<") + e.Name() + "> " + attribute + ": " + files::control_character_text(value, i) +
                ": not XML 1.0 text");
  return value;
}

Transform parse_origin(const tinyxml2::XMLElement* origin, const std::string& source) {
  Transform t;
  if (origin == nullptr) return t;
  if (const char* xyz = origin->Attribute("xyz")) {
    t.translation = parse_triple(xyz, source, origin->GetLineNum(), "xyz");
    if (t.translation.norm() > kMaxOriginM)
      fail_at(source, origin->GetLineNum(),
              "an origin " + shortest_number_text(t.translation.norm()) + " m from its parent frame: more than " +
                  shortest_number_text(kMaxOriginM) + " m is not a robot's geometry");
  }
  if (const char* rpy = origin->Attribute("rpy"))
    t.rotation = rotation_from_rpy(parse_triple(rpy, source, origin->GetLineNum(), "rpy"));
  return t;
}

// Each element's place in document order (urdf_text.hpp): a pre-order walk of the tree.
using ElementIndex = std::unordered_map<const tinyxml2::XMLElement*, std::size_t>;
ElementIndex index_elements(const tinyxml2::XMLDocument& doc) {
  ElementIndex index;
  for (const tinyxml2::XMLElement* e = doc.FirstChildElement(); e != nullptr;) {
    index.emplace(e, index.size());
    const tinyxml2::XMLElement* next = e->FirstChildElement();
    for (const tinyxml2::XMLElement* up = e; next == nullptr && up != nullptr;
         up = up->Parent() != nullptr ? up->Parent()->ToElement() : nullptr)
      next = up->NextSiblingElement();
    e = next;
  }
  return index;
}

// What a joint's own values leave to say, by joint name: refusals that matter only when the
// joint is on the chain (its limits and axis are used nowhere else; urdfdom loads such a file),
// and warnings for the chain's joints.
struct JointFindings {
  std::map<std::string, std::pair<int, std::string>> refusals;  // line, reason
  std::map<std::string, std::string> warnings;                  // "FILE:LINE: what"
};

UrdfJoint parse_joint(const tinyxml2::XMLElement& e, const ElementIndex& index, const std::string& source,
                      JointFindings& findings) {
  UrdfJoint j;
  j.line = e.GetLineNum();
  j.element = index.at(&e);
  j.name = required_name(e, "name", source);
  const std::string type = required_attribute(e, "type", source);
  const std::string where = "joint '" + j.name + "'";
  if (type == "revolute") {
    j.type = UrdfJointType::revolute;
  } else if (type == "continuous") {
    j.type = UrdfJointType::continuous;
  } else if (type == "prismatic") {
    j.type = UrdfJointType::prismatic;
  } else if (type == "fixed") {
    j.type = UrdfJointType::fixed;
  } else if (type == "floating" || type == "planar") {
    j.type = UrdfJointType::fixed;
    j.lower = j.upper = std::numeric_limits<double>::quiet_NaN();  // marks "not a chain joint"
  } else {
    fail_at(source, j.line,
            where + " is of type '" + type +
                "', which URDF does not have (revolute, continuous, prismatic, fixed, floating, planar)");
  }
  const tinyxml2::XMLElement* parent = e.FirstChildElement("parent");
  const tinyxml2::XMLElement* child = e.FirstChildElement("child");
  if (parent == nullptr || child == nullptr) fail_at(source, j.line, where + " needs <parent> and <child>");
  j.parent_link = required_name(*parent, "link", source);
  j.child_link = required_name(*child, "link", source);
  const tinyxml2::XMLElement* origin = e.FirstChildElement("origin");
  j.parent_T_joint = parse_origin(origin, source);
  if (origin != nullptr) {
    j.origin_element = index.at(origin);
    j.origin_line = origin->GetLineNum();
  }
  if (const tinyxml2::XMLElement* axis = e.FirstChildElement("axis")) {
    if (const char* xyz = axis->Attribute("xyz")) {
      const Vector3 v = parse_triple(xyz, source, axis->GetLineNum(), where + ": axis");
      if (v.norm() < 1e-12 && j.type != UrdfJointType::fixed)
        findings.refusals.emplace(j.name, std::pair{axis->GetLineNum(), where + ": zero axis"});
      if (v.norm() >= 1e-12) j.axis = v.normalized();
    }
  }
  if (j.type == UrdfJointType::revolute || j.type == UrdfJointType::prismatic) {
    const tinyxml2::XMLElement* limit = e.FirstChildElement("limit");
    if (limit == nullptr) fail_at(source, j.line, where + " (" + type + ") needs a <limit>");
    const char* lower = limit->Attribute("lower");
    const char* upper = limit->Attribute("upper");
    const int line = limit->GetLineNum();
    if (lower != nullptr || upper != nullptr) {  // neither: no limits (urdf_chain.hpp)
      j.lower = lower != nullptr ? parse_number(lower, source, line, "lower") : 0.0;
      j.upper = upper != nullptr ? parse_number(upper, source, line, "upper") : 0.0;
    }
    if (j.lower == 0.0 && j.upper == 0.0) {  // CAD exporters' "not set" (urdf_chain.hpp)
      j.lower = -std::numeric_limits<double>::infinity();
      j.upper = std::numeric_limits<double>::infinity();
      findings.warnings.emplace(j.name, source + ":" + std::to_string(line) + ": " + where +
                                            ": limits 0 and 0 read as no limits given (as CAD exporters write "
                                            "them); give the joint's range if it has one");
    } else if (j.lower > j.upper) {
      findings.refusals.emplace(j.name, std::pair{line, where + ": lower limit above upper"});
    } else if (j.lower == j.upper) {
      findings.refusals.emplace(
          j.name, std::pair{line, where + ": lower and upper limits are equal (" + shortest_number_text(j.lower) +
                                      "), so the joint cannot move: make it fixed, or give its "
                                      "range"});
    }
  }
  return j;
}

// A link's <inertial>: its mass and centre of mass in the link's frame (none: mass 0).
struct Inertial {
  double mass_kg = 0.0;
  Vector3 centre_m = Vector3::Zero();
};

struct Tree {
  std::map<std::string, int> link_lines;
  std::map<std::string, Inertial> inertials;        // by link, those with a mass
  std::map<std::string, UrdfJoint> joint_to_child;  // by child link
  std::map<std::string, int> mimic_lines;           // by joint name
  std::map<std::string, std::string> type_names;    // joint name -> type text (for refusals)
  JointFindings findings;
  std::string robot_name;
  std::string root;  // the one link that is no joint's child
};

// The links form one tree (what urdfdom's initTree and initRoot demand, and a cycle wherever it
// is): every link has at most one parent by now; a link from which the way up never reaches a
// root is on or below a cycle, refused at the cycle's last joint in the file; then a second root
// is refused.
void check_one_tree(Tree& tree, const std::string& source) {
  std::map<std::string, int> state;  // 1: on the way up being walked, 2: reaches a root
  for (const auto& [start, line] : tree.link_lines) {
    std::vector<std::string> way;
    std::string link = start;
    for (;;) {
      const int s = state[link];
      if (s == 2) break;
      if (s == 1) {  // `link` is on a cycle: the joints from it up to it again
        std::vector<const UrdfJoint*> cycle;
        std::string names = link;
        for (std::string l = link; cycle.empty() || l != link;) {
          cycle.push_back(&tree.joint_to_child.at(l));
          l = cycle.back()->parent_link;
          names += " <- " + l;
        }
        const UrdfJoint* last = *std::max_element(
            cycle.begin(), cycle.end(), [](const UrdfJoint* a, const UrdfJoint* b) { return a->line < b->line; });
        fail_at(source, last->line,
                "joint '" + last->name + "' closes a cycle of links (" + names +
                    ", each the child of the next): a URDF's links form a tree");
      }
      state[link] = 1;
      way.push_back(link);
      const auto up = tree.joint_to_child.find(link);
      if (up == tree.joint_to_child.end()) break;  // a root
      link = up->second.parent_link;
    }
    for (const std::string& l : way) state[l] = 2;
  }
  std::vector<std::pair<int, std::string>> roots;  // by line
  for (const auto& [name, line] : tree.link_lines)
    if (!tree.joint_to_child.contains(name)) roots.emplace_back(line, name);
  std::sort(roots.begin(), roots.end());
  if (roots.size() > 1)
    fail_at(source, roots[1].first,
            "link '" + roots[1].second + "' is the child of no joint, as is link '" + roots[0].second +
                "': a URDF's links form one tree (connect it with a joint, or remove it)");
  tree.root = roots.front().second;
}

Tree parse_tree(const std::string& text, const std::string& source) {
  if (const std::size_t nul = text.find('\0'); nul != std::string::npos)
    fail_at(source,
            1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(nul), '\n')),
            "a NUL byte: not XML text (UTF-16?)");
  tinyxml2::XMLDocument doc;
  if (doc.Parse(text.c_str(), text.size()) != tinyxml2::XML_SUCCESS)
    fail_at(source, doc.ErrorLineNum(), std::string("XML: ") + doc.ErrorStr());
  const XmlTextMap map = map_xml_text(text);
  if (map.end < text.size())
    fail_at(source, map.end_line, "an end tag that closes no element: the rest of the file would be ignored");
  if (map.sealed_end_tag_line != 0)
    fail_at(source, map.sealed_end_tag_line, "'</' and '/>' around one tag: not XML (an end tag or an empty element?)");
  const tinyxml2::XMLElement* robot = doc.FirstChildElement("robot");
  if (robot == nullptr) fail_at(source, 1, "no <robot> element: not a URDF");
  Tree tree;
  if (robot->Attribute("name") == nullptr)
    fail_at(source, robot->GetLineNum(), "<robot> without a 'name' attribute, which URDF requires");
  tree.robot_name = robot->Attribute("name");
  if (const std::size_t i = files::first_control_character(tree.robot_name); i != std::string::npos)
    fail_at(source, robot->GetLineNum(),
            "<robot> name: " + files::control_character_text(tree.robot_name, i) + ": not XML 1.0 text");
  for (const tinyxml2::XMLElement* l = robot->FirstChildElement("link"); l; l = l->NextSiblingElement("link")) {
    const std::string name = required_name(*l, "name", source);
    if (const auto [first, added] = tree.link_lines.emplace(name, l->GetLineNum()); !added)
      fail_at(source, l->GetLineNum(),
              "link '" + name + "' defined twice (first on line " + std::to_string(first->second) + ")");
    if (const tinyxml2::XMLElement* inertial = l->FirstChildElement("inertial")) {
      const tinyxml2::XMLElement* mass = inertial->FirstChildElement("mass");
      if (mass == nullptr) continue;
      const std::string what = "link '" + name + "' <mass> value";
      const char* value = mass->Attribute("value");
      if (value == nullptr) fail_at(source, mass->GetLineNum(), what + ": missing");
      Inertial in;
      in.mass_kg = parse_number(value, source, mass->GetLineNum(), what);
      if (in.mass_kg < 0.0 || in.mass_kg > kMaxMassKg)
        fail_at(source, mass->GetLineNum(),
                what + " " + shortest_number_text(in.mass_kg) + " is not a link's mass (0 to " +
                    shortest_number_text(kMaxMassKg) + " kg)");
      in.centre_m = parse_origin(inertial->FirstChildElement("origin"), source).translation;
      tree.inertials.emplace(name, in);
    }
  }
  const ElementIndex index = index_elements(doc);
  std::map<std::string, int> joint_lines;
  for (const tinyxml2::XMLElement* e = robot->FirstChildElement("joint"); e; e = e->NextSiblingElement("joint")) {
    UrdfJoint j = parse_joint(*e, index, source, tree.findings);
    if (const auto [first, added] = joint_lines.emplace(j.name, j.line); !added)
      fail_at(source, j.line,
              "joint '" + j.name + "' defined twice (first on line " + std::to_string(first->second) + ")");
    for (const std::string* link : {&j.parent_link, &j.child_link})
      if (!tree.link_lines.contains(*link))
        fail_at(source, j.line, "joint '" + j.name + "' names link '" + *link + "', which is not defined");
    if (e->FirstChildElement("mimic") != nullptr)
      tree.mimic_lines[j.name] = e->FirstChildElement("mimic")->GetLineNum();
    tree.type_names[j.name] = e->Attribute("type");
    const std::string child = j.child_link;
    if (const auto other = tree.joint_to_child.find(child); other != tree.joint_to_child.end())
      fail_at(source, j.line,
              "link '" + child + "' is the child of joint '" + j.name + "' and of joint '" + other->second.name +
                  "' (line " + std::to_string(other->second.line) + "): a link has one parent in a URDF's tree");
    tree.joint_to_child.emplace(child, std::move(j));
  }
  if (tree.link_lines.empty()) fail_at(source, robot->GetLineNum(), "the robot has no links");
  check_one_tree(tree, source);
  return tree;
}

// The joints from `base` down to `tip` (empty when tip == base); false when base is not above
// tip. The links form a tree (check_one_tree), so the way up ends.
bool path_between(const Tree& tree, const std::string& base, const std::string& tip, std::vector<UrdfJoint>& out) {
  out.clear();
  std::string link = tip;
  while (link != base) {
    const auto it = tree.joint_to_child.find(link);
    if (it == tree.joint_to_child.end()) return false;
    out.push_back(it->second);
    link = it->second.parent_link;
  }
  std::reverse(out.begin(), out.end());
  return true;
}

// The mass of `link` and of the links hanging off it outside the chain (recursively, through
// fixed, revolute, continuous and prismatic joints at their zero), with their centre of mass in
// `link`'s frame.
UrdfMass rigid_mass(const Tree& tree, const std::map<std::string, std::vector<const UrdfJoint*>>& children,
                    const std::set<std::string>& on_chain, const std::string& link) {
  UrdfMass m;
  Vector3 moment = Vector3::Zero();
  std::vector<std::pair<std::string, Transform>> todo{{link, Transform{}}};
  while (!todo.empty()) {
    const auto [name, pose] = todo.back();
    todo.pop_back();
    if (const auto in = tree.inertials.find(name); in != tree.inertials.end()) {
      m.mass_kg += in->second.mass_kg;
      moment += in->second.mass_kg * (pose * in->second.centre_m);
    }
    if (const auto below = children.find(name); below != children.end())
      for (const UrdfJoint* j : below->second)
        if (!std::isnan(j->lower) && !on_chain.contains(j->child_link))  // NaN: floating or planar
          todo.emplace_back(j->child_link, pose * j->parent_T_joint);
  }
  if (m.mass_kg > 0.0) m.centre_m = moment / m.mass_kg;
  return m;
}

int movable(const std::vector<UrdfJoint>& joints) {
  return static_cast<int>(
      std::count_if(joints.begin(), joints.end(), [](const UrdfJoint& j) { return j.type != UrdfJointType::fixed; }));
}

}  // namespace

int UrdfChain::movable_count() const { return movable(joints); }

UrdfChain parse_urdf_chain(const std::string& text, const std::string& source, const UrdfChainEnds& ends) {
  const Tree tree = parse_tree(text, source);
  UrdfChain chain;
  chain.source = source;
  chain.robot_name = tree.robot_name;

  if (!ends.base_link.empty() && !tree.link_lines.contains(ends.base_link))
    fail_at(source, 1, "no link named '" + ends.base_link + "' (--base-link)");
  chain.base_link = ends.base_link.empty() ? tree.root : ends.base_link;

  std::vector<UrdfJoint> path;
  if (!ends.tip_link.empty()) {
    if (!tree.link_lines.contains(ends.tip_link))
      fail_at(source, 1, "no link named '" + ends.tip_link + "' (--tip-link)");
    if (!path_between(tree, chain.base_link, ends.tip_link, path))
      fail_at(source, tree.link_lines.at(ends.tip_link),
              "link '" + ends.tip_link + "' is not below link '" + chain.base_link + "'");
    chain.tip_link = ends.tip_link;
  } else {
    // Down the tree from the base, counting movable joints: each link once.
    std::map<std::string, std::vector<const UrdfJoint*>> children;  // by parent link
    for (const auto& [child, j] : tree.joint_to_child) children[j.parent_link].push_back(&j);
    std::map<std::string, int> joints_to;  // movable joints from the base to the link
    std::vector<std::string> todo{chain.base_link};
    joints_to[chain.base_link] = 0;
    struct Candidate {
      std::string tip;
      int joints;
    };
    std::vector<Candidate> leaves;
    while (!todo.empty()) {
      const std::string link = std::move(todo.back());
      todo.pop_back();
      const int here = joints_to.at(link);
      const auto below = children.find(link);
      if (below == children.end()) leaves.push_back({link, here});
      if (below != children.end())
        for (const UrdfJoint* j : below->second)
          if (joints_to.emplace(j->child_link, here + (j->type == UrdfJointType::fixed ? 0 : 1)).second)
            todo.push_back(j->child_link);
    }
    std::sort(leaves.begin(), leaves.end(), [](const Candidate& a, const Candidate& b) { return a.tip < b.tip; });
    int best = -1;
    for (const Candidate& c : leaves) best = std::max(best, c.joints);
    std::vector<std::string> best_tips;
    for (const Candidate& c : leaves)
      if (c.joints == best) best_tips.push_back(c.tip);
    if (best_tips.size() != 1) {
      std::string list;
      for (std::size_t i = 0; i < leaves.size() && i < kMaxListedChains; ++i)
        list += "\n  " + chain.base_link + " -> " + leaves[i].tip + " (" + std::to_string(leaves[i].joints) +
                " movable joints)";
      if (leaves.size() > kMaxListedChains)
        list += "\n  and " + std::to_string(leaves.size() - kMaxListedChains) + " more";
      fail_at(source, 1, "which chain? choose one with --tip-link (and --base-link):" + list);
    }
    chain.tip_link = best_tips.front();
    path_between(tree, chain.base_link, chain.tip_link, path);
  }
  chain.tip_line = tree.link_lines.at(chain.tip_link);
  for (const UrdfJoint& j : path) {
    if (std::isnan(j.lower))
      fail_at(source, j.line,
              "joint '" + j.name + "' is of type '" + tree.type_names.at(j.name) +
                  "': a serial chain has revolute, continuous, prismatic and fixed joints only");
    if (tree.mimic_lines.contains(j.name) && j.type != UrdfJointType::fixed)
      fail_at(source, tree.mimic_lines.at(j.name),
              "joint '" + j.name +
                  "' mimics another joint: chains with mimic joints are not supported "
                  "(calibrate the chain without it, or make it fixed)");
    if (const auto r = tree.findings.refusals.find(j.name); r != tree.findings.refusals.end())
      fail_at(source, r->second.first, r->second.second);
    if (const auto w = tree.findings.warnings.find(j.name); w != tree.findings.warnings.end())
      chain.warnings.push_back(w->second);
  }
  chain.joints = std::move(path);
  std::map<std::string, std::vector<const UrdfJoint*>> children;  // by parent link
  for (const auto& [child, j] : tree.joint_to_child) children[j.parent_link].push_back(&j);
  std::set<std::string> on_chain{chain.base_link};
  for (const UrdfJoint& j : chain.joints) on_chain.insert(j.child_link);
  for (const UrdfJoint& j : chain.joints) chain.masses.push_back(rigid_mass(tree, children, on_chain, j.child_link));
  return chain;
}

std::vector<Transform> urdf_link_poses(const UrdfChain& chain, std::span<const double> q) {
  std::vector<Transform> poses;
  Transform pose;
  std::size_t k = 0;
  for (const UrdfJoint& j : chain.joints) {
    pose = pose * j.parent_T_joint;
    if (j.type != UrdfJointType::fixed) {
      const double value = q[k++];
      Transform motion;
      if (j.type == UrdfJointType::prismatic) {
        motion.translation = value * j.axis;
      } else {
        motion.rotation = Eigen::AngleAxisd(value, j.axis).toRotationMatrix();
      }
      pose = pose * motion;
    }
    poses.push_back(pose);
  }
  return poses;
}

RobotModel model_from_urdf(const UrdfChain& chain) {
  const int n = chain.movable_count();
  if (n == 0)
    fail_at(chain.source, chain.tip_line,
            "no movable joint between '" + chain.base_link + "' and '" + chain.tip_link + "'");
  if (n > core::kMaxJoints)
    fail_at(chain.source, chain.tip_line,
            std::to_string(n) + " movable joints between '" + chain.base_link + "' and '" + chain.tip_link +
                "'; at most " + std::to_string(core::kMaxJoints));
  const std::vector<double> zero(static_cast<std::size_t>(n), 0.0);
  const std::vector<Transform> poses = urdf_link_poses(chain, zero);

  RobotModel tmpl;
  tmpl.name = chain.robot_name.empty() ? chain.tip_link : chain.robot_name;
  tmpl.tool = ToolKind::frame;
  std::vector<AxisLine> axes;
  for (std::size_t k = 0; k < chain.joints.size(); ++k) {
    const UrdfJoint& j = chain.joints[k];
    if (j.type == UrdfJointType::fixed) continue;
    const Transform parent = k == 0 ? Transform{} : poses[k - 1];
    if (axes.empty()) tmpl.base_T_frame0 = parent;
    const Transform joint_frame = parent * j.parent_T_joint;
    const bool prismatic = j.type == UrdfJointType::prismatic;
    axes.push_back({joint_frame.translation, joint_frame.rotation * j.axis,
                    prismatic ? core::JointType::prismatic : core::JointType::revolute});
    Joint joint;
    joint.name = j.name;
    joint.type = axes.back().type;
    joint.lower = j.lower;
    joint.upper = j.upper;
    tmpl.joints.push_back(joint);
  }
  RobotModel model = chain_from_axes(tmpl, axes, zero, poses.back());
  for (Joint& j : model.joints) {
    (j.type == core::JointType::revolute ? j.parameters.theta_rad : j.parameters.d_m) += j.offset;
    j.offset = 0.0;
  }
  // The flange (frame n) slid along the last axis to the last movable joint's child link, as
  // DH tables put it (a UR's d6): link n has a = alpha = 0 here, so Tz(s) moves to its end.
  const std::size_t last =
      static_cast<std::size_t>(std::find_if(chain.joints.rbegin(), chain.joints.rend(),
                                            [](const UrdfJoint& j) { return j.type != UrdfJointType::fixed; })
                                   .base() -
                               chain.joints.begin()) -
      1;
  const Transform flange = chain_at_joints(model, zero).frames.base_T_frame[static_cast<std::size_t>(n)];
  const double s = (poses[last].translation - flange.translation).dot(flange.rotation.col(2));
  model.joints.back().parameters.d_m += s;
  Transform slide;
  slide.translation = Vector3(0, 0, -s);
  model.flange_T_tool = slide * model.flange_T_tool;
  // The tip link is the flange (robot_model.hpp): the TCP there until told otherwise, and the
  // measured point there until identify estimates it.
  model.flange_link = chain.tip_link;
  model.frame_n_T_flange = model.flange_T_tool;
  model.flange_T_tcp = Transform{};
  // Masses: movable joint i moves its child link and the links fixed after it up to the next
  // movable joint; their centre of mass in frame i at the readings' zero, where the URDF's link
  // poses are known. Gravity: the base link's -z (REP 103), in frame 0.
  const core::ChainFrames<double> frames = chain_at_joints(model, zero).frames;
  std::vector<Vector3> moment(static_cast<std::size_t>(n), Vector3::Zero());
  int i = -1;
  for (std::size_t k = 0; k < chain.joints.size(); ++k) {
    if (chain.joints[k].type != UrdfJointType::fixed) ++i;
    if (i < 0 || chain.masses[k].mass_kg == 0.0) continue;
    const auto at = static_cast<std::size_t>(i);
    model.joints[at].mass_kg += chain.masses[k].mass_kg;
    moment[at] +=
        chain.masses[k].mass_kg * (frames.base_T_frame[at + 1].inverse() * (poses[k] * chain.masses[k].centre_m));
  }
  for (std::size_t j = 0; j < model.joints.size(); ++j)
    if (model.joints[j].mass_kg > 0.0) model.joints[j].centre_of_mass_m = moment[j] / model.joints[j].mass_kg;
  model.gravity_mps2 = model.base_T_frame0.rotation.transpose() * Vector3(0.0, 0.0, -kStandardGravity_mps2);
  return model;
}

bool is_urdf_path(const std::string& path) {
  if (path.size() < 5) return false;
  std::string ext = path.substr(path.size() - 5);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".urdf";
}

}  // namespace kincal::model

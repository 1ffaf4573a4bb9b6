#include "host/model/urdf.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <utility>

#include "host/files/input_file.hpp"
#include "host/model/axes.hpp"
#include "host/model/number_text.hpp"
#include "host/model/urdf_text.hpp"
#include "host/model/xml_text.hpp"

namespace kincal::model {

namespace {

std::string num(double v) { return shortest_number_text(v); }

std::string triple(const Vector3& v) { return num(v.x()) + " " + num(v.y()) + " " + num(v.z()); }

std::string origin(const Transform& t) {
  return "<origin xyz=\"" + triple(t.translation) + "\" rpy=\"" + triple(rpy_from_rotation(t.rotation)) + "\"/>";
}

Transform rx(double angle) {
  Transform t;
  t.rotation = Eigen::AngleAxisd(angle, Vector3::UnitX()).toRotationMatrix();
  return t;
}
Transform rz(double angle) {
  Transform t;
  t.rotation = Eigen::AngleAxisd(angle, Vector3::UnitZ()).toRotationMatrix();
  return t;
}
Transform translate(const Vector3& v) {
  Transform t;
  t.translation = v;
  return t;
}

}  // namespace

std::string write_urdf(const RobotModel& model) {
  const core::ChainModel<double> chain = to_chain(model);
  std::ostringstream out;
  out << "<?xml version=\"1.0\"?>\n";
  out << "<!-- kincal: geometry of '" << escape_xml_text(model.name)
      << "' in the joint origins; joint values are the controller's readings (SI units) -->\n";
  out << "<robot name=\"" << escape_xml_text(model.name) << "\">\n";
  out << "  <link name=\"device\"/>\n";
  Transform previous_s = chain.base_T_frame0;
  std::string parent = "device";
  for (int i = 0; i < model.joint_count(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    const core::Link<double>& link = chain.links[k];
    const core::LinkParameters<double>& p = link.parameters;
    Transform pre, post;
    if (link.convention == core::LinkConvention::modified_dh) {
      pre = rx(p.alpha_rad) * translate(Vector3(p.a_m, 0, 0));
      post = rz(p.theta_rad) * translate(Vector3(0, 0, p.d_m));
    } else {
      post = core::link_transform(link, 0.0);
    }
    const Joint& j = model.joints[k];
    const bool revolute = j.type == core::JointType::revolute;
    const bool limited = std::isfinite(j.lower) && std::isfinite(j.upper);
    const std::string child = "link" + std::to_string(i + 1);
    out << "  <link name=\"" << child << "\"/>\n";
    out << "  <joint name=\"" << escape_xml_text(j.name) << "\" type=\""
        << (revolute ? (limited ? "revolute" : "continuous") : "prismatic") << "\">\n";
    out << "    <parent link=\"" << parent << "\"/>\n    <child link=\"" << child << "\"/>\n";
    out << "    " << origin(previous_s * pre) << "\n    <axis xyz=\"0 0 1\"/>\n";
    if (limited || !revolute) {
      out << "    <limit lower=\"" << num(limited ? j.lower : -1e9) << "\" upper=\"" << num(limited ? j.upper : 1e9)
          << "\" effort=\"0\" velocity=\"0\"/>\n";
    }
    out << "  </joint>\n";
    previous_s = post;
    parent = child;
  }
  out << "  <link name=\"tool\"/>\n";
  out << "  <joint name=\"tool_mount\" type=\"fixed\">\n    <parent link=\"" << parent
      << "\"/>\n    <child link=\"tool\"/>\n";
  out << "    " << origin(previous_s * chain.flange_T_tool) << "\n  </joint>\n";
  out << "</robot>\n";
  return out.str();
}

namespace {

// `body_T_link` frame of a link a movable joint carries, moved onto the joint's calibrated axis
// line (point, unit direction) with `axis_in_link` along it: the smallest turn and, for a
// revolute joint, the slide along the axis to the foot of the perpendicular.
Transform onto_axis(const Transform& estimate, const Vector3& axis_in_link, const AxisLine& axis) {
  Transform t = estimate;
  const Vector3 direction = axis.direction.normalized();
  t.rotation = Eigen::Quaterniond::FromTwoVectors(estimate.rotation * axis_in_link, direction).toRotationMatrix() *
               estimate.rotation;
  if (axis.type == core::JointType::revolute)
    t.translation = axis.point + (estimate.translation - axis.point).dot(direction) * direction;
  return t;
}

// Below these an origin counts as unchanged and keeps its text. Above what the model's round
// trip through chain_from_axes leaves (about 2e-12 m on metre-long arms with skew axes, found
// by fuzz.urdf), and small enough that ten kept origins move a tool 2 m out by under 1e-9 m.
// Both are relative beyond a metre (times the arm's size, the farthest origin the round trip
// goes through: the links' and the models' frames, below): the round trip's error grows with
// the lengths upstream (a 405 m link moved the next joint's 0.4 m origin by 6e-11 m:
// fuzz.urdf, urdf_regressions/origin_405_m.urdf), and a frame's turn about an axis that nearly
// coincides with the next (1e-6 m apart, 3e-8 rad, 400 m out) is known to eps x size / their
// distance (1.6e-10 rad came back: urdf_regressions/nearly_parallel_axes_1e-6_m_apart.urdf).
constexpr double kUnchangedM = 1e-11;
constexpr double kUnchangedRad = 1e-11;

// The text for three numbers whose attribute held `old_text`: the old text with each number that
// moved by more than `tolerance` respelled, so that white space (tabs, several spaces, a line
// end inside the value) and the spelling of the numbers that did not move stay as they were.
// An old value that is not three numbers is replaced whole.
std::string triple_text(const Vector3& value, std::string_view old_text, double tolerance) {
  std::vector<std::pair<std::size_t, std::size_t>> numbers;  // [begin, end) in old_text
  for (std::size_t p = old_text.find_first_not_of(" \t\r\n"); p != std::string_view::npos;) {
    const std::size_t end = std::min(old_text.find_first_of(" \t\r\n", p), old_text.size());
    numbers.emplace_back(p, end);
    p = old_text.find_first_not_of(" \t\r\n", end);
  }
  if (numbers.size() != 3) return triple(value);
  std::string out(old_text.substr(0, numbers[0].first));
  for (std::size_t k = 0; k < 3; ++k) {
    const std::string_view old = old_text.substr(numbers[k].first, numbers[k].second - numbers[k].first);
    const std::string_view digits = old.starts_with('+') ? old.substr(1) : old;  // as the reader takes it
    double was = 0.0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), was);
    const auto i = static_cast<Eigen::Index>(k);
    const bool keep =
        ec == std::errc() && end == digits.data() + digits.size() && std::abs(was - value[i]) <= tolerance;
    out += keep ? std::string(old) : num(value[i]);
    const std::size_t next = k + 1 < 3 ? numbers[k + 1].first : old_text.size();
    out += old_text.substr(numbers[k].second, next - numbers[k].second);
  }
  return out;
}

struct Edit {
  std::size_t begin, end;
  std::string text;
};

// The element the reader put at `index`, checked against the text's own map.
const XmlElementSpan& element_at(const XmlTextMap& map, std::size_t index, std::string_view name, int line) {
  if (index >= map.elements.size() || map.elements[index].name != name || map.elements[index].line != line)
    throw std::logic_error("write_calibrated_urdf: the text's element " + std::to_string(index) + " is not the <" +
                           std::string(name) + "> tinyxml2 read on line " + std::to_string(line));
  return map.elements[index];
}

// The edits that give joint `j` the origin `o`: only what changed (an attribute value, a missing
// attribute or a missing <origin>; by more than kUnchangedM or kUnchangedRad times the arm's
// size `size_m`, at least a metre), nothing when nothing did.
void edit_origin(const std::string& text, const XmlTextMap& map, const UrdfJoint& j, const Transform& o, double size_m,
                 std::vector<Edit>& edits) {
  const double unchanged_m = kUnchangedM * size_m, unchanged_rad = kUnchangedRad * size_m;
  const bool move = (o.translation - j.parent_T_joint.translation).norm() > unchanged_m;
  const bool turn = Eigen::AngleAxisd(j.parent_T_joint.rotation.transpose() * o.rotation).angle() > unchanged_rad;
  if (!move && !turn) return;
  const XmlElementSpan& joint = element_at(map, j.element, "joint", j.line);
  if (j.origin_element == UrdfJoint::kNoElement) {
    const std::string q(1, joint.quote);
    edits.push_back({joint.start_tag_end, joint.start_tag_end,
                     "<origin xyz=" + q + triple(o.translation) + q + " rpy=" + q +
                         triple(rpy_from_rotation(o.rotation)) + q + "/>"});
    return;
  }
  const XmlElementSpan& origin = element_at(map, j.origin_element, "origin", j.origin_line);
  const auto set = [&](std::string_view name, const Vector3& value, double tolerance) {
    if (const XmlAttributeSpan* a = origin.attribute(name)) {
      const std::string_view old(text.data() + a->value_begin, a->value_end - a->value_begin);
      edits.push_back({a->value_begin, a->value_end, triple_text(value, old, tolerance)});
    } else {
      edits.push_back({origin.name_end, origin.name_end,
                       " " + std::string(name) + "=" + origin.quote + triple(value) + origin.quote});
    }
  };
  if (move) set("xyz", o.translation, unchanged_m);
  if (turn) set("rpy", rpy_from_rotation(o.rotation), unchanged_rad);
}

// The file's own line end: CRLF when its first line ends so.
std::string line_end(const std::string& text) {
  const std::size_t first_end = text.find('\n');
  return first_end != std::string::npos && first_end > 0 && text[first_end - 1] == '\r' ? "\r\n" : "\n";
}

// The new link `name` for the measured point and the fixed joint "<name>_joint" that places it
// in the tip link, inserted right after the <robot> start tag (links and joints may come in any
// order) with the file's own line end. Refused when the URDF has a link or joint of either name.
Edit measured_point_edit(const std::string& text, const XmlTextMap& map, const std::string& source,
                         const std::string& tip_link, const std::string& name, const Transform& tip_T_measured) {
  if (const std::size_t i = files::first_control_character(name); i != std::string::npos)
    throw InputError("the measured point's link name: " + files::control_character_text(name, i) +
                     ": a link name is printable text (XML takes none)");
  const std::string joint = name + "_joint";
  for (const XmlElementSpan& e : map.elements) {
    const XmlAttributeSpan* a = e.attribute("name");
    if (a == nullptr || (e.name != "link" && e.name != "joint")) continue;
    const std::string_view value(text.data() + a->value_begin, a->value_end - a->value_begin);
    if ((e.name == "link" && value == name) || (e.name == "joint" && value == joint))
      fail_at(source, e.line,
              "the URDF has a " + std::string(e.name) + " named '" + std::string(value) +
                  "' already: choose another name for the measured point's link");
  }
  if (map.elements.empty() || map.elements.front().name != "robot")
    throw std::logic_error("write_calibrated_urdf: the text's first element is not <robot>");
  const std::string eol = line_end(text);
  const std::string link = escape_xml_text(name);
  return {map.elements.front().start_tag_end, map.elements.front().start_tag_end,
          eol + "  <!-- kincal: the measured point (reflector, marker, board) the calibration identified -->" + eol +
              "  <link name=\"" + link + "\"/>" + eol + "  <joint name=\"" + escape_xml_text(joint) +
              "\" type=\"fixed\">" + eol + "    <parent link=\"" + escape_xml_text(tip_link) + "\"/>" + eol +
              "    <child link=\"" + link + "\"/>" + eol + "    " + origin(tip_T_measured) + eol + "  </joint>"};
}

std::string millimetres(double m) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(3);
  out << m * 1e3 << " mm";
  return out.str();
}

}  // namespace

std::string non_geometric_note(const RobotModel& model) {
  std::string joints;
  for (const Joint& j : model.joints)
    if (!j.coupling.empty() || j.scale || j.compliance) joints += (joints.empty() ? "" : ", ") + j.name;
  return joints.empty() ? ""
                        : "the joint map (coupling, scale, compliance) of " + joints +
                              " is not in this file: readings go in as they are";
}

CalibratedUrdf write_calibrated_urdf(const std::string& original_text, const std::string& source,
                                     const UrdfChainEnds& ends, const RobotModel& calibrated,
                                     const std::string& measured_point_link) {
  const UrdfChain chain = parse_urdf_chain(original_text, source, ends);
  const RobotModel nominal = model_from_urdf(chain);
  const int n = nominal.joint_count();
  if (calibrated.joint_count() != n)
    throw InputError(source + ": the chain " + chain.base_link + " -> " + chain.tip_link + " has " + std::to_string(n) +
                     " movable joints, the calibrated model " + std::to_string(calibrated.joint_count()));
  for (std::size_t i = 0; i < nominal.joints.size(); ++i)
    if (nominal.joints[i].type != calibrated.joints[i].type)
      throw InputError(source + ": joint '" + nominal.joints[i].name + "' and the calibrated model's joint " +
                       std::to_string(i + 1) + " are not of the same type");

  CalibratedUrdf result;
  if (const std::string note = non_geometric_note(calibrated); !note.empty()) result.notes.push_back(note);
  // Register: the calibrated frame 0 is put where the URDF's is.
  result.device_T_base_link = calibrated.base_T_frame0 * nominal.base_T_frame0.inverse();
  RobotModel registered = calibrated;
  registered.base_T_frame0 = nominal.base_T_frame0;
  const std::vector<double> zero(static_cast<std::size_t>(n), 0.0);
  // The calibrated geometry in the nominal's conventions, so that frame i means the same
  // place on body i in both.
  const RobotModel cal =
      chain_from_axes(nominal, joint_axes(registered, zero), zero, forward_kinematics(registered, zero));
  const std::vector<AxisLine> cal_axes = joint_axes(cal, zero);
  const core::ChainFrames<double> nominal_frames = chain_at_joints(nominal, zero).frames;
  const core::ChainFrames<double> cal_frames = chain_at_joints(cal, zero).frames;
  const Transform cal_tool = forward_kinematics(cal, zero);
  const auto body_moved = [&](int body, const Transform& nominal_pose) {
    const auto b = static_cast<std::size_t>(body);
    return cal_frames.base_T_frame[b] * nominal_frames.base_T_frame[b].inverse() * nominal_pose;
  };

  const std::vector<Transform> nominal_poses = urdf_link_poses(chain, zero);
  // The arm's size (kUnchangedM, kUnchangedRad): the farthest origin of the URDF's joints and of the models'
  // frames (axes 405 m out that meet 3.7 km away put frames there, and an unchanged origin came
  // back 6e-9 m off: fuzz.urdf, urdf_regressions/frames_3700_m_out.urdf).
  double size_m = 1.0;
  for (const Transform& pose : nominal_poses) size_m = std::max(size_m, pose.translation.norm());
  for (const core::ChainFrames<double>* frames : {&nominal_frames, &cal_frames})
    for (const Transform& frame : frames->base_T_frame) size_m = std::max(size_m, frame.translation.norm());
  // A body whose lines did not move (its own axis and the next, or the tool after the last) did not
  // move: it keeps its nominal pose exactly, however ill-conditioned the frames chain_from_axes
  // builds on those lines are (axes 3.7e-6 rad from parallel that meet: the frame's turn about its
  // axis came back 1.4e-10 rad off, fuzz.urdf, urdf_regressions/nearly_parallel_axes_meeting.urdf).
  const std::vector<AxisLine> nominal_axes = joint_axes(nominal, zero), registered_axes = joint_axes(registered, zero);
  const auto same_line = [&](std::size_t i) {
    const AxisLine &a = nominal_axes[i], &b = registered_axes[i];
    return a.type == b.type && (a.point - b.point).norm() <= kUnchangedM * size_m &&
           a.direction.cross(b.direction).norm() <= kUnchangedRad * size_m && a.direction.dot(b.direction) > 0.0;
  };
  const Transform nominal_tool = forward_kinematics(nominal, zero),
                  registered_tool = forward_kinematics(registered, zero);
  const bool same_tool = (nominal_tool.translation - registered_tool.translation).norm() <= kUnchangedM * size_m &&
                         (calibrated.tool == ToolKind::point ||
                          Eigen::AngleAxisd(nominal_tool.rotation.transpose() * registered_tool.rotation).angle() <=
                              kUnchangedRad * size_m);
  const auto body_unchanged = [&](std::size_t b) {  // body b >= 1 carries axis b and axis b+1 (or the tool)
    return same_line(b - 1) && (b < nominal_axes.size() ? same_line(b) : same_tool);
  };
  std::vector<Transform> poses(chain.joints.size());
  std::vector<bool> rewrite(chain.joints.size(), false);
  int body = 0;
  for (std::size_t k = 0; k < chain.joints.size(); ++k) {
    const UrdfJoint& j = chain.joints[k];
    const Transform parent = k == 0 ? Transform{} : poses[k - 1];
    if (j.type != UrdfJointType::fixed) {
      ++body;
      const auto b = static_cast<std::size_t>(body);
      poses[k] =
          body_unchanged(b) ? nominal_poses[k] : onto_axis(body_moved(body, nominal_poses[k]), j.axis, cal_axes[b - 1]);
      rewrite[k] = true;
    } else {
      poses[k] = parent * j.parent_T_joint;  // a fixed joint keeps its origin, wherever it is
    }
  }
  // The measured point or frame from the tip link: a link of its own when asked, else a note.
  Transform tip_T_measured = poses.back().inverse() * cal_tool;
  if (calibrated.tool == ToolKind::point) tip_T_measured.rotation.setIdentity();
  const double measured_turn = Eigen::AngleAxisd(tip_T_measured.rotation).angle();
  if (measured_point_link.empty() && (tip_T_measured.translation.norm() > 1e-9 * size_m || measured_turn > 1e-9))
    result.notes.push_back("the measured point (the model's tool) is " +
                           millimetres(tip_T_measured.translation.norm()) + " from the tip link '" + chain.tip_link +
                           "' and is no link of this URDF (ask for it as a link of its own: kincal urdf --marker-link "
                           "NAME); the tip link and every fixed joint keep their place");

  // Edit the text itself, so that everything but the chain's changed <origin> attributes stays
  // byte for byte (formatting, comments, quotes, attribute order, line ends, a byte-order mark).
  const XmlTextMap map = map_xml_text(original_text);
  std::vector<Edit> edits;
  for (std::size_t k = 0; k < chain.joints.size(); ++k) {
    if (!rewrite[k]) continue;
    const UrdfJoint& j = chain.joints[k];
    const Transform parent = k == 0 ? Transform{} : poses[k - 1];
    edit_origin(original_text, map, j, parent.inverse() * poses[k], size_m, edits);
  }
  if (!measured_point_link.empty())
    edits.push_back(
        measured_point_edit(original_text, map, source, chain.tip_link, measured_point_link, tip_T_measured));
  const Transform& r = result.device_T_base_link;
  std::string comment = " kincal: calibrated joint origins of the chain " + chain.base_link + " -> " + chain.tip_link +
                        " (model '" + calibrated.name + "'). " + chain.base_link +
                        " in the measuring device's frame (device_T_base_link): xyz=\"" + triple(r.translation) +
                        "\" rpy=\"" + triple(rpy_from_rotation(r.rotation)) + "\" ";
  for (const std::string& note : result.notes) comment += "Note: " + note + " ";
  for (std::size_t p = comment.find("--"); p != std::string::npos; p = comment.find("--")) comment.replace(p, 2, "- ");
  const std::string eol = line_end(original_text);
  edits.push_back({map.prolog_end, map.prolog_end,
                   (map.has_declaration ? eol : "") + "<!--" + comment + "-->" + (map.has_declaration ? "" : eol)});
  std::sort(edits.begin(), edits.end(), [](const Edit& a, const Edit& b) { return a.begin > b.begin; });
  result.text = original_text;
  for (const Edit& e : edits) result.text.replace(e.begin, e.end - e.begin, e.text);
  return result;
}

}  // namespace kincal::model

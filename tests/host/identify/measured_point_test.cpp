// The measured point, the flange and the TCP kept apart (issue #42): a tracker's reflector 102 mm
// off a 7-joint arm's flange and 57 mm off its last axis, no link of the URDF. Identified where the
// data were measured (the measured point estimated first), and written back into the robot's URDF
// without moving a fixed joint or a link beyond the chain.
#include <doctest.h>

#include <algorithm>
#include <map>
#include <string>

#include "host/identify/identify.hpp"
#include "host/model/urdf.hpp"
#include "reflector_arm.hpp"

using namespace kincal;

namespace {

// Every `<tag name="...">...</tag>` (or `<tag .../>`) element of a URDF text by name, as written.
std::map<std::string, std::string> elements(const std::string& text, const std::string& tag) {
  std::map<std::string, std::string> out;
  for (std::size_t p = text.find("<" + tag + " "); p != std::string::npos; p = text.find("<" + tag + " ", p + 1)) {
    const std::size_t name = text.find("name=\"", p) + 6;
    const std::size_t start_end = text.find('>', p);
    const std::size_t end =
        text[start_end - 1] == '/' ? start_end + 1 : text.find("</" + tag + ">", p) + tag.size() + 3;
    out[text.substr(name, text.find('"', name) - name)] = text.substr(p, end - p);
  }
  return out;
}

bool holds(const identify::ParameterIds& ids, core::ParameterId id) {
  return std::any_of(ids.begin(), ids.end(),
                     [&](core::ParameterId k) { return k.kind == id.kind && k.link == id.link; });
}

}  // namespace

TEST_CASE("reflector off the flange: identified where it was measured, the URDF's flange and hand kept") {
  const model::RobotModel nominal = test::reflector_arm_nominal();
  REQUIRE(nominal.joint_count() == 7);
  CHECK(nominal.flange_link == "flange");
  const model::RobotModel truth = test::reflector_arm_truth(7);
  const model::Dataset train = test::reflector_rows(truth, 150, 11, "train.csv");
  const model::Dataset held_out = test::reflector_rows(truth, 100, 12, "held_out.csv");

  identify::IdentifyOptions at_nominal;
  at_nominal.estimate_measured_point = false;  // as before: decided at the nominal tool
  const identify::IdentifyResult before = identify::identify(nominal, train, at_nominal);
  const identify::IdentifyResult r = identify::identify(nominal, train, identify::IdentifyOptions{});
  const double rms_before = identify::accuracy(before.model, held_out).rms_m;
  const double rms = identify::accuracy(r.model, held_out).rms_m;
  MESSAGE("held-out RMS: decided at the nominal tool "
          << rms_before * 1e3 << " mm (" << before.identifiability.identified.size()
          << " identified), at the estimated reflector " << rms * 1e3 << " mm (" << r.identifiability.identified.size()
          << ")");
  // What the reflector off the last axis sees and a point on it does not: link 6's parameters
  // (the last axis' tilt and offset), identified now and held fixed before.
  std::vector<std::string> gained;
  for (const core::ParameterId& id : r.identifiability.identified)
    if (!holds(before.identifiability.identified, id)) gained.push_back(model::parameter_name(id));
  std::string gained_text;
  for (const std::string& g : gained) gained_text += " " + g;
  MESSAGE("identified only at the estimated reflector:" << gained_text);
  CHECK(std::any_of(gained.begin(), gained.end(), [](const std::string& g) { return g.ends_with("6"); }));
  CHECK(rms < rms_before);
  CHECK(rms < 3 * 2e-5 * std::sqrt(3.0));  // within the tracker's noise (0.02 mm per axis)
  // The measured point, from the flange: where the reflector is, to the last link's errors.
  CHECK((model::flange_T_measured(r.model).translation - test::reflector_in_flange()).norm() < 2e-3);

  // --params naming what the reflector sees is identified, not refused.
  identify::IdentifyOptions requested;
  requested.requested = {"base", "tool_x", "tool_y", "tool_z", gained.front()};
  CHECK_NOTHROW(identify::identify(nominal, train, requested));

  // The calibrated URDF: only the movable joints' origins change; every fixed joint (the flange's,
  // the hand's -45 deg, the TCP's, the finger's) and every link byte for byte.
  const std::string text = test::reflector_arm_urdf();
  const model::CalibratedUrdf out = model::write_calibrated_urdf(text, "arm7.urdf", {"", "flange"}, r.model);
  const auto joints_in = elements(text, "joint"), joints_out = elements(out.text, "joint");
  REQUIRE(joints_out.size() == joints_in.size());
  int moved = 0;
  for (const auto& [name, element] : joints_in) {
    CAPTURE(name);
    if (element.find("type=\"fixed\"") != std::string::npos) CHECK(joints_out.at(name) == element);
    moved += joints_out.at(name) != element ? 1 : 0;
  }
  CHECK(moved > 0);
  CHECK(elements(out.text, "link") == elements(text, "link"));
  REQUIRE(out.notes.size() == 1);
  CHECK(out.notes[0].find("measured point") != std::string::npos);

  // Asked for, the reflector is a link of its own, where the calibrated model puts it.
  const model::CalibratedUrdf marked =
      model::write_calibrated_urdf(text, "arm7.urdf", {"", "flange"}, r.model, "reflector");
  CHECK(marked.notes.empty());
  const model::UrdfChain to_reflector = model::parse_urdf_chain(marked.text, "marked.urdf", {"", "reflector"});
  for (const model::Measurement& m : held_out.rows) {
    const model::Vector3 urdf_point = marked.device_T_base_link * urdf_link_poses(to_reflector, m.q).back().translation;
    CHECK((urdf_point - model::forward_kinematics(r.model, m.q).translation).norm() < 1e-9);
  }
  CHECK_THROWS_WITH_AS(model::write_calibrated_urdf(text, "arm7.urdf", {"", "flange"}, r.model, "hand"),
                       doctest::Contains("a link named 'hand' already"), model::InputError);
}

TEST_CASE("a SCARA's reflector: estimated first where its height along the parallel axes cannot be told") {
  // R R P R, every axis vertical: the reflector's height is the registration's and the quill's.
  const std::string urdf = R"(<robot name="scara">
  <link name="base_link"/><link name="l1"/><link name="l2"/><link name="quill"/><link name="flange"/>
  <joint name="j1" type="revolute"><parent link="base_link"/><child link="l1"/><origin xyz="0 0 0.4"/>
    <axis xyz="0 0 1"/><limit lower="-2.9" upper="2.9" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.325 0 0"/>
    <axis xyz="0 0 1"/><limit lower="-2.6" upper="2.6" effort="1" velocity="1"/></joint>
  <joint name="j3" type="prismatic"><parent link="l2"/><child link="quill"/><origin xyz="0.275 0 0"/>
    <axis xyz="0 0 -1"/><limit lower="0" upper="0.2" effort="1" velocity="1"/></joint>
  <joint name="j4" type="revolute"><parent link="quill"/><child link="flange"/><origin xyz="0 0 -0.05"/>
    <axis xyz="0 0 -1"/><limit lower="-6.28" upper="6.28" effort="1" velocity="1"/></joint>
</robot>)";
  const model::RobotModel nominal = model::model_from_urdf(model::parse_urdf_chain(urdf, "scara.urdf", {"", "flange"}));
  model::RobotModel truth = nominal;
  model::Transform reflector;
  reflector.translation = model::Vector3(0.06, 0.02, -0.03);
  truth.flange_T_tool = nominal.frame_n_T_flange * reflector;
  truth.tool = model::ToolKind::point;
  truth.base_T_frame0.translation = model::Vector3(1.5, -0.7, 0.2);
  truth.base_T_frame0.rotation = model::rotation_from_rpy(model::Vector3(0.1, -0.2, 1.9));
  const model::Dataset train = test::reflector_rows(truth, 60, 21, "train.csv");
  const identify::IdentifyResult r = identify::identify(nominal, train, identify::IdentifyOptions{});
  const bool estimated = std::any_of(r.notes.begin(), r.notes.end(), [](const std::string& n) {
    return n.find("the measured point first, at the nominal geometry: 63.") != std::string::npos;
  });
  CHECK(estimated);  // 63.2 mm from the flange in the plane the data see; its height held
  CHECK(holds(r.identifiability.identified, {core::ParameterKind::tool_x, 0}));
  CHECK_FALSE(holds(r.identifiability.identified, {core::ParameterKind::tool_z, 0}));
  CHECK(r.residuals.rms_m < 5e-5);
}

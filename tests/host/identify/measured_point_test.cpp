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

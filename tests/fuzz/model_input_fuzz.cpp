// libFuzzer target for the host's three text readers (issues #16, #23): the dataset CSV reader,
// the robot model YAML reader and `kincal plan --constraints`' reader. The first input byte
// selects the reader (modulo 3); the rest is the file's text.
//   0  parse_dataset: either InputError or a dataset that write_dataset writes and parse_dataset
//      reads back to the same numbers (shortest exact form)
//   1  parse_model: either InputError or a model whose write_model text reads back as the same
//      robot (joints, name, tool kind; the numbers pass through rpy and decimal text, so they
//      are not compared bit for bit)
//   2  parse_plan_constraints for the Stanford arm (stanford_rrp.yaml: two revolute joints and a
//      prismatic one, limits of its own): either InputError or constraints that keep the
//      header's contract -- at least one constraint, every number finite, a box with min below
//      max, a unit floor normal and sight axis, a half angle in (0, pi), joint indices of the
//      model and distinct, each range with lower below upper inside the joint's limits -- and
//      that describe() and violated_constraints() take at the middle of the limits
// Any other exception, a crash, a leak or undefined behaviour is a finding. Runs standalone too
// (file arguments), and as the ctest fuzz.model_input for a bounded time.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "host/identify/plan_constraints.hpp"
#include "host/model/dataset.hpp"
#include "host/model/model_file.hpp"

using namespace kincal;

namespace {

void require(bool condition) {
  if (!condition) std::abort();
}

void fuzz_dataset(const std::string& text) {
  model::Dataset d;
  try {
    std::istringstream in(text);
    d = model::parse_dataset(in, "fuzz.csv");
  } catch (const model::InputError&) {
    return;
  }
  std::ostringstream out;
  model::write_dataset(out, d);
  std::istringstream again(out.str());
  const model::Dataset e = model::parse_dataset(again, "again.csv");
  require(e.rows.size() == d.rows.size() && e.joint_count == d.joint_count);
  for (std::size_t i = 0; i < d.rows.size(); ++i) {
    require(e.rows[i].q == d.rows[i].q);
    require(e.rows[i].position == d.rows[i].position);
  }
}

void fuzz_model(const std::string& text) {
  model::RobotModel m;
  try {
    m = model::parse_model(text, "fuzz.yaml");
  } catch (const model::InputError&) {
    return;
  }
  // What kincal writes it must read (an InputError here escapes and is a finding), the same robot.
  const model::RobotModel again = model::parse_model(model::write_model(m), "again.yaml");
  require(again.joint_count() == m.joint_count() && again.name == m.name && again.tool == m.tool);
}

bool unit(const model::Vector3& v) { return v.allFinite() && std::abs(v.norm() - 1.0) < 1e-12; }

void fuzz_plan_constraints(const std::string& text) {
  static const model::RobotModel robot = model::load_model(KINCAL_ROBOTS_DIR "/stanford_rrp.yaml");
  identify::PlanConstraints c;
  try {
    c = identify::parse_plan_constraints(text, "fuzz.yaml", robot);
  } catch (const model::InputError&) {
    return;
  }
  require(c.workspace || c.floor || !c.joint_ranges.empty() || c.sight);
  if (c.workspace)
    require(c.workspace->min_m.allFinite() && c.workspace->max_m.allFinite() &&
            (c.workspace->min_m.array() < c.workspace->max_m.array()).all());
  if (c.floor) require(c.floor->point_m.allFinite() && unit(c.floor->normal));
  if (c.sight)
    require(c.sight->apex_m.allFinite() && unit(c.sight->axis) && c.sight->half_angle_rad > 0.0 &&
            c.sight->half_angle_rad < std::numbers::pi);
  std::set<int> joints;
  for (const identify::JointRange& r : c.joint_ranges) {
    require(r.joint >= 0 && r.joint < robot.joint_count() && joints.insert(r.joint).second);
    const model::Joint& j = robot.joints[static_cast<std::size_t>(r.joint)];
    require(std::isfinite(r.lower) && std::isfinite(r.upper) && r.lower < r.upper && r.lower >= j.lower &&
            r.upper <= j.upper);
  }
  for (const identify::Constraint k : identify::kConstraints) {
    const bool given = k == identify::Constraint::joint_limits ||
                       (k == identify::Constraint::joint_ranges && !c.joint_ranges.empty()) ||
                       (k == identify::Constraint::workspace && c.workspace) ||
                       (k == identify::Constraint::floor && c.floor) || (k == identify::Constraint::sight && c.sight);
    if (given) require(!identify::describe(k, c, robot).empty());
  }
  std::vector<double> q;
  for (const model::Joint& j : robot.joints) q.push_back(0.5 * (j.lower + j.upper));
  const unsigned violated = identify::violated_constraints(robot, c, q);
  require((violated & 1u) == 0);  // the middle of the limits is within them
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  if (data[0] % 3 == 0)
    fuzz_dataset(text);
  else if (data[0] % 3 == 1)
    fuzz_model(text);
  else
    fuzz_plan_constraints(text);
  return 0;
}

// libFuzzer target for the host's text readers of robot data (issues #16, #23, #24): the dataset
// CSV reader, the robot model YAML reader, `kincal plan --constraints`' reader, and `kincal
// correct`'s target tables and URScript programs. The first input byte selects the reader
// (modulo 5); the rest is the file's text.
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
//   3  parse_target_table for 3 joints, at most 50 rows: either InputError or a table of 1 to 50
//      rows on increasing lines, each with 3 finite readings (joint targets) or none or 3 (a
//      Cartesian target's seed), a finite point and a rotation orthonormal to 1e-9
//   4  parse_urscript for 3 joints, at most 50 motions: either InputError or literals (a motion's
//      own or a variable's) whose bracketed values lie apart inside the text; writing each
//      target back (readings, or x,y,z and the rotation vector) and reading the result gives the
//      same targets, and the text outside the brackets is kept byte for byte
// Any other exception, a crash, a leak or undefined behaviour is a finding. Runs standalone too
// (file arguments), and as the ctest fuzz.model_input for a bounded time.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "host/correct/target_table.hpp"
#include "host/correct/urscript.hpp"
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

bool finite_pose(const model::Transform& pose) {
  const Eigen::Matrix3d r(pose.rotation);
  return pose.translation.allFinite() && r.allFinite() &&
         (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-9;
}

void fuzz_target_table(const std::string& text) {
  correct::TargetTable t;
  try {
    t = correct::parse_target_table(text, "fuzz.csv", 3, 50);
  } catch (const model::InputError&) {
    return;
  }
  require(!t.rows.empty() && t.rows.size() <= 50 && (t.cartesian || !t.orientation));
  int line = 0;
  for (const correct::TargetRow& row : t.rows) {
    require(row.line > line);
    line = row.line;
    require(row.q.size() == 3 || (t.cartesian && row.q.empty()));
    for (const double v : row.q) require(std::isfinite(v));
    if (t.cartesian) require(finite_pose(row.pose));
  }
}

void fuzz_urscript(const std::string& text) {
  correct::UrProgram p;
  try {
    p = correct::parse_urscript(text, "fuzz.script", 3, 50);
  } catch (const model::InputError&) {
    return;
  }
  require(p.motions.size() <= 50);
  // The literals' bracketed values lie in the text, apart from each other.
  const auto text_order = [](const correct::UrProgram& program) {
    std::vector<std::size_t> order(program.literals.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return program.literals[a].begin < program.literals[b].begin; });
    return order;
  };
  const std::vector<std::size_t> order = text_order(p);
  std::size_t after = 0;
  for (const std::size_t i : order) {
    const correct::UrLiteral& l = p.literals[i];
    require(l.begin >= after && l.begin <= l.end && l.end <= p.text.size() && l.values.size() == l.numbers.size());
    after = l.end;
  }
  // Each motion's target written back (readings, or x,y,z and the rotation vector), a seed as read.
  std::vector<std::vector<double>> values;
  for (const correct::UrLiteral& l : p.literals) values.push_back(l.numbers);
  for (const correct::UrMotion& m : p.motions) {
    require(m.literal < p.literals.size() && (!m.seed || *m.seed < p.literals.size()));
    if (!m.target.cartesian) {
      require(m.target.q.size() == 3);
      values[m.literal] = m.target.q;
      continue;
    }
    require(finite_pose(m.target.pose));
    const Eigen::AngleAxisd r{Eigen::Matrix3d(m.target.pose.rotation)};
    const Eigen::Vector3d v = r.angle() * r.axis();
    const model::Vector3& x = m.target.pose.translation;
    values[m.literal] = {x.x(), x.y(), x.z(), v.x(), v.y(), v.z()};
  }
  const std::string written = correct::write_urscript(p, values);
  const correct::UrProgram again = correct::parse_urscript(written, "again.script", 3, 50);
  require(again.motions.size() == p.motions.size() && again.literals.size() == p.literals.size());
  for (std::size_t i = 0; i < p.motions.size(); ++i) {
    const correct::Target &a = p.motions[i].target, &b = again.motions[i].target;
    require(a.line == b.line && a.cartesian == b.cartesian && a.q == b.q);
    require(a.pose.translation == b.pose.translation);
    require((Eigen::Matrix3d(a.pose.rotation) - Eigen::Matrix3d(b.pose.rotation)).cwiseAbs().maxCoeff() < 1e-9);
  }
  // Outside the brackets, byte for byte: the text before each literal's values, and after the last.
  std::size_t from = 0, again_from = 0;
  for (const std::size_t i : order) {
    const correct::UrLiteral &l = p.literals[i], &m = again.literals[i];
    require(p.text.compare(from, l.begin - from, written, again_from, m.begin - again_from) == 0);
    from = l.end, again_from = m.end;
  }
  require(p.text.compare(from, std::string::npos, written, again_from, std::string::npos) == 0);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  switch (data[0] % 5) {
    case 0:
      fuzz_dataset(text);
      break;
    case 1:
      fuzz_model(text);
      break;
    case 2:
      fuzz_plan_constraints(text);
      break;
    case 3:
      fuzz_target_table(text);
      break;
    default:
      fuzz_urscript(text);
  }
  return 0;
}

// host/correct's files (issue #24): target tables refused with FILE:LINE:COLUMN, and a URScript
// program's round trip -- every line but the targets byte for byte (CRLF kept), the corrected
// targets equal to the CSV path's.
#include <doctest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <Eigen/Geometry>

#include "host/correct/target_table.hpp"
#include "host/correct/urscript.hpp"
#include "host/model/model_file.hpp"
#include "host/model/number_text.hpp"

using namespace kincal;

namespace {

model::RobotModel robot(const char* file) { return model::load_model(std::string(KINCAL_ROBOTS_DIR) + "/" + file); }

std::string refusal(const std::string& text, int joints) {
  try {
    correct::parse_target_table(text, "t.csv", joints);
  } catch (const model::InputError& e) {
    return e.what();
  }
  return "accepted";
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    out.push_back(text.substr(start, end + 1 - start));
    start = end + 1;
  }
  return out;
}

// Numbers as a CSV row ("," between) or a URScript list (", " between).
std::string numbers(const std::vector<double>& v, const char* between = ",") {
  std::string s;
  for (double x : v) s += (s.empty() ? "" : between) + model::shortest_number_text(x);
  return s;
}

std::string list(const std::vector<double>& v) { return numbers(v, ", "); }

// A pose as URScript writes it: x, y, z and the rotation vector.
std::vector<double> rotvec(const model::Transform& t) {
  const Eigen::AngleAxisd r{Eigen::Matrix3d(t.rotation)};
  const Eigen::Vector3d v = r.angle() * r.axis();
  return {t.translation.x(), t.translation.y(), t.translation.z(), v.x(), v.y(), v.z()};
}

std::string urscript_refusal(const std::string& text) {
  try {
    correct::parse_urscript(text, "p.script", 6);
  } catch (const model::InputError& e) {
    return e.what();
  }
  return "accepted";
}

// Why the first motion a program leaves as written is left ("none" when it leaves none).
std::string urscript_left(const std::string& text) {
  const correct::UrProgram p = correct::parse_urscript(text, "p.script", 6);
  return p.left.empty() ? "none" : p.left.front().why;
}

// The UR10 the URScript tests correct for: its nominal (ur10.yaml), a calibration of it, and the
// nominal arm in frame 0, where a program's poses are.
struct Ur10 {
  model::RobotModel start = robot("ur10.yaml"), calibrated = start, arm = start;
  Ur10() {
    calibrated.joints[1].parameters.a_m += 2e-3;
    calibrated.joints[2].offset += 1.5e-3;
    calibrated.joints[4].parameters.alpha_rad -= 1e-3;
    calibrated.flange_T_tool.translation.z() += 1e-3;
    arm.base_T_frame0 = model::Transform{};
  }
};

}  // namespace

TEST_CASE("target tables: joint and Cartesian targets read; bad tables refused with file:line:column") {
  const correct::TargetTable j =
      correct::parse_target_table("# taught\r\nq1,q2,q3\r\n0.1,0.2,0.3\r\n\r\n1,2,3\r\n", "t.csv", 3);
  CHECK_FALSE(j.cartesian);
  REQUIRE(j.rows.size() == 2);
  CHECK(j.rows[1].line == 5);
  // A cap on the rows (plan --candidates'), refused at the row past it.
  CHECK(correct::parse_target_table("q1\n0\n1\n", "t.csv", 1, 2).rows.size() == 2);
  CHECK_THROWS_WITH_AS(correct::parse_target_table("q1\n0\n# note\n1\n2\n", "t.csv", 1, 2),
                       "t.csv:5:1: more than 2 targets, the most this command takes", model::InputError);
  CHECK(j.rows[1].q == std::vector<double>{1, 2, 3});
  const correct::TargetTable c = correct::parse_target_table("x,y,z,qw,qx,qy,qz\n1,2,3,0,1,0,0\n", "t.csv", 3);
  CHECK(c.cartesian);
  CHECK(c.orientation);
  CHECK(c.rows[0].q.empty());
  CHECK(c.rows[0].pose.rotation(1, 1) == doctest::Approx(-1.0));

  CHECK(refusal("q1,q2,q3\n0.1,nan,0.3\n", 3) == "t.csv:2:5: column q2: nan is not finite");
  CHECK(refusal("q1,q2,q3\n0.1,0.2,abc\n", 3) == "t.csv:2:9: column q3: 'abc' is not a number");
  CHECK(refusal("q1,q2,q3\n0.1,,0.3\n", 3) == "t.csv:2:5: column q2 is empty");
  CHECK(refusal("q1,q2,q3\n0.1,0.2\n", 3) == "t.csv:2:1: 2 fields, the header (line 1) has 3");
  CHECK(refusal("q1,q2\n0.1,0.2\n", 3).find("t.csv:1:1: header: 2 joint columns, the model has 3 joints") == 0);
  CHECK(refusal("q1,q2,q3,q4\n0.1,0.2,0.3,0.4\n", 3).find("t.csv:1:10: header: unknown column 'q4'") == 0);
  CHECK(refusal("x,y,q1\n1,2,3\n", 3).find("t.csv:1:1: header: x, y and z go together") == 0);
  CHECK(refusal("x,y,z,qw\n1,2,3,1\n", 3).find("qw, qx, qy and qz go together") != std::string::npos);
  CHECK(refusal("x,y,z,qw,qx,qy,qz\n1,2,3,1,1,0,0\n", 3).find("t.csv:2:7: the quaternion's norm") == 0);
  CHECK(refusal("q1,q1,q2\n", 3).find("t.csv:1:4: header: column 'q1' appears twice") == 0);
  CHECK(refusal("q1,q2,q3\n", 3) == "t.csv:1:1: no targets after the header");
  CHECK(refusal("", 3).find("t.csv:1:1: no header row") == 0);
}

TEST_CASE("URScript: refused targets and the ones left as written name file:line:column") {
  const auto refused = urscript_refusal;
  const auto left = urscript_left;  // a target computed when the program runs: left as written, named
  CHECK(left("def p():\n  movej(home_q, a=1.4)\nend\n")
            .find("p.script:2:9: movej's target home_q is not assigned in this program") == 0);
  CHECK(left("def p():\n  movel(pose_add(base, p[0, 0, 1, 0, 0, 0]))\nend\n")
            .find("p.script:2:9: movel's target is not a literal [...] or p[...], a variable assigned one") == 0);
  CHECK(refused("  movej([1, 2, 3])\n").find("p.script:1:9: movej: 3 joint values, the model has 6 joints") == 0);
  CHECK(refused("  movel(p[1, 2, 3, 0, 0])\n").find("p.script:1:10: movel: a pose") == 0);
  CHECK(refused("movej([d2r(90), 0, 0, 0, 0, 0])\n")
            .find("p.script:1:8: column movej value 1: 'd2r(90)' is not a number") == 0);
  CHECK(refused("  # movej(home)\n  textmsg(\"movej\")\n  my_movej(1)\n") == "accepted");
  // A motion left as written takes nothing from the program; the others are read as ever.
  const correct::UrProgram some_left = correct::parse_urscript(
      "def p():\n  movej(get_actual_joint_positions())\n  movej([0, 0, 0, 0, 0, 0])\n  movec(w, p[0, 0, 1, 0, 0, 0])\n"
      "end\n",
      "p.script", 6);
  CHECK(some_left.motions.size() == 1);
  CHECK(some_left.literals.size() == 1);
  REQUIRE(some_left.left.size() == 2);
  CHECK(some_left.left[0].line == 2);
  CHECK(some_left.left[1].call == "movec");
  CHECK(some_left.left[1].why.find("p.script:4:9: movec's target w is not assigned in this program") == 0);
  // Strings are not code: a motion written in one is text, a '#' in one starts no comment, and an
  // escaped quote does not end one (the audit's finding: a textmsg's movej was rewritten).
  const std::string q6 = "[0.1, -0.4, 0.3, 0.2, -0.5, 0.7]";
  for (const std::string& text :
       {"textmsg(\"movej(" + q6 + ")\")\n", "textmsg('movel(p" + q6 + ")')\n",
        "popup(\"say \\\"movej(" + q6 + ")\\\" # not a comment\")\n", "s = \"servoj(\" # movej(" + q6 + ")\n"})
    CHECK(correct::parse_urscript(text, "p.script", 6).motions.empty());
  const correct::UrProgram after_string =
      correct::parse_urscript("textmsg(\"# movej(\") movej(" + q6 + ", a=1)\n", "p.script", 6);
  REQUIRE(after_string.motions.size() == 1);
  CHECK(after_string.literals[after_string.motions[0].literal].begin == 27);
  CHECK(refused("textmsg(\"movej(" + q6 + "))\n") == "p.script:1:9: a string is not closed on its line");
  CHECK(refused("movej(" + q6 + ", a=1) # don't\nx = 'it''s'\ny = 'a\\'\n") ==
        "p.script:3:5: a string is not closed on its line");
  // A target that goes on past its literal is an expression: refused, not corrected as the literal.
  for (const std::string rest : {" + [0.01, 0, 0, 0, 0, 0])", "*2)", "[0])", " ", ""})
    CHECK(left("movej(" + q6 + rest + "\n")
              .find("p.script:1:" + std::to_string(39 + (rest[0] == ' ')) +
                    ": movej's target goes on past its literal") == 0);
  CHECK(refused("movel(p" + q6 + " , a=1)\nmovej(" + q6 + ")\nservoj( " + q6 + "\t)\n") == "accepted");
  // A rotation vector beyond a turn: degrees given as radians, or one whose norm overflows.
  CHECK(refused("movel(p[0.5, 0, 0.5, 0, 180, 0])\n")
            .find("p.script:1:8: movel: the rotation vector's angle is 180 rad, more than a turn") == 0);
  CHECK(
      refused("movel(p[0.5, 0, 0.5, 1e300, 0, 1e300])\n").find("p.script:1:8: movel: the rotation vector's angle is") ==
      0);
  CHECK(refused("movel(p[0.5, 0, 0.5, 0, 3.14159, 0])\n") == "accepted");
  // More motions than the command takes: the one past the limit is named.
  CHECK(correct::parse_urscript("movej([0, 0, 0, 0, 0, 0])\nmovel(p[0, 0, 1, 0, 0, 0])\n", "p.script", 6, 2)
            .motions.size() == 2);
  CHECK_THROWS_WITH_AS(
      correct::parse_urscript("movej([0, 0, 0, 0, 0, 0])\n# x\nmovel(p[0, 0, 1, 0, 0, 0])\n", "p.script", 6, 1),
      "p.script:3:1: more than 1 motions, the most kincal correct takes", model::InputError);
}

TEST_CASE("URScript round trip: other lines byte for byte, CRLF kept, targets equal to the CSV path's") {
  const Ur10 ur10;
  const model::RobotModel &start = ur10.start, &calibrated = ur10.calibrated, &arm = ur10.arm;
  const std::vector<double> a = {0.1, -1.2, 1.4, -1.6, -1.5, 0.3}, b = {0.4, -1.0, 1.2, -1.8, -1.4, 0.1},
                            c = {0.3, -1.1, 1.3, -1.7, -1.5, 0.2};
  const auto pose_near = [&](const std::vector<double>& q, double dz) {
    model::Transform t = model::forward_kinematics(arm, q);
    t.translation.z() += dz;
    return t;
  };
  const model::Transform p1 = pose_near(a, 0.01), p2 = pose_near(b, -0.02);
  const std::string program =
      "def pick():\r\n  # movej([0, 0, 0, 0, 0, 0]) stays a comment\r\n  set_tcp(p[0, 0, 0.1, 0, 0, 0])\r\n"
      "  movej([" +
      list(a) + "], a=1.4, v=1.05)\r\n  movel(p[" + list(rotvec(p1)) +
      "], a=1.2, v=0.25)\r\n"
      "  textmsg(\"movel\")\r\n\r\n  movej([" +
      list(b) + "])\r\n  movep(p[" + list(rotvec(p2)) + "], r=0.01)\r\n  servoj([" + list(c) + "], t=0.008)\r\nend\r\n";
  const correct::UrProgram parsed = correct::parse_urscript(program, "p.script", 6);
  REQUIRE(parsed.motions.size() == 5);
  CHECK(parsed.motions[1].call == "movel");
  CHECK_THROWS_AS(correct::write_urscript(parsed, {}), std::invalid_argument);

  correct::TargetCorrector corrector(start, calibrated, correct::TargetFrame::base, std::nullopt);
  std::vector<correct::Target> targets;
  for (const correct::UrMotion& m : parsed.motions) targets.push_back(m.target);
  const std::vector<correct::TargetResult> results = corrector.correct(targets, {}, "p.script");
  for (const correct::TargetResult& r : results) REQUIRE(r.solution.outcome == correct::Outcome::reached);
  const std::string written = correct::write_urscript(parsed, correct::urscript_values(parsed, results));
  const std::vector<std::string> before = lines(program), after = lines(written);
  REQUIRE(before.size() == after.size());
  const std::vector<int> motion_lines = {4, 5, 8, 9, 10};
  for (std::size_t i = 0; i < before.size(); ++i) {
    const bool motion =
        std::find(motion_lines.begin(), motion_lines.end(), static_cast<int>(i + 1)) != motion_lines.end();
    if (!motion) CHECK(before[i] == after[i]);
    CHECK(after[i].size() >= 2);
    CHECK(after[i].substr(after[i].size() - 2) == "\r\n");
  }
  CHECK(after[3].find("], a=1.4, v=1.05)\r\n") != std::string::npos);

  // The CSV path: the joint targets in one table, the poses in another with the seeds the
  // program gave them (the joint target before each).
  const correct::TargetTable joints = correct::parse_target_table(
      "q1,q2,q3,q4,q5,q6\n" + numbers(a) + "\n" + numbers(b) + "\n" + numbers(c) + "\n", "j.csv", 6);
  std::string poses_text = "x,y,z,qw,qx,qy,qz,q1,q2,q3,q4,q5,q6\n";
  for (const auto& [p, seed] : {std::pair{p1, a}, std::pair{p2, b}}) {
    const Eigen::Quaterniond q(p.rotation);
    poses_text += numbers({p.translation.x(), p.translation.y(), p.translation.z(), q.w(), q.x(), q.y(), q.z()}) + "," +
                  numbers(seed) + "\n";
  }
  const correct::TargetTable poses = correct::parse_target_table(poses_text, "p.csv", 6);
  const auto as_targets = [](const correct::TargetTable& t) {
    std::vector<correct::Target> out;
    for (const correct::TargetRow& r : t.rows) out.push_back({r.line, t.cartesian, r.q, r.pose, t.orientation});
    return out;
  };
  const std::vector<correct::TargetResult> from_joints = corrector.correct(as_targets(joints), {}, "j.csv");
  const std::vector<correct::TargetResult> from_poses = corrector.correct(as_targets(poses), {}, "p.csv");

  const correct::UrProgram back = correct::parse_urscript(written, "back.script", 6);
  REQUIRE(back.motions.size() == 5);
  const int joint_motion[3] = {0, 2, 4}, pose_motion[2] = {1, 3};
  for (int k = 0; k < 3; ++k)
    CHECK(back.motions[static_cast<std::size_t>(joint_motion[k])].target.q ==
          from_joints[static_cast<std::size_t>(k)].solution.q);
  for (int k = 0; k < 2; ++k) {
    const model::Transform& got = back.motions[static_cast<std::size_t>(pose_motion[k])].target.pose;
    const model::Transform& want = from_poses[static_cast<std::size_t>(k)].command;
    CHECK((got.translation - want.translation).norm() < 1e-12);
    CHECK((got.rotation - want.rotation).norm() < 1e-12);
    // The command differs from the target by the calibration; the real arm at the commanded
    // pose's readings reaches the target.
    CHECK((want.translation - (k == 0 ? p1 : p2).translation).norm() > 1e-4);
  }
}

TEST_CASE("URScript as PolyScope writes it: waypoint variables and get_inverse_kin corrected where they are assigned") {
  const Ur10 ur10;
  const std::vector<double> a = {0.1, -1.2, 1.4, -1.6, -1.5, 0.3}, b = {0.4, -1.0, 1.2, -1.8, -1.4, 0.1};
  const auto pose = [&](const std::vector<double>& q) { return rotvec(model::forward_kinematics(ur10.arm, q)); };
  // A subprogram above the globals names a waypoint assigned below it; an unused variable's
  // literal is not read; a string and a comment name variables too.
  const std::string program =
      "def cell():\n  def approach():\n    movel(Waypoint_2_p, a=1.2, v=0.25)\n  end\n"
      "  global Plane_1=p[x, y]\n  set_tcp(p[0.0,0.0,0.0,0.0,0.0,0.0])\n"
      "  global Waypoint_1_p=p[" +
      list(pose(a)) + "]\n  global Waypoint_1_q=[" + list(a) + "]\n  global Waypoint_2_p=p[" + list(pose(b)) +
      "]\n  global Waypoint_2_q=[" + list(b) +
      "]\n  $ 3 \"Waypoint_1\" \"breakAfter\"\n"
      "  movej(get_inverse_kin(Waypoint_1_p, qnear=Waypoint_1_q), a=1.39, v=1.05)\n"
      "  approach()  # movej(Waypoint_9_q)\n  movej(Waypoint_2_q, a=1.39, v=1.05)\n"
      "  movel(Waypoint_1_p, a=1.2, v=0.25)\nend\n";
  const correct::UrProgram parsed = correct::parse_urscript(program, "cell.script", 6);
  REQUIRE(parsed.motions.size() == 4);
  REQUIRE(parsed.literals.size() == 4);  // each waypoint's p and q once, Plane_1 not read
  const correct::UrMotion &first = parsed.motions[1], &last = parsed.motions[3];
  CHECK(first.target.cartesian);
  CHECK(first.target.q == a);  // the seed: qnear
  REQUIRE(first.seed);
  CHECK(parsed.literals[*first.seed].numbers == a);
  CHECK(last.literal == first.literal);
  CHECK(!last.seed);
  CHECK(!parsed.motions[2].target.cartesian);
  CHECK(parsed.motions[2].target.q == b);
  CHECK(parsed.motions[0].target.line == 3);
  CHECK((parsed.motions[0].target.pose.translation - model::forward_kinematics(ur10.arm, b).translation).norm() <
        1e-12);

  correct::TargetCorrector corrector(ur10.start, ur10.calibrated, correct::TargetFrame::base, std::nullopt);
  std::vector<correct::Target> targets;
  for (const correct::UrMotion& m : parsed.motions) targets.push_back(m.target);
  const std::vector<correct::TargetResult> results = corrector.correct(targets, b, "cell.script");
  for (const correct::TargetResult& r : results) REQUIRE(r.solution.outcome == correct::Outcome::reached);
  const std::string written = correct::write_urscript(parsed, correct::urscript_values(parsed, results));
  // Only the four assignments changed; every motion line is byte for byte, as is Plane_1's.
  const std::vector<std::string> before = lines(program), after = lines(written);
  REQUIRE(before.size() == after.size());
  for (std::size_t i = 0; i < before.size(); ++i)
    CHECK((before[i] == after[i]) == (before[i].find("global Waypoint_") == std::string::npos));
  const correct::UrProgram back = correct::parse_urscript(written, "back.script", 6);
  // The pose is the command of the first motion naming it, its qnear that motion's readings, and
  // the joint target its own correction.
  CHECK(back.literals[back.motions[1].literal].numbers == correct::urscript_values(parsed, results)[first.literal]);
  CHECK(back.motions[1].target.q == results[1].solution.q);
  CHECK((back.motions[1].target.pose.translation - results[1].command.translation).norm() < 1e-12);
  CHECK(back.motions[2].target.q == results[2].solution.q);
  CHECK(results[1].solution.q != a);

  const auto refused = urscript_refusal;
  const auto left = urscript_left;  // a target computed when the program runs: left as written, named
  const std::string q = "[" + list(a) + "]", p = "p[" + list(pose(a)) + "]";
  CHECK(left("w = " + q + "\nmovej(w)\nw = " + q + "\n")
            .find("p.script:2:7: movej's target w is assigned 2 times (lines 1, 3)") == 0);
  CHECK(left("global w = get_actual_joint_positions()\nmovej(w)\n")
            .find("p.script:2:7: movej's target w is assigned an expression on line 1, not a literal") == 0);
  CHECK(left("w = " + q + "\nw[0] = 0.5\nmovej(w)\n").find("movej's target w is assigned 2 times") !=
        std::string::npos);
  CHECK(left("w = " + q + " + " + q + "\nmovej(w)\n").find("assigned an expression on line 1") != std::string::npos);
  const std::string own_tcp = "movej(get_inverse_kin(w, qnear=" + q + ", tcp=p[0, 0, 0.1, 0, 0, 0]))";
  CHECK(left("w = " + p + "\n" + own_tcp + "\n")
            .find("p.script:2:" + std::to_string(own_tcp.find("tcp=") + 5) +
                  ": get_inverse_kin with a tcp of its own") == 0);
  CHECK(refused("w = " + p + "\nmovej(get_inverse_kin(w, qnear=w))\n")
            .find("p.script:2:32: get_inverse_kin's qnear w holds a pose, not the model's 6 joint positions") == 0);
  CHECK(refused("w = [1, 2, 3, 4, d2r(5), 6]\nmovej(w)\n").find("p.script:1:17: column w value 5: 'd2r(5)'") == 0);
  CHECK(refused("w = [1, 2, 3]\nmovej(w)\n").find("p.script:1:5: w: 3 joint values, the model has 6 joints") == 0);
  // get_inverse_kin of joint positions (the fuzzer's finding: they were taken as a joint target
  // whose readings the qnear then replaced).
  CHECK(refused("w = " + q + "\nmovej(get_inverse_kin(w, qnear=" + q + "))\nmovel(w)\n")
            .find("p.script:1:5: w: a pose p[x, y, z, rx, ry, rz] has 6 values, this one is a list [...]") == 0);
  CHECK(left("movej(w + 1)\n").find("p.script:1:9: movej's target goes on past its literal or name") == 0);
  CHECK(refused("w = " + p + "\nmovej(get_inverse_kin(w, " + q + ", 1e-10, 1e-10))\n") == "accepted");
  // The TCPs a program sets: a literal, a variable assigned one once; anything else is unknown,
  // never refused.
  REQUIRE(parsed.tcps.size() == 1);
  CHECK(parsed.tcps[0].line == 6);
  REQUIRE(parsed.tcps[0].flange_T_tcp);
  CHECK(parsed.tcps[0].flange_T_tcp->translation.norm() == 0.0);
  const correct::UrProgram tcps = correct::parse_urscript(
      "t = p[0, 0, 0.15, 0, 0, 1.5708]\nset_tcp(t)\nset_tcp(get_tcp_offset())\nset_tcp(p[0, 0, d2r(1)])\n", "t.script",
      6);
  REQUIRE(tcps.tcps.size() == 3);
  REQUIRE(tcps.tcps[0].flange_T_tcp);
  CHECK(tcps.tcps[0].flange_T_tcp->translation.z() == 0.15);
  CHECK(tcps.tcps[0].flange_T_tcp->rotation(1, 0) == doctest::Approx(1.0));
  CHECK(!tcps.tcps[1].flange_T_tcp);
  CHECK(!tcps.tcps[2].flange_T_tcp);
  CHECK(tcps.tcps[2].line == 4);

  // movec: its via point and its end, two targets of one motion line.
  const correct::UrProgram circle =
      correct::parse_urscript("w = " + p + "\nmovec(w, " + p + ", a=1.2, r=0)\n", "c.script", 6);
  REQUIRE(circle.motions.size() == 2);
  CHECK(circle.motions[0].call == "movec");
  CHECK(circle.motions[1].target.cartesian);
  CHECK(circle.motions[0].literal != circle.motions[1].literal);
  CHECK(circle.motions[1].target.line == 2);
  CHECK(refused("movec(" + p + ")\n").find("p.script:1:") == 0);
  CHECK(refused("movec(" + p + ")\n").find("movec takes a via point and an end") != std::string::npos);
}

TEST_CASE("URScript from offline programming: pose_trans(FRAME, POSE) corrected in its frame") {
  const Ur10 ur10;
  const std::vector<double> a = {0.1, -1.2, 1.4, -1.6, -1.5, 0.3};
  const auto text = [](const model::Transform& t) { return "p[" + list(rotvec(t)) + "]"; };
  model::Transform frame;  // a part's frame, as a CAM post writes it
  frame.translation = {-0.3, 0.2, 0.1};
  frame.rotation = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const model::Transform goal = model::forward_kinematics(ur10.arm, a), local = frame.inverse() * goal;
  const std::string program = "def cam():\n  global Ref_frame = " + text(frame) + "\n  movel(pose_trans(Ref_frame," +
                              text(local) + "),a=1.2,v=0.1,r=0.001)\nend\n";
  const correct::UrProgram parsed = correct::parse_urscript(program, "cam.script", 6);
  REQUIRE(parsed.motions.size() == 1);
  REQUIRE(parsed.literals.size() == 1);  // the pose alone: the frame is kept
  const correct::UrMotion& m = parsed.motions[0];
  REQUIRE(m.base_T_frame);
  CHECK((m.target.pose.translation - goal.translation).norm() < 1e-12);
  CHECK((m.target.pose.rotation - goal.rotation).norm() < 1e-12);

  correct::TargetCorrector corrector(ur10.start, ur10.calibrated, correct::TargetFrame::base, std::nullopt);
  const std::vector<correct::TargetResult> results = corrector.correct({m.target}, a, "cam.script");
  REQUIRE(results[0].solution.outcome == correct::Outcome::reached);
  const std::string written = correct::write_urscript(parsed, correct::urscript_values(parsed, results));
  const std::vector<std::string> before = lines(program), after = lines(written);
  CHECK(after[1] == before[1]);  // the frame kept
  CHECK(after[2] != before[2]);
  CHECK(after[2].find("  movel(pose_trans(Ref_frame,p[") == 0);
  CHECK(after[2].find("]),a=1.2,v=0.1,r=0.001)") != std::string::npos);
  // Frame * the written pose is the pose to command.
  const correct::UrProgram back = correct::parse_urscript(written, "back.script", 6);
  CHECK((back.motions[0].target.pose.translation - results[0].command.translation).norm() < 1e-12);
  CHECK((back.motions[0].target.pose.rotation - results[0].command.rotation).norm() < 1e-12);

  const auto refused = urscript_refusal;
  const auto left = urscript_left;  // a target computed when the program runs: left as written, named
  const std::string f = text(frame), l = text(local);
  CHECK(refused("movel(pose_trans(" + f + "," + l + "))\n") == "accepted");
  CHECK(left("movel(pose_trans(r," + l + "))\n").find("p.script:1:18: pose_trans's target r is not assigned") == 0);
  CHECK(left("r = " + f + "\nr = " + f + "\nmovel(pose_trans(r," + l + "))\n")
            .find("p.script:3:18: pose_trans's target r is assigned 2 times (lines 1, 2)") == 0);
  CHECK(left("movel(pose_trans(get_actual_tcp_pose()," + l + "))\n")
            .find("p.script:1:18: pose_trans's frame is not a literal p[...] or a variable assigned one") == 0);
  CHECK(left("movel(pose_trans(" + f + "," + l + "," + l + "))\n").find("pose_trans takes a frame and a pose") !=
        std::string::npos);
  CHECK(refused("movel(pose_trans(" + f + ",[1, 2, 3, 4, 5, 6]))\n").find("this one is a list [...]") !=
        std::string::npos);
  CHECK(refused("w = " + l + "\nmovel(pose_trans(" + f + ", w))\nmovel(w)\n")
            .find("p.script:3:7: w is a target in the robot's base frame and in a pose_trans frame") == 0);
  CHECK(refused("w = " + l + "\nmovel(pose_trans(" + f + ", w))\nmovel(pose_trans(p[0, 0, 0, 0, 0, 0], w))\n")
            .find("w is a target in two pose_trans frames") != std::string::npos);
  CHECK(refused("w = " + l + "\nmovel(pose_trans(" + f + ", w))\nmovep(pose_trans(" + f + ", w))\n") == "accepted");
  // A frame kept as written cannot be a target corrected elsewhere.
  CHECK(refused("r = " + f + "\nmovel(r)\nmovel(pose_trans(r, " + l + "))\n")
            .find("p.script:3:18: r is the frame of this pose_trans and a target corrected elsewhere") == 0);
}

TEST_CASE("URScript from a file: a byte-order mark is kept, the rest read as without it") {
  const std::string path =
      (std::filesystem::temp_directory_path() / ("kincal_bom_" + std::to_string(::getpid()) + ".script")).string();
  std::ofstream(path, std::ios::binary) << "\xEF\xBB\xBFmovej([0.1, -1.2, 1.4, -1.6, -1.5, 0.3])\r\nend\r\n";
  const correct::UrProgram p = correct::read_urscript(path, 6);
  std::filesystem::remove(path);
  REQUIRE(p.motions.size() == 1);
  CHECK(p.motions[0].target.q == std::vector<double>{0.1, -1.2, 1.4, -1.6, -1.5, 0.3});
  CHECK(correct::write_urscript(p, {{0.5, -1.2, 1.4, -1.6, -1.5, 0.3}}) ==
        "\xEF\xBB\xBFmovej([0.5, -1.2, 1.4, -1.6, -1.5, 0.3])\r\nend\r\n");
}

TEST_CASE("urscript: a program as editors write it comes back byte for byte but the values that changed (issue #44)") {
  // A byte-order mark, tabs, CRLF and LF mixed, no spaces or odd spaces inside the brackets, values
  // spelled with a '+'-less exponent and trailing zeros, no line end after the last line.
  const std::string program =
      "\xEF\xBB\xBF"
      "def p():\r\n\t# home\r\n\tmovej([0.1,-0.4,0.30,2e-1,-0.5,0.7], a=1.4)\n"
      "\tservoj([ 0.2 ,\t-0.3, 0.2, 0.1, -0.6, 0.5 ], t=0.008)\r\n"
      "\tmovel( p[0.5,\t0.1, 0.4 , 0, 3.14, 0] )\r\nend";
  const correct::UrProgram parsed = correct::parse_urscript(program, "p.script", 6);
  REQUIRE(parsed.motions.size() == 3);
  CHECK(parsed.motions[0].target.q[3] == 0.2);
  // Each value's own bytes are the number alone.
  REQUIRE(parsed.literals.size() == 3);
  for (const correct::UrLiteral& literal : parsed.literals) {
    REQUIRE(literal.values.size() == 6);
    for (const auto& [begin, end] : literal.values) {
      const std::string value = program.substr(begin, end - begin);
      CHECK(value.find_first_of(" \t,[]") == std::string::npos);
      CHECK(!value.empty());
    }
  }
  // The same values back: the very same bytes (spellings such as 0.30 and 2e-1 kept).
  std::vector<std::vector<double>> same = {
      parsed.motions[0].target.q, parsed.motions[1].target.q, {0.5, 0.1, 0.4, 0, 3.14, 0}};
  CHECK(correct::write_urscript(parsed, same) == program);
  // Two values changed: only their bytes differ.
  std::vector<std::vector<double>> changed = same;
  changed[0][2] = 0.3125;
  changed[2][1] = -0.25;
  const std::string written = correct::write_urscript(parsed, changed);
  CHECK(written ==
        "\xEF\xBB\xBF"
        "def p():\r\n\t# home\r\n\tmovej([0.1,-0.4,0.3125,2e-1,-0.5,0.7], a=1.4)\n"
        "\tservoj([ 0.2 ,\t-0.3, 0.2, 0.1, -0.6, 0.5 ], t=0.008)\r\n"
        "\tmovel( p[0.5,\t-0.25, 0.4 , 0, 3.14, 0] )\r\nend");
  // A literal given a wrong count of values is a programming error, not a silent truncation.
  changed[1].pop_back();
  CHECK_THROWS_AS(correct::write_urscript(parsed, changed), std::invalid_argument);
}

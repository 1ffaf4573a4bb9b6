// Universal Robots' URScript programs in and out (issues #24, #42): the targets of motion lines read
// as joint or Cartesian targets, and the program written back with corrected targets.
//
// Read: every call movej(, movel(, movep(, movec(, servoj( or servoc( in the code of a line -- not
// inside a string ("..." or '...', a backslash escaping the next character) nor behind a '#' --
// whose first argument is one of
//   - a literal: [q1, ..., qN] (joint positions, rad) or p[x, y, z, rx, ry, rz] (a pose in the
//     robot's base frame: m, and a rotation vector in rad);
//   - a variable the program assigns a literal once and nowhere else (`global Waypoint_1_p=p[...]`,
//     as PolyScope writes its waypoints; `local` or neither too): that literal is the target, and
//     the one rewritten, so every motion naming the variable moves to the corrected target;
//   - pose_trans(FRAME, POSE) (offline programs' targets in a part's frame: Fusion's and RoboDK's
//     posts), FRAME and POSE each a pose literal or a variable as above: the target FRAME * POSE,
//     POSE rewritten (FRAME * POSE' the pose to command), FRAME kept (a variable's pose named in
//     two frames, or in one and in the base frame, is refused: one value cannot serve both);
//   - get_inverse_kin(TARGET, qnear=SEED) (PolyScope's MoveJ; SEED also as the second positional
//     argument, other arguments but tcp= ignored), TARGET a pose literal or variable as above and
//     SEED a joint literal or variable: a Cartesian target whose seed (the controller's branch,
//     the reference of the joint-change limit) is SEED, and SEED rewritten with the corrected
//     readings unless a motion takes it as its own joint target;
// followed by ',' or ')'; movec's second argument (its end; the first is its via point) too, a
// target of its own. One call per line is read (the first). Each set_tcp( is read too
// (UrProgram::tcps: its pose when it is a literal or a variable assigned one once), never refused.
//
// Left as written, each named in UrProgram::left ("FILE:LINE:COLUMN: what"; correct says so on
// standard error): a motion whose target is computed when the program runs -- any other
// expression (pose_add(...), get_actual_tcp_pose(), a function's parameter: a gripper URCap's
// depth-compensating servoj), a target that goes on past its literal or name ([...] + [...]), a
// variable assigned no literal in the program, more than once, or an expression (an element
// assignment `q[0] = 1` counts), get_inverse_kin with a tcp of its own, a literal continued on the
// next line; a movec with either target so is left whole. Its value is not known before the
// program runs, so no correction is computed for it, and refusing the program would leave its
// corrected motions to hand editing.
//
// Refused (model::InputError "FILE:LINE:COLUMN: what", at the motion, or at the assignment for
// what its literal holds): a line longer than 64 KiB (no program has one: the file is something
// else), a string not closed on its line, a joint list whose length is not the model's joint
// count, a pose without six values, a seed that is a pose, a value that is not a plain finite
// number (d2r(90), a variable inside the list), a pose's rotation vector longer than a turn (2 pi
// rad: degrees, most likely), a variable's pose named in two frames, a variable that is a
// pose_trans frame and a target too (its rewritten value would move the motions in its frame),
// get_inverse_kin of joint positions, a movec with one argument, more than kMaxTargets motions. A literal assigned to a
// variable no motion names is not read.
//
// Written: the program's bytes unchanged but for each target value's own bytes, which become the
// new value (its shortest exact decimal; a value that did not change keeps its spelling). So the
// commas, spaces and tabs inside the brackets, line ends (LF, CRLF, mixed, none after the last
// line), comments, blank lines and every other line are kept byte for byte, a UTF-8 byte-order
// mark too (files::kProgramFile keeps it).
// The text comes from files::read_text (kProgramFile).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "host/correct/target_correction.hpp"

namespace kincal::correct {

// A literal whose values a correction rewrites: a motion's own, or the one a variable is assigned.
struct UrLiteral {
  int line = 0;
  bool pose = false;
  std::vector<double> numbers;     // as read
  std::size_t begin = 0, end = 0;  // byte range of the values between the brackets in the text
  // Byte range of each value in the text (the number alone, without the blanks around it).
  std::vector<std::pair<std::size_t, std::size_t>> values;
};

struct UrMotion {
  std::string call;                 // movej, movel, movep, movec (via point and end: two), servoj, servoc
  Target target;                    // line (the motion's), cartesian, q (joints, or the seed) or pose
  std::size_t literal = 0;          // program.literals index of the target's values
  std::optional<std::size_t> seed;  // get_inverse_kin's qnear: program.literals index
  // pose_trans(FRAME, POSE)'s frame: target.pose is FRAME * POSE, and POSE is what is rewritten.
  std::optional<model::Transform> base_T_frame;
};

// A set_tcp( call: the TCP the program's poses are of from there on.
struct UrTcp {
  int line = 0;
  std::optional<model::Transform> flange_T_tcp;  // a pose literal or a variable assigned one once; else unknown
};

// A motion left as written: its target is computed when the program runs.
struct UrLeft {
  int line = 0;
  std::string call;
  std::string why;  // "FILE:LINE:COLUMN: what"
};

struct UrProgram {
  std::string source;
  std::string text;
  std::vector<UrLiteral> literals;  // each once, however many motions name it
  std::vector<UrMotion> motions;
  std::vector<UrLeft> left;  // in line order
  std::vector<UrTcp> tcps;   // every set_tcp, in the file's order (never refused: the poses are checked against them)
};

// max_motions: the motion past it is refused as it is read (kMaxTargets for `correct`).
UrProgram read_urscript(const std::string& path, int joint_count, std::size_t max_motions = kMaxTargets);
UrProgram parse_urscript(std::string text, const std::string& source, int joint_count,
                         std::size_t max_motions = kMaxTargets);

// The program with each literal's values replaced: values[i] for literals[i] (joint readings, or
// x,y,z,rx,ry,rz for a pose). Throws std::invalid_argument when the counts differ (literals, or
// values of a literal).
std::string write_urscript(const UrProgram& program, const std::vector<std::vector<double>>& values);

// The new values of each literal from the corrector's results (results[i] for motions[i]): the
// corrected readings for a joint target, the commanded pose (TargetResult::command) as
// x,y,z,rx,ry,rz for a Cartesian one, the first motion naming a literal deciding; a seed no motion
// takes as its target gets the corrected readings of the first target it seeds.
std::vector<std::vector<double>> urscript_values(const UrProgram& program, const std::vector<TargetResult>& results);

}  // namespace kincal::correct

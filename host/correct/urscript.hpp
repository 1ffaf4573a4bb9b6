// Universal Robots' URScript programs in and out (issue #24): the literal targets of motion lines
// read as joint or Cartesian targets, and the program written back with corrected targets.
//
// Read: every call movej(, movel(, movep( or servoj( in the code of a line -- not inside a string
// ("..." or '...', a backslash escaping the next character) nor behind a '#' -- whose first argument
// is a literal: [q1, ..., qN] (joint positions, rad) or p[x, y, z, rx, ry, rz] (a pose in the
// robot's base frame: m, and a rotation vector in rad) followed by ',' or ')'. One call per line
// is read (the first). Refused (model::InputError "FILE:LINE:COLUMN: what"): a line longer than
// 64 KiB (no program has one: the file is something else), a string not closed on its line, a
// target that goes on past its literal ([...] + [...], [...] * 2: the program would move where no
// correction was computed), a joint list whose length is not
// the model's joint count, a pose without six values, a value that is not a plain finite number
// (d2r(90), a variable inside the list), a pose's rotation vector longer than a turn (2 pi rad:
// degrees, most likely), more than kMaxTargets motions, a motion call whose target is a variable
// (movej(home)): its value is not known before the program runs, and a target left uncorrected
// would be silent.
//
// Written: the program's bytes unchanged but for each target value's own bytes, which become the
// new value (its shortest exact decimal; a value that did not change keeps its spelling). So the
// commas, spaces and tabs inside the brackets, line ends (LF, CRLF, mixed, none after the last
// line), comments, blank lines and every other line are kept byte for byte, a UTF-8 byte-order
// mark too (files::kProgramFile keeps it).
// The text comes from files::read_text (kProgramFile).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "host/correct/target_correction.hpp"

namespace kincal::correct {

struct UrMotion {
  std::string call;                // movej, movel, movep, servoj
  Target target;                   // line, cartesian, q or pose (orientation always)
  std::size_t begin = 0, end = 0;  // byte range of the values between the brackets in the text
  // Byte range of each value in the text (the number alone, without the blanks around it).
  std::vector<std::pair<std::size_t, std::size_t>> values;
};

struct UrProgram {
  std::string source;
  std::string text;
  std::vector<UrMotion> motions;
};

// max_motions: the motion past it is refused as it is read (kMaxTargets for `correct`).
UrProgram read_urscript(const std::string& path, int joint_count, std::size_t max_motions = kMaxTargets);
UrProgram parse_urscript(std::string text, const std::string& source, int joint_count,
                         std::size_t max_motions = kMaxTargets);

// The program with each motion's values replaced: values[i] for motions[i] (joint readings for a
// joint target, x,y,z,rx,ry,rz for a pose). Throws std::invalid_argument when the counts differ
// (motions, or values of a motion).
std::string write_urscript(const UrProgram& program, const std::vector<std::vector<double>>& values);

// The new values of each motion from the corrector's results: the corrected readings for joint
// targets, the commanded pose (TargetResult::command) as x,y,z,rx,ry,rz for Cartesian ones.
std::vector<std::vector<double>> urscript_values(const UrProgram& program, const std::vector<TargetResult>& results);

}  // namespace kincal::correct

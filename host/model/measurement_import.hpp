// Measurement exports as they come (laser-tracker software, spreadsheets) into a kincal dataset
// (dataset.hpp): what `kincal import` runs.
//
// The user names everything that cannot be guessed safely: which header names hold the joint
// readings, the position and (optionally) the orientation; the unit of each (mm or m; deg or rad);
// the Euler convention of the orientation; optionally the per-component standard deviations.
// A column is named by its header name, or by its number, "#7" (1-based), where the header holds
// a name twice (a motion-capture export's X, Y, Z of the rotation and of the position): a name
// that appears twice is refused only when an option names it, the message giving both numbers.
// A header written as a comment ("# J1  J2  X ...", as numpy.savetxt writes it) is read without
// the '#'. The header is the first line holding every named column, among the first 100 lines: lines
// before it (a title, the instrument's settings, a spreadsheet's "sep=;") are skipped. When no
// line holds them all, the first line that is not blank is taken, and the message names the
// column it lacks.
// Guessed only where no ambiguity exists: the separator (the header line's most frequent of ';',
// tab and ',' outside double quotes; runs of blanks when none of those splits it -- a whitespace-
// aligned export, numpy.savetxt's or a fixed-width report's, whose header names cannot hold a blank
// unless quoted and whose cells cannot be empty; or given), and the decimal mark, from the numbers
// together: a comma in a number is a decimal comma (in a ',' separated file it can only be there in
// a quoted field, "-21,140068", as spreadsheets write it). Refused as ambiguous: a number with both
// '.' and ',' (a thousands separator), a ',' separated file whose numbers use both marks, and a ','
// separated row with more fields than the header (unquoted decimal commas: the message says so).
//
// Euler conventions: "intrinsic-ABC" or "extrinsic-ABC" with ABC three axis letters (x, y, z, no
// two neighbours equal), the angles given in the order of the letters:
//   intrinsic-xyz  R = Rx(a) * Ry(b) * Rz(c)   (rotate about x, then the new y, then the new z)
//   extrinsic-xyz  R = Rz(c) * Ry(b) * Rx(a)   (rotate about the fixed x, then fixed y, then z)
// R is device_R_tool (the tool's axes in the device frame), as the dataset's quaternion.
//
// Quaternions (instead of Euler angles; motion-capture exports): the columns named for w, x, y, z,
// device_R_tool as the Euler angles give it. A quaternion whose norm is off 1 by more than 1 %
// is refused (a column named wrong, or a scaled export); within it, normalized.
//
// Standard deviations: the position's three become the diagonal covariance columns (m^2). The
// dataset format carries no orientation covariance, so orientation standard deviations are read,
// checked and summarized (ImportResult) but not written; identify estimates the orientation noise.
//
// Row ids: the column named by `id` (a time stamp, a record number) is kept per row as text,
// trimmed and unquoted, in the dataset's id column; it must not be empty. Ids need not differ
// (ImportResult counts the distinct ones: an export whose time stamps a spreadsheet rounded to one
// value tells no row apart, and the dataset's line still does).
//
// A units row (motion-capture and tracker exports write one under the header: "mm", "[deg]",
// "Millimeters", "°"): the first row after the header, when none of the named numeric columns
// holds a number and one holds a unit word (m, mm, rad, deg and their spelled-out names). Each
// unit it gives is held against the options (--joint-unit, --position-unit, --angle-unit) and a
// difference is refused naming the column and both units (a file in mm imported as m); a word
// that is no unit kincal reads is refused too; an empty cell is taken as the options say. The row
// is then skipped (ImportResult::units_line).
//
// Measurements not taken: a row in which every measured column (the position, and the
// orientation and standard deviations when named) is empty or NaN -- a tracker that lost its beam,
// a marker the cameras did not see -- is left out and listed (ImportResult::skipped), its joint
// readings unread. A row with some measured columns empty and others not is refused (a partial
// measurement), and so is a file in which no row holds one.
//
// Joint units: one for every joint, or one per joint (a mixed arm: deg,deg,m,deg,...); rad or deg
// for a revolute joint, m or mm for a prismatic one (check_joint_units() holds them against a
// model).
//
// Reads: import_measurements_file() reads through files::read_text() (files/input_file.hpp: a
// regular file or "-" for standard input, at most files::kExportFile.max_bytes, UTF-8 with or
// without a byte-order mark, CRLF or LF); fields quoted in messages are cut to 80 bytes. Fields
// may stand in double quotes as RFC 4180 says (a spreadsheet quotes a time stamp or a comment
// holding the separator; "" for a quote); a quote not closed on its line (a field spanning lines)
// or text after a closing quote is refused.
//
// Errors (InputError "FILE:LINE:COLUMN: what", COLUMN 1-based, the header name in the message):
// a named column missing, or named by a name the header holds twice, or by a number past its
// last column; one header column named for two roles (twice in --joints, or as a joint and a
// coordinate); more than kMaxRows data rows (dataset.hpp); a row with the wrong number of fields;
// a field that is not a finite number; an empty id; a standard deviation <= 0; a bad unit or
// convention name; a unit count that is neither 1 nor the joint count; a units row that
// disagrees (above). A message about a row with an id ends with "(id TEXT)".
#pragma once

#include <array>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "host/model/dataset.hpp"

namespace kincal::model {

enum class LengthUnit { m, mm };
enum class JointUnit { rad, deg, m, mm };

struct EulerConvention {
  bool intrinsic = true;
  std::array<int, 3> axes{0, 1, 2};  // 0 = x, 1 = y, 2 = z
};

// "intrinsic-xyz" etc.; throws InputError naming the text.
EulerConvention parse_euler_convention(const std::string& text);
LengthUnit parse_length_unit(const std::string& text);  // "m" or "mm"
AngleUnit parse_angle_unit(const std::string& text);    // "rad" or "deg"
JointUnit parse_joint_unit(const std::string& text);    // "rad", "deg", "m" or "mm"

// device_R_tool from three angles (rad) in the convention's order.
Eigen::Matrix3d rotation_from_euler(const EulerConvention& convention, const Eigen::Vector3d& angles_rad);

struct ImportOptions {
  char separator = 0;                                  // 0: detect from the header line; ' ': runs of blanks
  std::vector<std::string> joints;                     // header names, in the model's joint order
  std::vector<JointUnit> joint_units{JointUnit::rad};  // one for all joints, or one per joint
  std::array<std::string, 3> position;                 // x, y, z
  LengthUnit position_unit = LengthUnit::m;            // also the unit of position_std
  std::optional<std::array<std::string, 3>> position_std;
  std::optional<std::array<std::string, 3>> angles;  // in the convention's order
  EulerConvention convention;
  AngleUnit angle_unit = AngleUnit::rad;  // also the unit of angle_std
  std::optional<std::array<std::string, 3>> angle_std;
  std::optional<std::array<std::string, 4>> quaternion;  // w, x, y, z: the orientation instead of angles
  std::optional<std::string> id;                         // header name of the row id or time stamp column
};

struct ImportResult {
  Dataset data;
  char separator = ',';  // the one used (' ': runs of blanks)
  bool decimal_comma = false;
  double median_position_std_m = 0.0;  // over rows and components; 0 without std columns
  double median_angle_std_rad = 0.0;   // read, not written (see above)
  std::size_t distinct_ids = 0;        // 0 without an id column
  int header_line = 0;                 // 1-based: the lines before it skipped
  int units_line = 0;                  // a units row under the header, checked against the options; 0: none
  struct Skipped {
    int line = 0;
    std::string id;  // empty without an id column
  };
  std::vector<Skipped> skipped;  // rows that hold no measurement, left out
};

ImportResult import_measurements(std::istream& in, const std::string& source, const ImportOptions& options);
// `path` "-": standard input.
ImportResult import_measurements_file(const std::string& path, const ImportOptions& options);

// Throws InputError naming the joint when the units do not fit the model: their count is neither
// 1 nor the model's joint count, an angle unit for a prismatic joint, a length unit for a
// revolute one.
void check_joint_units(const std::vector<JointUnit>& units, const RobotModel& model);

}  // namespace kincal::model

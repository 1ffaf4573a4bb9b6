// Target tables for `kincal correct` (issue #24): CSV files of joint targets, as a program or a
// teach pendant holds them, or of Cartesian targets, and the table the command writes back.
//
//   joint targets      q1,...,qN                        readings (rad, or m for a prismatic joint)
//   Cartesian targets  x,y,z[,qw,qx,qy,qz][,q1,...,qN]  the tool point (m); optionally its
//                                                       orientation as a unit quaternion (w first);
//                                                       optionally a seed reading per target
// One header row naming the columns (any order), then one row per target. Blank lines and lines
// starting with '#' are skipped; CRLF line ends are taken; numbers are plain decimal
// (std::from_chars), SI units. Which kind a table is: x,y,z present -> Cartesian.
//
// Refused (model::InputError "FILE:LINE:COLUMN: what", COLUMN the byte column of the field; the
// header's errors name the column too): no header row; an unknown, empty or repeated column name;
// q columns that are not exactly q1..qN for the model's N joints (joint targets must have them,
// Cartesian ones have them all or none); x,y,z incomplete; a partial quaternion; a row with more or
// fewer fields than the header; an empty field, a field that is not a number, a number that is
// not finite; a quaternion whose norm is not 1 within 1e-3 (it is normalized otherwise); a table
// without targets. The text comes from files::read_text (kDatasetFile: regular files, at most
// 256 MiB, UTF-8).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "host/model/robot_model.hpp"

namespace kincal::correct {

struct TargetRow {
  int line = 0;
  std::vector<double> q;  // joint targets, or the seed of a Cartesian target (empty: none)
  model::Transform pose;  // Cartesian targets; rotation the identity without orientation columns
};

struct TargetTable {
  std::string source;
  bool cartesian = false;
  bool orientation = false;  // Cartesian targets with qw,qx,qy,qz
  std::vector<TargetRow> rows;
};

// max_rows: more targets are refused ("SOURCE:LINE:1: more than MAX_ROWS targets, ...") as the row
// past it is reached, before more memory is taken (a row holds about 200 bytes: a 50 MB table of
// short rows took 2.4 GB).
TargetTable read_target_table(const std::string& path, int joint_count, std::size_t max_rows = SIZE_MAX);
TargetTable parse_target_table(std::string_view text, const std::string& source, int joint_count,
                               std::size_t max_rows = SIZE_MAX);

// A number cell as read above: the whole (trimmed) field a finite std::from_chars double, else
// model::InputError "SOURCE:LINE:COLUMN: column NAME: what". Shared with the URScript reader.
double parse_cell(std::string_view field, const std::string& name, const std::string& source, int line, int column);

}  // namespace kincal::correct

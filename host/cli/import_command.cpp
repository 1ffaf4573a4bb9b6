#include "host/cli/import_command.hpp"

#include <iostream>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>

#include "host/cli/model_option.hpp"
#include "host/files/input_file.hpp"
#include "host/files/output_file.hpp"
#include "host/identify/plausibility.hpp"
#include "host/model/dataset.hpp"
#include "host/model/measurement_import.hpp"

namespace kincal::cli {

namespace {

struct ImportArgs {
  std::string in, out, separator, position_unit, angle_unit = "deg", euler, id;
  std::vector<std::string> joints, joint_units, position, position_std, orientation, orientation_std, quaternion;
  ModelOption model;
};

std::array<std::string, 3> three(const std::vector<std::string>& names, const char* option) {
  if (names.size() != 3)
    throw model::InputError(std::string(option) + ": expected three column names separated by commas, got " +
                            std::to_string(names.size()));
  return {names[0], names[1], names[2]};
}

int run_import(const ImportArgs& a) {
  try {
    model::ImportOptions o;
    if (!a.separator.empty()) {
      if (a.separator == "tab" || a.separator == "\\t") {
        o.separator = '\t';
      } else if (a.separator == "blanks" || a.separator == " ") {
        o.separator = ' ';
      } else if (a.separator.size() == 1 && a.separator != "\"") {
        o.separator = a.separator[0];
      } else {
        throw model::InputError("--separator '" + a.separator +
                                "': expected one character (not a double quote), 'tab' or 'blanks'");
      }
    }
    o.joints = a.joints;
    o.joint_units.clear();
    for (const std::string& u : a.joint_units) o.joint_units.push_back(model::parse_joint_unit(u));
    o.position = three(a.position, "--position");
    o.position_unit = model::parse_length_unit(a.position_unit);
    if (!a.position_std.empty()) o.position_std = three(a.position_std, "--position-std");
    if (!a.orientation.empty()) {
      if (a.euler.empty()) throw model::InputError("--orientation needs --euler (e.g. intrinsic-xyz)");
      o.angles = three(a.orientation, "--orientation");
      o.convention = model::parse_euler_convention(a.euler);
      o.angle_unit = model::parse_angle_unit(a.angle_unit);
    }
    if (!a.orientation_std.empty()) o.angle_std = three(a.orientation_std, "--orientation-std");
    if (!a.quaternion.empty()) {
      if (a.quaternion.size() != 4)
        throw model::InputError("--quaternion: expected four column names (w, x, y, z) separated by commas, got " +
                                std::to_string(a.quaternion.size()));
      o.quaternion = std::array<std::string, 4>{a.quaternion[0], a.quaternion[1], a.quaternion[2], a.quaternion[3]};
    }
    if (!a.id.empty()) o.id = a.id;
    files::refuse_overwriting({{"--out", a.out}}, {{"export", a.in}, {"--model", a.model.path}});
    // Everything is read and checked before the dataset is written: a failed run leaves no file.
    std::optional<model::RobotModel> nominal;
    if (!a.model.path.empty()) {
      nominal = a.model.load();
      model::check_joint_units(o.joint_units, *nominal);
      model::check_joint_count(*nominal, static_cast<int>(o.joints.size()), "--joints");
    }
    const model::ImportResult r = model::import_measurements_file(a.in, o);
    const std::vector<std::string> findings =
        nominal ? identify::implausibilities(*nominal, r.data) : identify::implausibilities(r.data);
    std::ostringstream text;
    model::write_dataset(text, r.data);
    files::write_file_atomically(a.out, text.str());
    std::cout << "kincal import: " << r.data.rows.size() << " rows from " << r.data.source << " (separator '"
              << (r.separator == '\t'  ? std::string("tab")
                  : r.separator == ' ' ? std::string("blanks")
                                       : std::string(1, r.separator))
              << "', decimal " << (r.decimal_comma ? "comma" : "point") << "), " << r.data.joint_count << " joints"
              << (r.data.has_orientation ? ", position and orientation" : ", positions");
    if (o.position_std) std::cout << "; median position std " << r.median_position_std_m * 1e3 << " mm (covariance)";
    if (o.angle_std)
      std::cout << "; median orientation std " << r.median_angle_std_rad * 180.0 / std::numbers::pi
                << " deg (not written: the dataset format has no orientation covariance; identify estimates the "
                   "orientation noise)";
    if (o.id) std::cout << "; " << r.distinct_ids << " distinct ids in column '" << a.id << "' (kept as id)";
    if (r.header_line > 1) std::cout << "; the header on line " << r.header_line << " (the lines before it skipped)";
    if (r.units_line > 0)
      std::cout << "; the units row on line " << r.units_line << " agrees with the units given (skipped)";
    std::cout << "\nwrote " << a.out << '\n';
    if (!r.skipped.empty()) {
      constexpr std::size_t kNamed = 10;  // an export of 10,000 lost readings is not listed whole
      std::cerr << "kincal import: warning: " << r.skipped.size() << " of " << r.skipped.size() + r.data.rows.size()
                << " rows hold no measurement (every measured column empty or NaN: a lost beam, an occluded "
                   "marker) and are left out: line";
      for (std::size_t i = 0; i < r.skipped.size() && i < kNamed; ++i)
        std::cerr << (i == 0 ? (r.skipped.size() > 1 ? "s " : " ") : ", ") << r.skipped[i].line
                  << (r.skipped[i].id.empty() ? "" : " (id " + files::excerpt(r.skipped[i].id) + ")");
      if (r.skipped.size() > kNamed) std::cerr << " and " << r.skipped.size() - kNamed << " more";
      std::cerr << '\n';
    }
    if (o.id && r.distinct_ids < r.data.rows.size())
      std::cerr << "kincal import: warning: the " << r.data.rows.size() << " rows have only " << r.distinct_ids
                << " distinct values of '" << a.id
                << "': an id does not tell its rows apart (messages name the dataset's line too)\n";
    for (const std::string& f : findings) std::cerr << "kincal import: warning: " << f << '\n';
    if (nominal && findings.empty())
      std::cout << "plausible for " << nominal->name << " (units, limits, distances, handedness, joint order)\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "kincal import: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

void add_import_command(CLI::App& app, int& status) {
  auto a = std::make_shared<ImportArgs>();
  auto* cmd = app.add_subcommand("import", "Turn a measurement export (CSV) into a kincal dataset");
  cmd->add_option("export", a->in, "the measurement export (CSV with one header row; '-': standard input)")->required();
  cmd->add_option("--out,-o", a->out, "the dataset to write (kincal CSV, SI units)")->required();
  cmd->add_option("--separator", a->separator,
                  "field separator: one character, 'tab', or 'blanks' (columns aligned by runs of spaces or tabs) "
                  "(default: detected; blanks only where no ';', tab or ',' splits the header)");
  cmd->add_option("--joints", a->joints, "header names of the joint readings, in the model's order")
      ->delimiter(',')
      ->required();
  cmd->add_option("--joint-unit", a->joint_units,
                  "unit of the joint readings: one for all joints or one per joint (rad, deg; m, mm for prismatic "
                  "joints), e.g. deg,deg,m,deg")
      ->delimiter(',')
      ->check(CLI::IsMember({"rad", "deg", "m", "mm"}))
      ->required();
  cmd->add_option("--position", a->position, "header names of x, y, z")->delimiter(',')->required();
  cmd->add_option("--position-unit", a->position_unit, "unit of the positions and their std")
      ->check(CLI::IsMember({"m", "mm"}))
      ->required();
  cmd->add_option("--position-std", a->position_std, "header names of the std of x, y, z (-> covariance columns)")
      ->delimiter(',');
  auto* orientation = cmd->add_option("--orientation", a->orientation,
                                      "header names of the three Euler angles, in the convention's order")
                          ->delimiter(',');
  // The convention, unit and std of the angles mean nothing without them.
  cmd->add_option("--euler", a->euler,
                  "Euler convention: intrinsic-xyz (R = Rx Ry Rz), extrinsic-xyz (R = Rz Ry Rx), ...")
      ->needs(orientation);
  cmd->add_option("--angle-unit", a->angle_unit, "unit of the Euler angles and their std (default deg)")
      ->check(CLI::IsMember({"rad", "deg"}))
      ->needs(orientation);
  cmd->add_option("--orientation-std", a->orientation_std,
                  "header names of the Euler angles' std (checked, summarized)")
      ->delimiter(',')
      ->needs(orientation);
  cmd->add_option("--quaternion", a->quaternion,
                  "header names of the orientation as a unit quaternion, in the order w, x, y, z (whatever "
                  "order the file's columns stand in; motion-capture exports)")
      ->delimiter(',')
      ->excludes(orientation);
  cmd->add_option("--id", a->id,
                  "header name of a row id or time stamp column, kept per row (the dataset's id column) and named "
                  "in messages about the row");
  add_model_option(*cmd, a->model,
                   "check the data against this model and warn (units, limits, distances, handedness, joint order)",
                   false);
  cmd->callback([a, &status] { status = run_import(*a); });
}

}  // namespace kincal::cli

// libFuzzer target for the import of measurement exports (issue #25): model::import_measurements,
// the reader `kincal import` runs on laser-tracker and spreadsheet exports. The first input byte
// chooses the options (separator given or detected, joint units, orientation and standard
// deviation columns, one column named twice); the rest is the export's text. Either InputError,
// or a dataset that write_dataset writes and parse_dataset reads back with the same rows. Any
// other exception, a crash, a leak, undefined behaviour, or a message that quotes more than
// ~80 bytes of a field is a finding. Runs standalone too (file arguments), and as the ctest
// fuzz.import for a bounded time; seeds in import_seeds/.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include "host/model/dataset.hpp"
#include "host/model/measurement_import.hpp"

using namespace kincal;

namespace {

void require(bool condition) {
  if (!condition) std::abort();
}

model::ImportOptions options_from(std::uint8_t choice) {
  model::ImportOptions o;
  o.joints = {"J1", "J2", "J3"};
  o.position = {"X", "Y", "Z"};
  static const char kSeparators[] = {0, ',', ';', '\t'};
  o.separator = kSeparators[choice & 3];
  if (choice & 4) o.joint_units = {model::JointUnit::deg, model::JointUnit::rad, model::JointUnit::mm};
  if (choice & 8) o.position_unit = model::LengthUnit::mm;
  if (choice & 16) {
    o.angles = std::array<std::string, 3>{"A", "B", "C"};
    o.convention = model::parse_euler_convention(choice & 32 ? "extrinsic-zyx" : "intrinsic-xyz");
  }
  if (choice & 64) o.position_std = std::array<std::string, 3>{"SX", "SY", "SZ"};
  if (choice & 128) o.joints[2] = "X";  // one column named for two values: always refused
  return o;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const model::ImportOptions o = options_from(data[0]);
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  model::ImportResult r;
  try {
    std::istringstream in(text);
    r = model::import_measurements(in, "fuzz.csv", o);
  } catch (const model::InputError& e) {
    // A message names the file and at most a few quoted fields of 80 bytes each.
    require(std::string(e.what()).size() < 4096);
    return 0;
  }
  require(!(data[0] & 128));
  std::ostringstream out;
  model::write_dataset(out, r.data);
  std::istringstream again(out.str());
  const model::Dataset d = model::parse_dataset(again, "again.csv");
  require(d.rows.size() == r.data.rows.size() && d.joint_count == 3);
  for (std::size_t i = 0; i < d.rows.size(); ++i) {
    require(d.rows[i].q == r.data.rows[i].q);
    require(d.rows[i].position == r.data.rows[i].position);
  }
  return 0;
}

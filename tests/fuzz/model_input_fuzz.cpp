// libFuzzer target for the host's two text readers (issue #16): the dataset CSV reader and the
// robot model YAML reader. The first input byte selects the reader; the rest is the file's text.
//   0  parse_dataset: either InputError or a dataset that write_dataset writes and parse_dataset
//      reads back to the same numbers (shortest exact form)
//   1  parse_model: either InputError or a model whose write_model text reads back as the same
//      robot (joints, name, tool kind; the numbers pass through rpy and decimal text, so they
//      are not compared bit for bit)
// Any other exception, a crash, a leak or undefined behaviour is a finding. Runs standalone too
// (file arguments), and as the ctest fuzz.model_input for a bounded time.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

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

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  if (data[0] % 2 == 0)
    fuzz_dataset(text);
  else
    fuzz_model(text);
  return 0;
}

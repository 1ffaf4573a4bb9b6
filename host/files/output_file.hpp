// The one rule for every file kincal writes (issue #16): an output never overwrites an input, and
// an output appears whole or not at all.
//
// refuse_overwriting() checks every output before any work (each command calls it first): an
// output whose directory does not exist, an output that exists and is not a regular file
// (directory, device, named pipe, socket: never replaced), and "-" where the command writes no
// standard output are refused by name; then it compares resolved paths
// (std::filesystem::weakly_canonical, and std::filesystem::equivalent for hard links) of every
// output against every input and every other output, and throws OutputError naming both options;
// an output with an image's name (input_limits.hpp's is_image_file) in a directory given as an
// input (of images: those files are its views, today's or the next run's) is refused the same way.
// Commands write their outputs only after every input is read and checked, so a failed run leaves
// no output behind.
// write_file_atomically() writes into a temporary file in the target's directory, fsyncs it,
// renames it over the target and fsyncs the directory: a crash, a full disk or an exception leaves
// the previous file (or none), never half a file. The journal of a session is the one file that is
// appended in place (host/session/journal.hpp); it is an input of the refusal check.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace kincal::files {

// A refused or failed output: the message names the option(s) and path(s).
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A path given on the command line, with the option that gave it ("--out", "-o", "image 3").
// An empty path (option not given) and "-" (standard output/input) take part in no comparison.
// `standard_output`: an output that may be "-" (the command documents it).
struct NamedPath {
  std::string option;
  std::string path;
  bool standard_output = false;
};

// Throws OutputError "--out d.csv is the same file as --data d.csv: refusing to overwrite an
// input (choose another output path)" when an output resolves to an input or to another output.
void refuse_overwriting(const std::vector<NamedPath>& outputs, const std::vector<NamedPath>& inputs);

// Writes `content` to `path` through a temporary file in the same directory and a rename. The new
// file keeps the permissions of the file it replaces (new files: 0666 less the umask). Throws
// OutputError naming the path and the system's reason -- also for a target that exists and is not
// a regular file; the target is then unchanged.
void write_file_atomically(const std::string& path, std::string_view content);

// write_file_atomically(), or standard output for "" and "-" (for outputs whose NamedPath has
// standard_output). Throws OutputError when standard output fails (a closed pipe, a full disk).
void write_output(const std::string& path, std::string_view content);

}  // namespace kincal::files

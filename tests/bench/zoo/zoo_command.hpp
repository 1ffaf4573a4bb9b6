// Running the kincal CLI as a user would (issue #41): one subprocess per command, its standard
// output and error kept, and the CSV files it writes read back by their header names.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace zoo {

struct CommandRun {
  std::string command_line;  // as a user would type it
  int exit_code = -1;        // 128 + signal when it died of one
  std::string out, err;
};

// Runs argv (argv[0] a path) in `directory`; its outputs go through files there named `<step>.out`
// and `<step>.err`. Throws std::runtime_error when the process cannot be started.
CommandRun run_command(const std::vector<std::string>& argv, const std::string& directory, const std::string& step);

// A CSV file's columns by header name, as text, and as numbers (a field that is not one reads as NaN).
std::map<std::string, std::vector<std::string>> read_csv_fields(const std::string& path);
std::map<std::string, std::vector<double>> read_csv_columns(const std::string& path);

std::string read_text(const std::string& path);
void write_text(const std::string& path, const std::string& text);

}  // namespace zoo

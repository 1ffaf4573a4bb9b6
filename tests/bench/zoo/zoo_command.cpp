#include "zoo_command.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

extern char** environ;

namespace zoo {

namespace {

std::string quoted(const std::string& s) { return s.find_first_of(" '\"$") == std::string::npos ? s : "'" + s + "'"; }

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> fields;
  std::istringstream in(line);
  for (std::string f; std::getline(in, f, ',');) fields.push_back(f);
  return fields;
}

}  // namespace

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + path);
}

CommandRun run_command(const std::vector<std::string>& argv, const std::string& directory, const std::string& step) {
  CommandRun run;
  for (const std::string& a : argv) run.command_line += (run.command_line.empty() ? "" : " ") + quoted(a);
  const std::string out_path = directory + "/" + step + ".out", err_path = directory + "/" + step + ".err";
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, 2, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  // The child runs in `directory`: the relative file names a user would type.
  posix_spawn_file_actions_addchdir_np(&actions, directory.c_str());
  std::vector<char*> args;
  std::vector<std::string> storage = argv;
  for (std::string& a : storage) args.push_back(a.data());
  args.push_back(nullptr);
  pid_t pid = 0;
  const int started = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (started != 0) throw std::runtime_error("cannot start " + argv[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  run.out = read_text(out_path);
  run.err = read_text(err_path);
  return run;
}

std::map<std::string, std::vector<std::string>> read_csv_fields(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::map<std::string, std::vector<std::string>> columns;
  if (!std::getline(in, line)) return columns;
  const std::vector<std::string> header = split(line);
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> fields = split(line);
    for (std::size_t i = 0; i < header.size(); ++i) columns[header[i]].push_back(i < fields.size() ? fields[i] : "");
  }
  return columns;
}

std::map<std::string, std::vector<double>> read_csv_columns(const std::string& path) {
  std::map<std::string, std::vector<double>> columns;
  for (const auto& [name, fields] : read_csv_fields(path))
    for (const std::string& f : fields) {
      char* end = nullptr;
      const double parsed = std::strtod(f.c_str(), &end);
      columns[name].push_back(end != f.c_str() && *end == '\0' ? parsed : std::nan(""));
    }
  return columns;
}

}  // namespace zoo

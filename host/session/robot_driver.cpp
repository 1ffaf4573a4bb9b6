#include "host/session/robot_driver.hpp"

#include <sys/wait.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <istream>
#include <ostream>

namespace kincal::session {

namespace {

std::string joint_list(const std::vector<double>& q) {
  std::string out;
  char number[32];
  for (std::size_t i = 0; i < q.size(); ++i) {
    std::snprintf(number, sizeof number, "%.9g", q[i]);
    if (i) out += ' ';
    out += number;
  }
  return out;
}

}  // namespace

std::string expand_robot_command(const std::string& command_template, const std::vector<double>& target) {
  std::string out;
  const std::string list = joint_list(target);
  for (std::size_t i = 0; i < command_template.size();) {
    if (command_template.compare(i, 3, "{q}") == 0) {
      out += list;
      i += 3;
    } else {
      out += command_template[i++];
    }
  }
  return out;
}

std::vector<double> parse_readings(const std::string& text, std::size_t count) {
  std::vector<double> values;
  const char* p = text.data();
  const char* end = p + text.size();
  while (p < end) {
    if (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r' || *p == ',') {
      ++p;
      continue;
    }
    double v = 0;
    const auto [next, ec] = std::from_chars(p, end, v);
    if (ec != std::errc{} || !std::isfinite(v)) return {};
    values.push_back(v);
    p = next;
  }
  if (values.size() != count) return {};
  return values;
}

std::vector<double> ManualRobotDriver::move_to(int index, const std::vector<double>& target) {
  prompt_ << "\npose " << index << ": move the robot to q = [" << joint_list(target)
          << "] (rad, m) and press Enter;\n  type the readings if the robot stands elsewhere, or 'q' to stop: "
          << std::flush;
  std::string line;
  if (!std::getline(answers_, line)) throw SessionError("pose " + std::to_string(index) + ": no answer (end of input)");
  if (line == "q" || line == "quit") throw SessionError("pose " + std::to_string(index) + ": stopped by the operator");
  if (line.find_first_not_of(" \t\r") == std::string::npos) return target;
  std::vector<double> readings = parse_readings(line, target.size());
  if (readings.empty())
    throw SessionError("pose " + std::to_string(index) + ": '" + line + "' is not " + std::to_string(target.size()) +
                       " joint readings");
  return readings;
}

CommandRobotDriver::CommandRobotDriver(std::string command_template) : template_(std::move(command_template)) {
  if (template_.find("{q}") == std::string::npos)
    throw SessionError("--robot-cmd '" + template_ + "': the command must contain {q} (the joint values)");
}

std::vector<double> CommandRobotDriver::move_to(int index, const std::vector<double>& target) {
  const std::string command = expand_robot_command(template_, target);
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) throw SessionError("pose " + std::to_string(index) + ": cannot run '" + command + "'");
  std::string output;
  char buffer[512];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0 && output.size() < 65536) output.append(buffer, n);
  const int status = ::pclose(pipe);
  if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    const std::string how = status != -1 && WIFEXITED(status)
                                ? "exited with status " + std::to_string(WEXITSTATUS(status))
                                : std::string("did not exit normally");
    throw SessionError("pose " + std::to_string(index) + ": robot command '" + command + "' " + how);
  }
  std::vector<double> readings = parse_readings(output, target.size());
  return readings.empty() ? target : readings;
}

}  // namespace kincal::session

#include "host/files/output_file.hpp"

#include "host/files/input_limits.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <system_error>
#include <vector>

#include "host/files/file_type.hpp"

namespace kincal::files {

namespace {

namespace fs = std::filesystem;

bool takes_part(const NamedPath& p) { return !p.path.empty() && p.path != "-"; }

// The same file: equal resolved paths, or (both existing) the same inode through another name.
bool same_file(const std::string& a, const std::string& b) {
  std::error_code ea, eb;
  const fs::path ca = fs::weakly_canonical(fs::absolute(a), ea);
  const fs::path cb = fs::weakly_canonical(fs::absolute(b), eb);
  if (!ea && !eb && ca == cb) return true;
  std::error_code ee;
  return fs::exists(a, ee) && fs::exists(b, ee) && fs::equivalent(a, b, ee) && !ee;
}

std::string describe(const NamedPath& p) { return p.option + " " + p.path; }

// Whether `output` is an image in `input`, a directory given as images: one of them, or one the
// next run that reads the directory would take as a view. Other files beside them (a calibration
// written next to its views) are not read from it.
bool image_in_directory(const std::string& output, const std::string& input) {
  std::error_code ec;
  if (!is_image_file(output) || !fs::is_directory(input, ec)) return false;
  const fs::path parent = fs::path(output).parent_path();
  return same_file(parent.empty() ? "." : parent.string(), input);
}

// Why an existing output is not replaced, or "" for a regular file.
std::string not_replaceable(mode_t mode) {
  const std::string why = not_a_regular_file(mode);
  return why.empty() || S_ISDIR(mode) ? why : why + ": refusing to replace it";
}

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw OutputError(path + ": " + what + " (" + std::strerror(errno) + ")");
}

// Closes a descriptor and removes the temporary file unless the rename consumed it.
class Temporary {
 public:
  explicit Temporary(std::string pattern) : name_(std::move(pattern)) {
    std::vector<char> buffer(name_.begin(), name_.end());
    buffer.push_back('\0');
    fd_ = ::mkstemp(buffer.data());
    if (fd_ >= 0) name_ = buffer.data();
  }
  Temporary(const Temporary&) = delete;
  Temporary& operator=(const Temporary&) = delete;
  ~Temporary() {
    if (fd_ >= 0) ::close(fd_);
    if (!renamed_) ::unlink(name_.c_str());
  }
  int fd() const { return fd_; }
  const std::string& name() const { return name_; }
  void close_checked(const std::string& path) {
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) fail(path, "cannot write");
  }
  void renamed() { renamed_ = true; }

 private:
  std::string name_;
  int fd_ = -1;
  bool renamed_ = false;
};

// The temporary file write_file_atomically() writes `path` through, in the same directory.
std::string temporary_pattern(const std::string& path) {
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  return (dir / ("." + target.filename().string() + ".kincal-XXXXXX")).string();
}

// An output that cannot be written where it is named: refused before any work. Whether its
// directory takes the temporary file is tried (and the file removed), not judged by access(),
// which says yes to root on a read-only /sys.
void check_output(const NamedPath& p) {
  if (p.path.empty()) return;
  if (p.path == "-") {
    if (!p.standard_output)
      throw OutputError(describe(p) +
                        ": this command does not write to standard output (name a file; ./- for a "
                        "file named '-')");
    return;
  }
  const fs::path dir = fs::path(p.path).parent_path();
  struct stat st {};
  if (::stat(p.path.c_str(), &st) == 0) {
    if (const std::string why = not_replaceable(st.st_mode); !why.empty()) throw OutputError(describe(p) + ": " + why);
  } else {
    std::error_code ec;
    if (!dir.empty() && !fs::is_directory(dir, ec))
      throw OutputError(describe(p) + ": the directory " + dir.string() + " does not exist");
  }
  const Temporary probe(temporary_pattern(p.path));
  if (probe.fd() < 0) {
    const int error = errno;
    throw OutputError(describe(p) + ": cannot create a file in the directory " + (dir.empty() ? "." : dir.string()) +
                      " (" + std::strerror(error) + ")");
  }
}

}  // namespace

void refuse_overwriting(const std::vector<NamedPath>& outputs, const std::vector<NamedPath>& inputs) {
  const auto refuse = [](const NamedPath& out, const NamedPath& other, const char* kind) {
    throw OutputError(describe(out) + " is the same file as " + describe(other) + ": refusing to overwrite " + kind +
                      " (choose another path for " + out.option + ")");
  };
  for (const NamedPath& o : outputs) check_output(o);
  for (auto o = outputs.begin(); o != outputs.end(); ++o) {
    if (!takes_part(*o)) continue;
    for (const NamedPath& in : inputs) {
      if (takes_part(in) && same_file(o->path, in.path)) refuse(*o, in, "an input");
      if (takes_part(in) && image_in_directory(o->path, in.path))
        throw OutputError(describe(*o) + " is an image in the directory " + describe(in) +
                          ": refusing to write among its views (choose another path for " + o->option + ")");
    }
    for (auto later = o + 1; later != outputs.end(); ++later)
      if (takes_part(*later) && same_file(o->path, later->path)) refuse(*later, *o, "another output");
  }
}

void write_file_atomically(const std::string& path, std::string_view content) {
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  struct stat existing {};
  mode_t mode = 0;
  if (::stat(path.c_str(), &existing) == 0) {
    if (const std::string why = not_replaceable(existing.st_mode); !why.empty()) throw OutputError(path + ": " + why);
    mode = existing.st_mode & 07777;
  } else {
    const mode_t mask = ::umask(0);
    ::umask(mask);
    mode = 0666 & ~mask;
  }
  Temporary tmp(temporary_pattern(path));
  if (tmp.fd() < 0) fail(path, "cannot create a temporary file beside it");
  if (::fchmod(tmp.fd(), mode) != 0) fail(path, "cannot set the permissions of its temporary file");

  const char* data = content.data();
  std::size_t left = content.size();
  while (left > 0) {
    const ssize_t n = ::write(tmp.fd(), data, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail(path, "cannot write");
    data += n;
    left -= static_cast<std::size_t>(n);
  }
  if (::fsync(tmp.fd()) != 0) fail(path, "cannot flush to disk");
  tmp.close_checked(path);
  if (::rename(tmp.name().c_str(), path.c_str()) != 0) fail(path, "cannot replace");
  tmp.renamed();
  // The rename itself is durable once the directory is flushed; a failure here loses nothing.
  const int dir_fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
}

void write_output(const std::string& path, std::string_view content) {
  if (!path.empty() && path != "-") {
    write_file_atomically(path, content);
    return;
  }
  std::cout.write(content.data(), static_cast<std::streamsize>(content.size()));
  std::cout.flush();
  if (!std::cout) throw OutputError("standard output: cannot write");
}

}  // namespace kincal::files

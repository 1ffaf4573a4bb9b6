// What input_file.cpp and output_file.cpp say about a path that is not a regular file.
#pragma once

#include <sys/stat.h>

#include <string>

namespace kincal::files {

// "is a directory, not a file", "is a character device, not a regular file", ... for a file of
// this st_mode that is not regular; "" for a regular file.
inline std::string not_a_regular_file(mode_t mode) {
  if (S_ISREG(mode)) return "";
  if (S_ISDIR(mode)) return "is a directory, not a file";
  const char* type = S_ISCHR(mode)    ? "a character device"
                     : S_ISBLK(mode)  ? "a block device"
                     : S_ISFIFO(mode) ? "a named pipe (FIFO)"
                     : S_ISSOCK(mode) ? "a socket"
                                      : "a special file";
  return std::string("is ") + type + ", not a regular file";
}

}  // namespace kincal::files

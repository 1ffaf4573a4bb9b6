// Numbers in files kincal writes for other programs (URDF, controller calibration files): the
// shortest text that reads back as the same double (std::to_chars), never "-0".
#pragma once

#include <charconv>
#include <string>

namespace kincal::model {

inline std::string shortest_number_text(double v) {
  if (v == 0.0) v = 0.0;
  char buffer[64];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, v);
  return ec == std::errc() ? std::string(buffer, end) : std::string("nan");
}

}  // namespace kincal::model

// Numbers in the camera module's text reports (internal to host/camera).
#pragma once

#include <cstdio>
#include <string>

namespace kincal::camera {

// `v` with `decimals` digits after the point ("%.*f").
inline std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

// `v` with four significant digits ("%.4g").
inline std::string general(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

}  // namespace kincal::camera

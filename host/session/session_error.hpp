// The error a calibration session stops with (issue #6): its message names the pose and what
// failed (robot driver, sensor, journal), so the operator knows where to resume.
#pragma once

#include <stdexcept>

namespace kincal::session {

class SessionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace kincal::session

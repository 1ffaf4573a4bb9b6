// The camera tests' way to check a refusal's text: several parts of one message, each by CHECK.
#pragma once

#include <exception>
#include <string>

// What f throws, or "(no error)" when it returns.
template <typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

inline bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

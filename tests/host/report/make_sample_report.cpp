// Writes the sample report (sample_report.hpp) to the path given: the page the browser test renders.
#include <cstdio>
#include <exception>

#include "sample_report.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_sample_report OUT.html\n");
    return 2;
  }
  try {
    kincal::report::write_html(kincal::report::testing::sample_report(), argv[1]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_sample_report: %s\n", e.what());
    return 1;
  }
  return 0;
}

// Writes the sample report (sample_report.hpp) to the path given, and the layout stress page to
// the second path when one is given: the pages the browser test renders.
#include <cstdio>
#include <exception>
#include <fstream>

#include "sample_report.hpp"

int main(int argc, char** argv) {
  if (argc != 2 && argc != 3) {
    std::fprintf(stderr, "usage: make_sample_report OUT.html [STRESS.html]\n");
    return 2;
  }
  try {
    kincal::report::write_html(kincal::report::testing::sample_report(), argv[1]);
    if (argc == 3 && !(std::ofstream(argv[2], std::ios::binary) << kincal::report::testing::layout_stress_page())) {
      std::fprintf(stderr, "make_sample_report: cannot write %s\n", argv[2]);
      return 1;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_sample_report: %s\n", e.what());
    return 1;
  }
  return 0;
}

// A sample report with every section and two runs (a simulated 6R arm with validation poses; a
// simulated RRP rig with circle and line sweeps, bus statistics and a paper comparison), made
// from seeded random numbers: what the report tests and the browser test render.
#pragma once

#include <string>

#include "host/report/report.hpp"

namespace kincal::report::testing {

Report sample_report();

// Figures in the sample that a reader must find in the page (as the report prints them).
inline constexpr const char* kSampleNominalMean = "3.2100 mm";
inline constexpr const char* kSampleIdentifiedRms = "0.0312 mm";
// Plots the sample holds: accuracy (2 runs), per pose (1 run), per joint (6), sweeps (2 circles
// with their residuals, 1 line, and a 3-D view of each of the 3).
inline constexpr int kSamplePlots = 2 + 1 + 6 + 2 * 2 + 1 + 3;

// A page of kStressPlots plots whose text makes layout hard, from seeded random numbers: long
// titles, legends, category names, axis labels and notes; tick labels of 7 digits or negative;
// log axes over many decades; sizes from 200 x 120 px up; equal aspect. The browser test checks
// that no text of them leaves its plot or overlaps another.
std::string layout_stress_page();
inline constexpr int kStressPlots = 48;

}  // namespace kincal::report::testing

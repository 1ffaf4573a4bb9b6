// `kincal demo` (issue #6): the whole calibration loop on the two simulated rigs of the papers,
// with the real firmware and protocol in the loop, and on the everyday rig of a camera and a
// printed board (issue #26), and the report.
//
// Per rig (simulated_rig.hpp): plan the poses, run the session (journal in the output folder),
// identify, compare with the hidden truth, and write one section of the HTML report.
//   ARID      Doty's platform rig: 40 random poses in view of the strip (full pose
//             measurements) + 30 random validation poses; full identification from the nominal
//             model; then the correction parameters go to the platform and the validation poses
//             are measured again at the corrected joint targets the platform streams back, and
//             the true tool pose at those targets (the simulator's truth) is compared with the
//             targets' goals too, so the correction is judged with and without the platform's
//             measurement noise.
//   Kapucu    Kapucu & Baysec's stereo rig: their single-joint sweeps, 10 readings per joint +
//             30 random validation poses (beacon in view); circle-point analysis, then the full
//             identification started from it; the DH table beside their Table 1 and the truth.
//   board     a camera on a UR5's flange and a printed 9 x 6 chessboard (0.3 m) fixed in the cell:
//             40 random poses near home with the whole board in view + 30 validation poses, each
//             view a full pose with its 6x6 covariance; full identification from the nominal
//             model, the board's place (base) and the camera's (tool, hand-eye) with the arm.
// Printed: the identified parameters beside the truth, before/after accuracy on the validation
// poses, and the identified model's error against the true tool positions in units of the
// measurement noise floor (the RMS distance of the measured positions from the true ones on the
// same poses) -- `demo_validation_rms_over_noise`, which tests/bench prints as a FIGURE.
//
// Errors: model::InputError (robots folder without the model files), SessionError, ReportError.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "host/identify/identify.hpp"
#include "host/session/online_correction.hpp"

namespace kincal::session {

struct DemoOptions {
  std::string robots_dir;  // holds arid_prrr.yaml, stanford_rrp.yaml and ur5.yaml
  std::string output_dir = "kincal-demo";
  std::uint64_t seed = 1;
  bool quick = false;  // about half the poses (for tests)
};

// The online correction against the simulator's truth: the true tool pose at the validation
// targets as given (uncorrected) and at the platform's corrected targets, each vs the targets'
// goals (position and orientation); no measurement noise in either.
struct CorrectionTruth {
  identify::AccuracyStats uncorrected, corrected;
};

struct DemoRigResult {
  std::string name;
  identify::AccuracyStats before, after;  // nominal and identified model vs the measurements
  double identified_vs_truth_rms_m = 0;   // identified model vs the true tool positions
  double nominal_vs_truth_rms_m = 0;
  double noise_rms_m = 0;                              // measured vs true tool positions, on the same poses
  std::optional<CorrectionCheck> correction;           // measured by the platform (its noise included)
  std::optional<CorrectionTruth> correction_vs_truth;  // the same check against the truth
  double seconds = 0;
};

struct DemoResult {
  std::vector<DemoRigResult> rigs;
  std::string report_path;
};

DemoResult run_demo(const DemoOptions& options, std::ostream& out);

}  // namespace kincal::session

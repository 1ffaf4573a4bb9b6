// Mistakes in a dataset that are made of plausible numbers (issue #41): checks that fit the data
// rather than compare their scale, so they hold for any arm and any instrument.
//
//   mirror        the measuring device's frame is left-handed against the robot's (two position
//                 columns swapped, an axis flipped at export): consecutive distances are kept, so
//                 the scale checks (plausibility.hpp) pass, and a solve "converges" to a model error
//                 of hundreds of mm. Found by registering the nominal tool points onto the measured
//                 ones twice, once with a rotation and once with a reflection (each with the
//                 measured point's offset from the tool estimated, as a reflector is rarely where
//                 the nominal tool is): a reflection that fits far better is the finding.
//   joint convention  the readings in another convention than the model's: two joint columns
//                 swapped or all in reverse order, a joint counted the other way round or from a
//                 zero a quarter or half turn away, a joint read relative to the one before it (a
//                 parallelogram arm's J2/J3): the readings taken the other way fit far better. A
//                 base joint's zero is the registration's and the last joint's the measured
//                 point's: no finding, no harm.
//   out of step   the robot's and the instrument's logs joined with one shifted by a row or a
//                 few: each row's readings with the position a few rows away fit far better.
//   moved         the instrument (or the robot's base) moved during the session: a second
//                 registration from some row on fits far better (a tracker bumped, a camera
//                 re-aimed halfway; the file's order is the session's). Or the measured point moved
//                 on the arm (a reflector re-seated in another nest, a marker knocked): a second
//                 offset from the tool, with the one registration, fits as well as both together;
//                 named apart from the instrument's move.
//
// Both fits are point registrations (Kabsch/Umeyama without scale, alternated with the linear
// least squares of the measured point's offset in the tool frame), O(rows) each; at most
// kMistakeRows rows (spread evenly over the file) are used. A finding needs the as-given
// registration to leave more than kMistakeFloor_m RMS -- far beyond what a real arm deviates from
// its drawing (millimetres for a service arm) -- and the alternative to fit at least five times
// better; data that cannot tell (a single sweep: points in a plane fit their mirror image
// exactly) give no finding. A move must also fit below kMistakeFloor_m: a wrong model's error is
// partly absorbed by a second registration, never down to an arm's accuracy (and it needs
// kMovedRatio, below, and each part to move every joint: a sweep of the wrist alone is fitted
// exactly by a registration of its own whatever the earlier joints' errors). A service arm's own
// errors can leave more than that floor, so after the solve, when the fit explains nothing,
// identify runs these checks again against the calibrated model (a 3 m arm with 1 deg errors and
// its tracker moved for the last 40 % of 300 rows: found only then).
// Moves that leave the as-given registration within kMistakeFloor_m (a tracker nudged by a
// millimetre) are not found here; after the solve, moved_against (below) looks for them against
// the calibrated model.
//
// After the solve:
//   fit verdict   a calibrated model that still leaves more than kMistakeFloor_m RMS and more than
//                 kMistakeNoiseRatio times the instrument noise explains nothing: the verdict says so
//                 and names the likely causes, never "close to nominal".
//   held out      validation rows that are training rows (the same readings and the same measured
//                 point, to the digits a file written again keeps) do not judge a calibration; rows
//                 at training readings measured anew judge repeatability more than the calibration
//                 between them.
#pragma once

#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "host/model/dataset.hpp"
#include "host/model/robot_model.hpp"

namespace kincal::identify {

// A number in a finding's sentence: 4 significant digits (plausibility.hpp's findings too).
std::string finding_number(double v);

inline constexpr int kMistakeRows = 2000;
inline constexpr double kMistakeFloor_m = 0.01;
inline constexpr double kMistakeNoiseRatio = 100.0;
inline constexpr int kMaxShiftRows = 3;       // the logs' steps tried each way
inline constexpr std::size_t kSplitRows = 8;  // rows each side of a registration's move, at least
// A move needs its two registrations to fit kMovedRatio times better than one, not 5: a tracker
// bumped 2 deg and 10 mm before the last 40 % of 40 UR10 rows leaves one registration 11 mm, the
// arm's own millimetre errors two 3.2 mm.
inline constexpr double kMovedRatio = 3.0;
// Explanations that fit within kSameFit times the best one's RMS fit as well: joint conventions
// named beside the best (points cannot tell them apart: exactly for the nominal; the arm's own
// errors fit each a little differently, 0.71 and 0.80 mm for the ARID's shoulder reversed and
// turned), and a move of the instrument or of the measured point alone against both.
inline constexpr double kSameFit = 2.0;

// What the fits above find, from one set of tool poses and one rotation registration:
//   measured_point_offset  the measured point's offset from the nominal tool, in the tool frame,
//                          that the rotation registration fits (a reflector on the flange where
//                          the model's tool is the flange): what the scale checks (plausibility.hpp)
//                          add to the nominal tool before comparing distances. Zero with fewer than
//                          6 rows, or beyond kMaxMeasuredPointOffset_m (no reflector or marker is
//                          mounted so far: the data are more wrong than an offset, and the scale
//                          check must see it).
//   registration_rotation  the device's rotation from the model's base that the positions fit (measured
//                          = R point + b), when they fit within kMistakeFloor_m: what the measured
//                          orientations must turn by too (plausibility.hpp).
//   mistakes               the findings above, one sentence each with the numbers (empty: none).
// Part of implausibilities() (plausibility.hpp).
inline constexpr double kMaxMeasuredPointOffset_m = 0.5;
struct FrameCheck {
  model::Vector3 measured_point_offset = model::Vector3::Zero();
  std::optional<model::Matrix3> registration_rotation;
  std::vector<std::string> mistakes;
};
FrameCheck frame_check(const model::RobotModel& nominal, const model::Dataset& data);

// The move check (`moved`, above) against the calibrated model, whatever its residual: a precise arm
// whose tracker was bumped 1 deg and 5 mm for the last 40 % of 40 rows leaves 7 mm RMS calibrated
// (under kMistakeFloor_m, so frame_check and unexplained_fit said nothing, and the verdict called
// the arm "close to its nominal geometry"). With the arm's errors calibrated away, a second
// registration that fits kCalibratedMovedRatio times better than one is the finding (the sentence
// frame_check gives); nothing otherwise, or with fewer than 2 kSplitRows rows. Measured: such
// moves fit 6.3 to 7.3 times better (40 rows of the UR10, the PUMA, the heavy arm; the zoo's
// irb2400 7.1), and 2.9 where a 7-joint arm's 31 parameters on 40 rows absorb more of the move
// (the zoo's sia20d); data without a move at most 1.34 times (the real UR10's rows in their
// session's order, 20 to 1495 of them) and 1.18 (the zoo's 72 cases of draw 0).
// Where the calibrated fit is already unexplained (`fit_unexplained`: unexplained_fit found it), the
// check no longer decides whether something is wrong, only names what: a move then need fit only
// kUnexplainedMovedRatio times better, where the second part's registration and offset (9
// parameters) are significant at kMoveSignificance by an F test against the calibration's residual
// degrees of freedom (3 a row - `identified_parameters`; none left: no finding). A measured point
// re-seated 40 mm away for the last 8 of 20 rows of a UR10 with a joint scale error: the 33
// parameters absorbed most of it (14 mm RMS left), a second part fits 2.2 to 2.4 times better,
// F(9, 18) = 7.7 to 9.5, p 1.4e-4 to 3e-5 as the noise's REML counts the priors' rows or not -- a
// level of 1e-4 named it by a factor of 3 on one and not on the other, 1e-3 by 7 and 29 (the
// check only names a cause where the fit is already unexplained); the real UR10's rows without a
// move never reach an unexplained fit.
inline constexpr double kCalibratedMovedRatio = 2.5;
inline constexpr double kUnexplainedMovedRatio = 2.0;
inline constexpr double kMoveSignificance = 1e-3;
std::optional<std::string> moved_against(const model::RobotModel& calibrated, const model::Dataset& data,
                                         bool fit_unexplained, int identified_parameters);

// A sentence when a calibrated model's RMS residual (m) is too large for any arm to leave (see
// above), naming the likely causes; nothing otherwise. `instrument_sigma_m` 0: unknown.
std::optional<std::string> unexplained_fit(double rms_m, double instrument_sigma_m);

// The same for the orientations (rad): more than kOrientationFloor_rad RMS (and kMistakeNoiseRatio
// times the instrument's orientation noise when given) is no arm's error but the orientation
// columns' -- another Euler convention than the export's (the real UR10 rows imported extrinsic
// where they are intrinsic: 15.6 deg RMS, the positions' fit unchanged), a quaternion order or
// inverse the checks before the solve did not catch. The solve weighs such orientations by their
// own misfit, so the positions' fit stands; the warning says so.
inline constexpr double kOrientationFloor_rad = 5.0 * std::numbers::pi / 180.0;
std::optional<std::string> unexplained_orientations(double rms_rad, double instrument_sigma_rad);

// The opposite of unexplained_fit: residuals kOverstatedNoiseRatio times smaller per axis than the instrument noise
// given (`--sigma` or the data's sigma or covariance columns; its median per axis, m) allows with
// `equations` and `parameters`, where those leave at least kMinNoiseDegrees degrees of freedom.
// No data scatter so far below their noise: the noise was given in mm (or mm^2) where kincal takes
// m (m^2) -- `--sigma 0.02` meant as 0.02 mm is 20 mm, and every standard deviation, the priors'
// weight (a puma's 40 rows fitted with priors left 4.2 mm RMS where 0.03 mm was there to have;
// model selection's unregularized candidate gave it back on a KUKA's 100), the outlier test and
// correct's spreads took it so. A sentence naming that; nothing otherwise.
inline constexpr double kOverstatedNoiseRatio = 10.0;
inline constexpr int kMinNoiseDegrees = 10;
std::optional<std::string> overstated_noise(double rms_m, double instrument_sigma_m, int equations, int parameters);

// How many of `held_out`'s rows are rows of `training`: the same readings and measured position
// (`rows`), or the same readings only (`configurations`, counting those rows too). The same: within
// what a file written again with fewer digits changes (a joint in degrees to 3 decimals, a
// position in mm to 3: model::same_readings) -- a re-measured point differs by the instrument's
// noise, more than that.
inline constexpr double kSamePosition_m = 1e-6;  // each coordinate
struct SharedRows {
  int rows = 0;
  int configurations = 0;
};
SharedRows training_rows_in(const model::Dataset& held_out, const model::Dataset& training);

}  // namespace kincal::identify

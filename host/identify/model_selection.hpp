// The model chosen by the data (issue #23): cross-validation over candidate models, what
// `kincal identify` runs before its solve.
//
// Candidates (candidate_models), from the smallest model to the largest:
//   registration        the base and the tool only, the geometry nominal
//   joint-offsets       and each joint's zero offset (theta<i>)
//   geometry-x2         every geometric parameter, the default priors twice as strong (sigmas
//                       halved), fixed
//   geometry            every geometric parameter, the priors' widths chosen by the data
//                       (prior_scale.hpp): the default before model selection
//   geometry-x0.5       the default priors half as strong (sigmas doubled), fixed
//   geometry-noprior    no priors: plain least squares
//   geometry+nongeometric  every parameter, the model file's scale<i>/compliance<i> included
//                       (only when the model has them; the geometry candidates hold them fixed)
//   geometry+gravity    every parameter and a compliance<i> (no prior) for every joint, gravity's
//                       deflection through the model's masses (only when links or payload have a
//                       mass and the model declares no compliance; identifiability holds fixed
//                       the joints gravity does not load): on the UR10 set, with the masses Universal
//                       Robots publishes, it is chosen and predicts 0.406 mm held out against
//                       geometry+scales' 0.428 (300 rows), 0.432 against 0.443 out of range
//   geometry+sag        every parameter, a compliance<i> for every joint and each link's mass<i>
//                       and centre of mass com_*<i> (priors centred on the start, their widths
//                       chosen by the data; only when the model has neither masses nor a
//                       compliance, as most public URDFs): identified in two stages and a gauge,
//                       masses and compliances never negative (sag.hpp)
//   geometry+scales     every parameter and a scale<i> (gear ratio, prior 1 %) for each joint
//                       the model file gives none (only when there is such a joint): on the UR10
//                       set the readings' scales are identified to about 0.01 % and differ from 1
//                       by up to 0.09 %
//   geometry+couplings  every parameter and a coupling<i>_<i-1> (prior 1 %) for each revolute
//                       joint after a revolute one: its share of the upstream joint's reading
//                       (model/robot_model.hpp; a transmission through the joint before it, as
//                       Fanuc's elbow J2 + J3), which no URDF carries
// Each is the caller's options (noise, rejection, --fix, --prior) with the candidate's fixed
// parameters added and its prior strength multiplied. Every candidate but geometry-x2 and
// geometry-x0.5 lets the data choose its priors' widths (prior_scale.hpp); those two keep the
// default widths, halved and doubled, so that cross-validation can overrule the evidence. The
// solve keeps every candidate within the physical bounds (problem.hpp: compliances never
// negative), so that each writes a model every command accepts.
//
// Scores, position errors of rows the candidate was not identified from (nothing is tuned on
// other data):
//   K-fold RMS          the rows in a fixed pseudo-random order (seed 23) dealt into K folds; each
//                       fold predicted by the candidate identified from the others
//   out-of-range RMS    the rows whose readings all lie inside the central `central_fraction` of
//                       each joint's range over the data (out_of_range_split; widened until they
//                       are a quarter of the rows, out_of_range_fold) train, the rest are
//                       predicted: extrapolation, where the #23 peers' data showed the
//                       difference between models
// Score: the mean of the two RMS values (extrapolation weighs as much as the K folds together); the
// K-fold RMS alone when there is no out-of-range fold: no row lies inside every joint's central
// range (e.g. a joint visited at two values only) or none outside, or a candidate the K folds
// judged cannot be identified from the rows in range (the fold would favour the small models that
// can). When the rows in range give fewer than 5 equations per parameter of the largest candidate
// judged, the score is the K-fold RMS and the fold's errors count only row by row in the paired
// test below: one split trained on a few rows judges their noise, and its RMS weighed as much as
// all K folds (on the zoo's irb6640/camera-board/coupled/40, 15 rows in range, 90 equations for
// 36 parameters, it preferred geometry+scales, 0.985 mm against 1.31, over the true couplings,
// which the K folds favoured 0.44 against 0.62, and left 10.9 times the oracle's held-out error;
// scored by the K folds, the couplings: 1.04), where row by row its rows still add their evidence
// (the UR10 bench's 30 training rows: geometry+scales beats geometry at paired t -2.0 with
// them, 0.4658 mm held out against 0.4807; its extrapolation split has 463 rows in range).
// A candidate that cannot be identified on some K-fold training rows (too few of them, a
// joint that never moved there) is out.
// The folds leave out configurations, not rows: a pose measured twice (model::configuration_of_rows)
// is in one fold whole -- a copy in training predicts the other by what that pose alone does, and
// favoured the larger candidates. "Rows" below counts configurations.
// K: 5 from kMinRowsForFiveFolds (100) rows; below, min(rows, few_rows_folds = 10) -- every row
// predicted from 90 % of the others or more, so that the large candidates can be identified on a
// fold's training rows (leave-one-out, K = rows, costs twice as much at 20 rows and more above).
// Rule, at every size: a candidate must have a lower score than the default (`geometry`) and
// held-out position errors lower than the default's row by row, by 2 standard errors of the
// paired differences (statistics.hpp: paired_t <= -2, the rejection gate's test; one difference
// per row: its K-fold error's, plus its out-of-range error's when the rule counts that fold and
// the row is in it -- counted as two rows, a row predicted in both folds made the test look
// surer than its data) -- or, for a candidate built on what the user gave about the arm's
// physics (Candidate::holds), a lower score alone (cross-validation's own rule: the masses, the
// file's terms are evidence the rows need not repeat; on the shared UR10 at 30 rows gravity
// predicted better in 25 of 25 choices and the 2-error bar chose it in 8), where the rows see
// that physics: a candidate with compliances whose gravity deflection at the K folds' held-out
// rows (RMS) is below its K-fold RMS takes the 2-error bar (on a rigid arm its free compliances
// fit a coincidence of the rows that the folds see too). Of those, the candidates built on what
// the user gave about the arm's physics (Candidate::holds: the model file's own scales and
// compliances, geometry+gravity with its masses) are taken first, then the others from the fewest
// parameters up, and each replaces the one chosen so far only by beating it row by row by the
// same 2 errors (one of as many parameters or one more, against one not built on physics, by a
// lower score alone): a larger structure shows what it adds over the smaller one it would replace
// as it must over the default (on a 7-joint Franka Panda measured by motion capture at 20 rows with
// one joint's scale off, geometry+sag's 49 parameters scored 9 % under geometry+scales' 38, paired
// t -0.9 between them, and predicted 1.35 times the oracle's held-out error where the scales give
// 1.11; prior_test), where two structures of about one size -- a joint's scale and its coupling,
// one parameter apart -- fit the noise alike and the score tells them apart (a ViperX 300 s by
// motion capture at 20 rows, one joint's scale off: geometry+scales' 33 parameters scored 20 %
// under geometry+couplings' 32, paired t -1.9, and predicted 1.10 times the oracle's held-out error
// where the couplings left 1.84). When cross-validation cannot judge the default (it
// cannot be identified on some fold's rows), it stands. Why not the lowest score alone: the scores
// of near-equal candidates differ by chance (with tens of rows, five folds of a few rows judge
// mostly noise, and the lowest alone traded the default for noise on a precise arm), and a
// generic structure can follow a physical effect inside the range of the data and not beyond it:
// on the shared UR10's extrapolation split (463 rows in the central 70 % of every joint's range,
// 1,032 judged), couplings scored 0.0061 mm below gravity (paired t -1.8) and extrapolated to
// 0.502 mm where gravity gives 0.427. Why from the fewest parameters and not in the list's order:
// on the zoo's coupled Motoman at 20 rows the true couplings (one parameter fewer than the scales)
// scored 15 % below the scales (paired t -1.7) and predicted 3.5 times better; a holder in the
// list's order kept the scales. A structure the default lacks shows in every row (a 0.4 %
// joint scale is millimetres at the tool: in the zoo the default left 200 times the oracle's
// held-out error at 20 rows, tests/bench/zoo).
// Below kMinRowsForSelection (20) rows `kincal identify` does not select: the large candidates
// cannot be identified on a fold's rows (a 7-joint arm measured at a point has 31 geometric
// parameters, 38 with a scale per joint, and the noise, from 3 equations a row) and the paired
// test over so few rows has little power.
//
// Cost: (K + 1) solves per candidate, 6 to 10 candidates: on the shared UR10 set (1495 rows) that
// is 48 solves; see realdata_ur10_bench for the measured time. Below 100 rows, (K + 1) per
// candidate and 6 more for the chosen one (the rejection gate's 5 folds, below): at most 11 solves
// per candidate, 15 to 25 ms each at 20 to 40 rows (Release, loaded machine): with 20 folds
// `kincal identify` on 40 PUMA rows took 3.4 s of CPU against 0.1 s without selection, a 7-joint
// arm with masses 5.7 s; 10 folds about halve that. `kincal identify` runs it by default with
// at least kMinRowsForSelection rows; otherwise, and with --params, --no-prior, --method other
// than full or --start cpa, the default is `geometry`.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "host/identify/identify.hpp"

namespace kincal::identify {

inline constexpr int kMinRowsForSelection = 20;
inline constexpr int kMinRowsForFiveFolds = 100;

struct Candidate {
  std::string name;
  std::string description;
  RobotModel model;  // what it identifies from: the nominal, or the nominal with scales added
  IdentifyOptions options;
  // Built on what the user gave about this arm's physics (its masses, its file's scales and
  // compliances): stands against a later candidate unless beaten row by row (the rule above).
  bool holds = false;
};

// The geometry+gravity candidate's model: the nominal with a gravity compliance on every joint,
// gravity's direction and each link's centre of mass (where the link has a mass) identified, when
// its links or payload have masses and it declares no compliance; nullopt otherwise. `kincal
// plan` plans for it (plan.hpp).
std::optional<RobotModel> gravity_model(const RobotModel& nominal);

// The candidates above for this model and the caller's options.
std::vector<Candidate> candidate_models(const RobotModel& nominal, const IdentifyOptions& base);

// The candidate named `name`; throws model::InputError listing the names when there is none.
Candidate find_candidate(const RobotModel& nominal, const IdentifyOptions& base, const std::string& name);

// Rows inside the central `fraction` of every joint's range over the data (train) and the rest.
struct RowSplit {
  std::vector<int> inside;
  std::vector<int> outside;
  double fraction = 0.0;  // the central fraction that made it
};
RowSplit out_of_range_split(const model::Dataset& data, double fraction);

struct SelectionOptions {
  int folds = 5;                  // K from kMinRowsForFiveFolds rows, and the rejection gate's
  int few_rows_folds = 10;        // K below that: min(rows, few_rows_folds)
  double central_fraction = 0.7;  // the out-of-range fold's first central fraction
  // The fold's training rows must be at least this share of the data: the central fraction widens
  // by 0.1 (at most to 0.95) until they are. Rows spread over every joint's range may leave none
  // inside 70 % of all six ranges at once (the worked example's first 300 UR10 rows: 0 at 0.7,
  // 18 at 0.8, 123 at 0.9), and a fold trained on a few rows judges only their noise.
  double min_inside_share = 0.25;
};

// The K select_model uses for `rows` rows (the rule above; at least 2).
int selection_folds(int rows, const SelectionOptions& options = {});

// The out-of-range fold's split (out_of_range_split at the first central fraction whose inside
// holds min_inside_share of the rows, see SelectionOptions).
RowSplit out_of_range_fold(const model::Dataset& data, const SelectionOptions& options);

// One model's scores above: identified from each fold's training rows by `options` (with
// options.rejection_gate off: the folds judge the rule as it is, identify.hpp), the K-fold RMS and,
// when there is an out-of-range fold and the model can be identified from its rows, the
// out-of-range RMS. What model selection scores each candidate by and identify's rejection gate
// compares. A model that cannot be identified on some K-fold training rows has no K-fold RMS
// (why says; out-of-range likewise).
struct CrossValidation {
  double kfold_rms_m = -1.0;         // < 0: not available
  double out_of_range_rms_m = -1.0;  // < 0: not available
  int parameters = 0;                // identified in the first fold's solve
  std::string why;                   // why a score is missing
  // Each held-out row's squared position error (m^2), in the same order for every model on the
  // same data (rows fold by fold; the out-of-range fold's rows): the pairs the gate compares; and
  // the data's row each belongs to.
  std::vector<double> kfold_error2, out_of_range_error2;
  std::vector<int> kfold_rows, out_of_range_rows;
  // A model with compliances: its gravity deflection at each K-fold held-out row (m^2, in
  // kfold_error2's order; empty for a rigid model) -- whether the rows see its physics.
  std::vector<double> kfold_deflection2;
};
CrossValidation cross_validate(const RobotModel& model, const model::Dataset& data, const IdentifyOptions& options,
                               const SelectionOptions& selection = {});
// How many of cross-validation's solves run at a time: the machine's hardware threads (at least 1).
unsigned parallel_solves();
// The same for several models (each candidate's model and options; names unused), in their order:
// every model's K + 1 solves run side by side on the machine's hardware threads, with the same
// results as one call each (the 8 candidates' 48 solves on 15,000 UR10 rows: minutes on one core).
std::vector<CrossValidation> cross_validate(const std::vector<Candidate>& models, const model::Dataset& data,
                                            const SelectionOptions& selection = {});

struct CandidateScore {
  std::string name;
  int parameters = 0;                // identified in the first fold's solve
  double kfold_rms_m = -1.0;         // < 0: not available (why says)
  double out_of_range_rms_m = -1.0;  // < 0: not available
  double score_m = -1.0;             // what the rule compares
  bool holds = false;                // Candidate::holds
  double t = 0.0;                    // paired t of its held-out errors against `against`'s (the rule)
  std::string against;               // what it was judged against: the default, or a candidate that holds
  std::string why;                   // why a score is missing
};

struct Selection {
  std::vector<CandidateScore> scores;  // in candidate_models' order
  Candidate chosen;
  // The chosen candidate's scores in full: with the default SelectionOptions, what identify's
  // rejection gate computes with the rule for it (identify(chosen.model, data, chosen.options,
  // chosen_cross_validation) saves those K + 1 solves).
  CrossValidation chosen_cross_validation;
  int folds = 0;               // K of the scores (selection_folds)
  bool leave_one_out = false;  // K is the number of rows
  int out_of_range_train_rows = 0, out_of_range_test_rows = 0;
  double out_of_range_fraction = 0.0;  // the central fraction of the out-of-range fold
  std::string reason;                  // the rule and the figures that decided
};

// The rule above over scored candidates (in candidate_models' order, with their cross-validations):
// the index of the chosen one, -1 when none has a score; records each judged candidate's t and
// against.
int choose_candidate(std::vector<CandidateScore>& scores, const std::vector<CrossValidation>& validations,
                     bool any_range);

// Scores every candidate and chooses (the rule above). Throws model::InputError when no
// candidate can be identified on the K-fold training rows.
Selection select_model(const RobotModel& nominal, const model::Dataset& data, const IdentifyOptions& base,
                       const SelectionOptions& options = {});

// The table and the choice, as `kincal identify` prints them.
std::string format_selection(const Selection& selection);

}  // namespace kincal::identify

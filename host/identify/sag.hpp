// Gravity sag for a model without masses (issue #41): model selection's geometry+sag candidate.
//
// A URDF without <inertial> gives the gravity deflection (model/robot_model.hpp: v_i +=
// compliance_i G_i(v)) nothing to act with. Here every link's mass and centre of mass become
// parameters beside every joint's compliance (mass<i>, com_x<i> .. com_z<i>, compliance<i>). G is
// linear in each link's mass and first moment, so only compliance x (mass, first moment) reaches
// the measurements: scaling every mass by s and every compliance by 1 / s changes nothing. The
// gauge is fixed explicitly: the compliance of the joint that sags most is held at its value
// from a first stage. Two stages, because at zero compliance the masses have no effect (their
// Jacobian columns are zero and identifiability would hold them all fixed):
//   1. every compliance identified with the masses held at a start that assumes nothing about the
//      robot: 1 kg per link at its frame's origin (kStartMass_kg);
//   2. from the nominal geometry again, with the compliances of stage 1: everything, masses and
//      centres of mass too, but the reference compliance (the largest sag at the data's poses)
//      held at its stage-1 value, and every geometric parameter stage 1 held fixed held again (the
//      masses' lever arms must not make d6 "separable" from the measured point's offset along the
//      last axis: it moved 180 mm on the zoo, the TCP with it). Identifiability
//      (identifiability.hpp) holds fixed what else the data cannot see (a vertical first axis's
//      load, a wrist's centre along its own axis, ...).
// Gravity's direction (robot_model.hpp's gravity_rx, gravity_ry) is held in stage 1 and
// identified in stage 2, for the same reason; the two stages serve geometry+gravity too (the
// model's own masses: no gauge, only the direction and the links' centres of mass, drawn toward
// the model's, wait for stage 1's compliances).
// Priors: the masses and centres of stage 2 are drawn toward the start (1 kg per link at its
// frame's origin, prior.hpp's widths, each class's scale chosen by the evidence: prior_scale.hpp),
// so that on a handful of rows the deflection keeps about stage 1's shape and only the data's
// evidence moves the masses -- a free mass and centre per link fitted the noise of 20 rows.
// A first axis that stands vertical at the start gives its compliance no load (unloaded_compliances
// holds it), but an arm off level, or a first joint tilted on its base, loads it by the tilt: its
// sag is compliance x tilt, and from a start with neither no solve can find it. When the found
// gravity loads such a joint, the stage runs again from there with that compliance free
// (tilted_sag_stage; the zoo's service arms with the first joint as compliant as the one that sags
// most: 5.54 and 3.90 x the oracle before, 1.11 and 1.00 after).
// Bounds: compliances never negative; the masses below. The result is an ordinary model with
// masses and compliances, which every command reads; the masses are in the gauge's units
// (kilograms only up to the common factor), as the report's group name says.
// Masses: across a revolute joint only the sum of the two links' masses reaches the loads -- a
// mass at a point of the joint's axis loads the joints before it alike on either link, and that
// joint and the ones after it not at all -- so identifiability holds all but one link's mass of
// such a run at the start's 1 kg, and the one left free carries the rest: when the data want less
// than the held masses already give, a free mass bounded at 0 could not follow (the zoo's SIA5D
// with a tracker, 100 rows: a link's mass at 0, 1.28 x the oracle's held-out error; free to go
// below 0, 1.005 x). So stage 2 solves with the masses free of sign; when one ends below 0, a
// third solve starts from the same loads with every run's mass spread evenly over its links
// (spread_masses_evenly) and keeps every mass at or above 0. Its priors are centred on its own
// start, the second's result spread, as every stage's are: so it stays with what the second found
// (the UR10's 300 real rows without its masses: 0.3987 mm held out; with the priors left centred
// on 1 kg at each frame's origin, which now means other loads, 0.4012, and 0.3993 bounded at 0).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "host/identify/identify.hpp"

namespace kincal::identify {

inline constexpr double kStartMass_kg = 1.0;

// The candidate's model: `nominal` (no masses, no compliance) with a compliance 0 on every joint,
// every link's mass (kStartMass_kg, centre at its frame's origin) and gravity's direction
// (robot_model.hpp's gravity_rx, gravity_ry) marked identified.
RobotModel with_identified_masses(const RobotModel& nominal);

// Stage 1 is due: some link's mass or gravity's direction is to be identified, no compliance is
// above 0 yet and the caller names no parameter list of its own.
bool needs_sag_start(const RobotModel& model, const IdentifyOptions& options);

// Stage 1's options: `options` with every identified mass and centre of mass, and gravity's
// direction, held fixed.
IdentifyOptions first_sag_stage(const RobotModel& model, const IdentifyOptions& options);

// Stage 2's start and options from stage 1's result: `model` with stage 1's compliances, the
// geometric parameters stage 1 held and (when masses are identified) the gauge's reference
// compliance added to the fixed parameters and the masses free of sign (third_sag_stage); a note
// says which. With no compliance above 0 after stage 1 (no sag seen), neither the masses, their
// centres nor gravity's direction are identified.
struct SagStage {
  RobotModel model;
  IdentifyOptions options;
  std::string note;
};
SagStage second_sag_stage(const RobotModel& model, const IdentifyOptions& options, const RobotModel& first,
                          const model::Dataset& data);

// Stage 3, when stage 2's result `solved` (from `second`, the masses free of sign) has a mass
// below 0: `second` with every link's mass and centre from spread_masses_evenly(solved.model),
// the gauge turned so that they average kStartMass_kg again (masses x f, every compliance / f:
// the same deflections, and the start's balance between the masses' and the centres' priors), the
// masses and centres stage 2 held held again, and every mass kept at or above 0; a note says so.
// When a run's masses sum to 0 or less, `second` with the masses kept at or above 0. None when no
// mass is below 0: stage 2's result stands.
std::optional<SagStage> third_sag_stage(const SagStage& second, const IdentifyResult& solved);

// Stage 2 (or 3) again, when gravity's direction as `solved` (from `stage`) found it loads a joint
// whose compliance the stage held because gravity barely loaded it at its start: a first axis
// that stands vertical in the file but tilted against gravity on the real arm (an arm off level, a
// first joint tilted on its base). Its sag is compliance x tilt, zero in both at the start, so no
// solve from there could find it; from the found direction the compliance acts and is identified
// beside everything else. `stage` with gravity as found (its prior centred there, as every
// stage's is on its start) and each freed compliance's prior the default deflection at the most
// loaded joint's load (of its kind), unless the caller names one: at its own load, the tilt's, a
// few percent of that, the default let 20-40 rows fit it to their noise. A note says which
// compliances are freed. None when no held compliance is loaded at the found direction.
std::optional<SagStage> tilted_sag_stage(const SagStage& stage, const IdentifyResult& solved,
                                         const model::Dataset& data);

// `model` with the same gravity loads in every pose and, over each run of links joined by revolute
// joints whose masses are identified, every link's mass the run's mean: mass moved across each
// joint at a point of its axis, with its first moment (see the top). None when a run's masses sum
// to 0 or less.
std::optional<RobotModel> spread_masses_evenly(const RobotModel& model);

// Each joint's largest |G_i| (robot_model.hpp's gravity_forces: N m, or N for a prismatic joint)
// over the data's poses, at the model's own masses.
std::vector<double> largest_gravity_loads(const RobotModel& model, const model::Dataset& data);

// What scales a compliance's default prior (prior.hpp): each joint's largest load and kind where
// the model identifies its masses (geometry+sag, whose compliances trade against the masses' first
// moments and ran free on a few dozen rows); none for a model with masses of its own, whose
// compliances the data see under known loads (on the UR10 with UR's masses the prior cost 0.6 %
// held out at 30 rows and tipped model selection on an extrapolation split to a worse candidate).
GravityLoads compliance_prior_loads(const RobotModel& model, const model::Dataset& data);

// A joint that gravity barely loads over the data -- its largest torque (a prismatic joint's force)
// at most kUnloadedShare of the most loaded joint's of its kind, at the model's own masses and
// gravity: a first axis standing vertical -- gives its compliance nothing to act with but the
// small tilt that loads it, and the fit trades one against the other (a Kinova Gen3's first axis,
// 7 urad off vertical in its URDF: a compliance of 1.86 rad/(N m), its standard deviation 1441,
// and the predicted spread at every target tens of millimetres). Each such compliance among
// `candidates`, with the reason identify prints for holding it fixed. The share: that axis's load
// was 7e-6 of the most loaded joint's, a wrist's on the zoo's arms and the UR10 0.2 % to 1 % (a
// compliance there is real, and 1 % held the UR10's wrist), an axis exactly vertical 1e-16.
inline constexpr double kUnloadedShare = 1e-4;
std::vector<HeldFixed> unloaded_compliances(const RobotModel& model, const model::Dataset& data,
                                            const ParameterIds& candidates);

// Stage 2's result `r` made a calibration of `nominal`'s arm (the stage-1 model's start):
//  - a compliance whose joint carries no mass (every mass after it identified as 0) cannot act and
//    model files refuse it: removed (the predictions do not change);
//  - the calibration record counts every compliance left from zero, the nominal's (stage 1's
//    values and the gauge's held one included), so that undoing the record (what `correct` and
//    `export` take the controller's model from) gives back an arm that does not sag rather than
//    one sagging by stage 1's compliances under the start's masses;
//  - the report's start, changes and prior centres count each compliance from `nominal`'s too
//    (from stage 1's, a compliance stage 2 took back to 0 was printed as a change of -87 urad/Nm).
void finish_sag_result(IdentifyResult& r, const RobotModel& nominal);

}  // namespace kincal::identify

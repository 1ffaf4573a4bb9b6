// The platform's correction parameter block (shared/parameters.hpp) built from two host models:
// what the CAN upload after a session (host/session/online_correction.hpp) sends and what the
// PC's correction (platform_step.hpp) reads with the platform's own code. Here, below both, so
// that correction on the PC needs no session.
//
// `controller` is the model the robot controller computes its targets with -- identify's
// starting model (IdentifyResult::start), which has the nominal geometry in the conventions the
// identification used (standard-DH pairs of nearly parallel axes become Doty links there) --
// and `identified` the calibrated one; both have the same joints and conventions. The block
// holds, per joint, the type, the convention, the controller's values (joint offsets folded into
// theta or d) and the differences identified - controller; the controller's tool and the tool's
// error as a small motion in the tool frame (t, r) with identified_tool = controller_tool *
// [exp(r), t] (the tool: each model's flange_T_tool, the point or frame the block corrects). The
// base is not in the block: the controller works in the robot's own base frame, and the base
// registration belongs to the measuring device, not to the arm. The joint map (block format 3):
// each joint's coupling row, the controller's scale and compliance (absent: 1 and 0) and
// identified - controller, the link masses and centres of mass, payload and gravity; coupling,
// payload and gravity must be the same in both models (an identified coupling has no place in the
// block), and the masses too unless the controller's model has no compliance (then the identified
// masses, geometry+sag's, go in: the controller's act on nothing).
//
// Errors: model::InputError when the models do not match (joint count, type, convention), have
// more joints than the protocol carries (shared::kJoints), or a value does not fit a float.
#pragma once

#include "host/model/robot_model.hpp"
#include "shared/parameters.hpp"

namespace kincal::correct {

shared::CorrectionParameters correction_block(const model::RobotModel& controller, const model::RobotModel& identified);

}  // namespace kincal::correct

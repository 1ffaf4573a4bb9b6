// The online correction after a calibration (issue #6): the platform's correction parameter
// block built from the identified model, its upload, and the proof that it works -- the
// validation poses measured again at the corrected joint targets the platform streams back
// (firmware/app/kinematic_correction.hpp reads the block as two chains and corrects each target).
//
// correction_block():
// `controller` is the model the robot controller computes its targets with -- identify's
// starting model (IdentifyResult::start), which has the nominal geometry in the conventions the
// identification used (standard-DH pairs of nearly parallel axes become Doty links there) --
// and `identified` the calibrated one; both have the same joints and conventions. The block
// holds, per joint, the type, the convention, the controller's values (joint offsets folded into
// theta or d) and the differences identified - controller; the controller's tool and the tool's
// error as a small motion in the tool frame (t, r) with identified_tool = controller_tool *
// [exp(r), t]. The base is not in the block: the controller works in the robot's own base frame,
// and the base registration belongs to the measuring device, not to the arm. The joint map
// (block format 3): each joint's coupling row, the controller's scale and compliance (absent: 1
// and 0) and identified - controller, the link masses and centres of mass, payload and gravity;
// coupling, masses, payload and gravity must be the same in both models (inputs, not identified).
//
// Errors: model::InputError when the models do not match (joint count, type, convention), have
// more joints than the protocol carries (shared::kJoints), or a value does not fit a float.
//
// verify_online_correction(): uploads the block, reads it back (the platform's CRC and version
// checked, then byte for byte), and for every validation target q_nom asks the platform for the
// corrected target q_corr over the joint stream, moves the robot there and measures. The goal of
// a target is where the controller's model puts the tool, placed with the identified base
// registration (the block corrects the arm, not the device-to-base registration): before = the
// errors at q_nom (from the session's validation data), after = the errors at q_corr. Throws
// SessionError (driver, sensor, platform refusing or answering wrongly).
#pragma once

#include <iosfwd>

#include "host/can/platform_client.hpp"
#include "host/model/robot_model.hpp"
#include "host/session/session.hpp"
#include "shared/parameters.hpp"

namespace kincal::session {

shared::CorrectionParameters correction_block(const model::RobotModel& controller, const model::RobotModel& identified);

struct CorrectionCheck {
  identify::AccuracyStats before, after;  // position (and orientation) errors w.r.t. the goals
  std::uint32_t storage_sequence = 0;     // the stored copy's sequence number on the platform
};

CorrectionCheck verify_online_correction(can::PlatformClient& client, bool fd, const Calibration& calibration,
                                         const SessionData& data, RobotDriver& driver, Sensor& sensor,
                                         std::ostream& log);

}  // namespace kincal::session

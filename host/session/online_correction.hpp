// The online correction after a calibration (issue #6): the platform's correction parameter
// block built from the identified model, its upload, and the proof that it works -- the
// validation poses measured again at the corrected joint targets the platform streams back
// (firmware/app/kinematic_correction.hpp reads the block as two chains and corrects each target).
//
// The block itself is built by correct::correction_block (host/correct/correction_block.hpp), which
// the PC's correction shares.
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

struct CorrectionCheck {
  identify::AccuracyStats before, after;  // position (and orientation) errors w.r.t. the goals
  std::uint32_t storage_sequence = 0;     // the stored copy's sequence number on the platform
};

CorrectionCheck verify_online_correction(can::PlatformClient& client, bool fd, const Calibration& calibration,
                                         const SessionData& data, RobotDriver& driver, Sensor& sensor,
                                         std::ostream& log);

}  // namespace kincal::session

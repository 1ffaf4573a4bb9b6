// The measured point first (issue #42): a stage of identify() that estimates the point or frame
// the data measured -- a tracker's reflector, a mocap marker, a board: 50-150 mm off the flange,
// often off the last axis, known to a few millimetres at best -- before anything is decided.
//
// Why first: which parameters a dataset can identify depends on where the measured point is. At
// a nominal tool on the last axis (a URDF's flange), the last axes' tilt and offset (a6, alpha6 of
// a 7-joint arm) move the point by a constant in the last body and are held fixed; a reflector
// 57 mm off that axis sees them. Deciding at the nominal tool threw away what the data measured
// (held-out 0.050 mm where the noise allowed 0.009 on such an arm).
//
// Method: the registration and the measured point alone (base_* and tool_x, tool_y, tool_z, with
// tool_rx..tool_rz when the data carry orientations of a frame tool) fitted at the start's
// geometry by identify() itself -- plain least squares (no prior: the point is unknown, not 10 mm
// from the flange), no rejection, the noise model's own passes. The start's base and tool are
// replaced by the fit; identifiability, the priors (centred there: the measured point's loose
// prior is about the estimate, not about the flange) and the solve then start from it.
//
// Runs when options.estimate_measured_point is set, the method is full or first-order, the tool's
// position is free (not fixed, and requested when parameters are requested) and a link or joint
// map parameter is among the requested ones (without one, nothing is decided: the fit is the
// solve). A fit the data cannot make (too few rows, a joint never moved) leaves the start as it is
// and says so in `notes`. Cost: one identify() of 6 to 12 parameters.
#pragma once

#include <string>
#include <vector>

#include "host/identify/identify.hpp"

namespace kincal::identify {

// The start with its base and tool at the estimate (see the top); `notes` gets one line.
RobotModel with_estimated_measured_point(const RobotModel& start, const model::Dataset& data,
                                         const IdentifyOptions& options, bool orientation_used,
                                         std::vector<std::string>& notes);

}  // namespace kincal::identify

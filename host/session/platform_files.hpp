// The integrator's files for a real sensor platform (issue #13): the camera block and the
// geometry block (shared/parameters.hpp) read from camera.yaml and platform.yaml, checked as the
// platform would check them. platform_setup.hpp loads them into the platform.
//
// camera.yaml: what `kincal camera calibrate` writes (OpenCV or ROS camera_info YAML), read by
// camera::load_camera and converted by camera::to_platform (calibration_file.hpp).
//
// platform.yaml: the platform's geometry. Frames and units: the camera frame as OpenCV's (x
// right, y down, z forward along the optical axis, origin at the projection centre), metres.
//   rangers:              exactly four, in the order of the platform's range inputs, each
//     - origin_m:  [x, y, z]   where the beam leaves the sensor
//       direction: [x, y, z]   the beam's direction; normalized on load (any non-zero length)
//   fiducial_side_m: 0.00635   optional, default Doty's 1/4 inch: the side s of the calibration
//                              square's small fiducials, from which Doty's six fiducial
//                              positions follow (host/target/doty_square.hpp)
//   square_pitch_m: 0.1016     optional, default Doty's 4 inch: centre-to-centre distance of
//                              the strip's neighbouring squares; 0 = one square per frame
// What the platform's measurement needs is checked here by the platform's own test
// (app::prepare_ranger_plane, firmware/app/platform_measurement.hpp), because the platform would
// take such a block and then answer kNoParameters: every beam's direction (normalized, float)
// within 1e-3 of +z in x and y and pointing forward (the beams parallel to the optical axis),
// every origin's z within 0.1 mm of the first ranger's, no three origins on one line in (x, y).
// square_pitch_m is 0 or within [shared::kMinSquarePitchM, shared::kMaxSquarePitchM], and above
// 15 s (the squares' fiducials would overlap).
//
//
// Errors: PlatformSetupError, its message naming the file and, for a bad value, the line and the
// key ("platform.yaml:4: rangers[1].direction: ..."): a missing file, a path that is not a regular
// file or is over files::kSettingsFile.max_bytes, text that is not UTF-8 (files/input_file.hpp),
// YAML that does not parse (with line:column) or that files::check_yaml_text refuses (too many
// nodes, a key given twice, a second document, nested too deep), a top that is not a map, an unknown or missing
// key, a value that is not a number, not finite or out of range; for a camera file the loader's
// and to_platform's messages behind the file's name.
// Cost: reading a file. Fuzzed by fuzz.camera_inputs (tests/fuzz/camera_inputs_fuzz.cpp).
#pragma once

#include <stdexcept>
#include <string>

#include "shared/parameters.hpp"

namespace kincal::session {

class PlatformSetupError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

shared::CameraIntrinsics read_camera_block(const std::string& camera_yaml);
shared::PlatformGeometry read_geometry_block(const std::string& platform_yaml);

}  // namespace kincal::session

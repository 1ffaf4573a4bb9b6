// Setting up a real sensor platform (issue #13): the camera block and the geometry block
// (shared/parameters.hpp) from the integrator's files, loaded into the platform and read back.
// Without both blocks the platform answers every pose measurement with kNoParameters; only the
// simulator built them so far. `kincal platform load` and `kincal platform show` use this.
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
// Errors: PlatformSetupError, its message naming the file and, for a bad value, the line and the
// key ("platform.yaml:4: rangers[1].direction: ..."): a missing file, a path that is not a regular
// file or is over files::kSettingsFile.max_bytes, text that is not UTF-8 (files/input_file.hpp),
// YAML that does not parse (with line:column),
// an unknown or missing key, a value that is not a number, not finite or out of range; for a
// camera file the loader's and to_platform's messages behind the file's name. load_block also
// throws PlatformSetupError when the block read back differs from the one uploaded, and passes on
// the client's can::PlatformError (the platform's refusal, e.g. kNotIdle while it measures or
// corrects, or no answer) and can::CanError.
// Cost: reading a file; load_block is two ISO-TP transfers, each waiting at most the client's
// timeout (3 s). Thread safety: as the client's (one thread per client).
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

#include "host/can/platform_client.hpp"
#include "shared/parameters.hpp"

namespace kincal::session {

class PlatformSetupError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

shared::CameraIntrinsics read_camera_block(const std::string& camera_yaml);
shared::PlatformGeometry read_geometry_block(const std::string& platform_yaml);

// Uploads the block (can::PlatformClient::upload), downloads it and compares the images byte for
// byte; returns the platform's storage sequence number of the stored copy.
std::uint32_t load_block(can::PlatformClient& client, const shared::CameraIntrinsics& camera);
std::uint32_t load_block(can::PlatformClient& client, const shared::PlatformGeometry& geometry);

// The block as a person reads it, several lines each ending in '\n'.
std::string describe(const shared::CameraIntrinsics& camera);
std::string describe(const shared::PlatformGeometry& geometry);

// What `kincal platform show` prints: the platform's camera and geometry blocks downloaded and
// described, or for each block it does not hold (or that does not decode), a line saying so and
// why ("camera: not loaded (...)"). complete: both blocks were there. Throws can::CanError, and
// can::PlatformError when no heartbeat comes within 1 s or it is of another protocol version.
struct PlatformBlocks {
  std::string text;
  bool complete = false;
};
PlatformBlocks read_platform_blocks(can::PlatformClient& client);

}  // namespace kincal::session

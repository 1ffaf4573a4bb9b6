// Setting up a real sensor platform (issue #13): the camera block and the geometry block
// (shared/parameters.hpp) from the integrator's files, loaded into the platform and read back.
// Without both blocks the platform answers every pose measurement with kNoParameters; only the
// simulator built them so far. `kincal platform load` and `kincal platform show` use this.
//
// The files: platform_files.hpp.
//
// Errors: PlatformSetupError (platform_files.hpp) when the block read back differs from the one
// uploaded; load_block passes on the client's can::PlatformError (the platform's refusal, e.g.
// kNotIdle while it measures or corrects, or no answer) and can::CanError.
// Cost: load_block is two ISO-TP transfers, each waiting at most the client's timeout (3 s).
// Thread safety: as the client's (one thread per client).
#pragma once

#include <cstdint>
#include <string>

#include "host/can/platform_client.hpp"
#include "host/session/platform_files.hpp"
#include "shared/parameters.hpp"

namespace kincal::session {
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

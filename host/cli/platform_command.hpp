// `kincal platform`: sets up a real sensor platform over SocketCAN (issue #13).
//   kincal platform load --can IF [--fd] [--camera camera.yaml] [--geometry platform.yaml]
//     reads the files (host/session/platform_files.hpp: formats and checks), uploads each block,
//     reads it back and compares it byte for byte, prints what was loaded and the storage
//     sequence. Files are read before the bus is opened, so a bad file never half-loads a platform.
//   kincal platform show --can IF [--fd]
//     downloads the camera and geometry blocks and prints them decoded, or which is missing.
// Exit 0, or 1 with a message naming the file, line and key, or the platform's refusal.
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

void add_platform_command(CLI::App& app, int& status);

}  // namespace kincal::cli

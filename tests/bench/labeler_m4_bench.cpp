// Instructions per pixel of the streaming labeler on the Cortex-M4 (QEMU, -icount shift=0), on
// 640x480 calibration-square frames, and the labeler's RAM for 640-pixel rows.
//
// The frames: light vellum (200 DN, +-4 DN texture) with Doty's six dark fiducials at 120 px
// per inch (30x30 px, the centre one 60x30, 210 px apart), edges blurred over one pixel, plus
// three bright spots the labeler does not select (dark polarity). Each row is written into
// BlobLabeler::row_buffer() outside the timed region — on the platform the camera's DMA does
// that — and commit_row() is timed. A second figure times push_row(), which copies the row.
#include <cstdint>
#include <cstdio>
#include <cstring>

#include "firmware/core/blob_labeler.hpp"
#include "tests/bench/m4_instruction_counter.hpp"

using namespace kincal::core;

namespace {

constexpr int kWidth = 640, kHeight = 480;
VgaLabelerBuffers g_buffers;
Blob g_blobs[64];
std::uint8_t g_row[kWidth];

struct Square {
  int x0, y0, x1, y1;  // inclusive
};

// One row of a calibration square centred at (cx, cy): fiducials p1..p6 of Doty's square.
void render_row(int y, int cx, int cy, std::uint8_t* row) {
  const int s = 30, d = 210;  // fiducial side and centre-to-perimeter distance, px
  const Square fiducials[6] = {
      {cx - d - s / 2, cy - d - s / 2, cx - d + s / 2 - 1, cy - d + s / 2 - 1},  // corner marker
      {cx - s / 2, cy - d - s / 2, cx + s / 2 - 1, cy - d + s / 2 - 1},          // top
      {cx - d - s / 2, cy - s / 2, cx - d + s / 2 - 1, cy + s / 2 - 1},          // left
      {cx - s / 2, cy - s, cx + s / 2 - 1, cy + s - 1},                          // centre, 30 x 60
      {cx + d - s / 2, cy - s / 2, cx + d + s / 2 - 1, cy + s / 2 - 1},          // right
      {cx - s / 2, cy + d - s / 2, cx + s / 2 - 1, cy + d + s / 2 - 1},          // bottom
  };
  std::uint32_t hash = static_cast<std::uint32_t>(y) * 2654435761u;
  for (int x = 0; x < kWidth; ++x) {
    hash = hash * 1664525u + 1013904223u;
    int v = 200 + static_cast<int>(hash >> 29) - 4;
    for (const Square& f : fiducials) {
      if (x >= f.x0 && x <= f.x1 && y >= f.y0 && y <= f.y1)
        v = 40;
      else if (x >= f.x0 - 1 && x <= f.x1 + 1 && y >= f.y0 - 1 && y <= f.y1 + 1)
        v = 120;  // blurred rim
    }
    row[x] = static_cast<std::uint8_t>(v);
  }
}

struct Result {
  double instructions_per_pixel;
  std::uint32_t blobs;
};

Result run(kincal::bench::M4InstructionCounter& counter, bool copy, int frames) {
  BlobLabeler labeler(g_buffers.memory());
  LabelerConfig config;
  config.polarity = Polarity::kDark;
  config.threshold = 128;
  std::uint64_t instructions = 0;
  std::uint32_t blobs = 0;
  for (int frame = 0; frame < frames; ++frame) {
    const int cx = 300 + 13 * frame, cy = 230 + 7 * frame;
    if (labeler.begin_frame(config, g_blobs) != LabelStatus::kOk) return {-1, 0};
    for (int y = 0; y < kHeight; ++y) {
      LabelStatus status;
      if (copy) {
        render_row(y, cx, cy, g_row);
        counter.start();
        status = labeler.push_row(g_row);
      } else {
        render_row(y, cx, cy, labeler.row_buffer().data());
        counter.start();
        status = labeler.commit_row(kWidth);
      }
      instructions += counter.stop_instructions();
      if (status != LabelStatus::kOk) return {-1, 0};
    }
    FrameSummary summary;
    counter.start();
    if (labeler.end_frame(summary) != LabelStatus::kOk) return {-1, 0};
    instructions += counter.stop_instructions();
    blobs += summary.blobs;
  }
  return {static_cast<double>(instructions) / (static_cast<double>(kWidth) * kHeight * frames), blobs};
}

}  // namespace

int main() {
  kincal::bench::M4InstructionCounter counter;
  constexpr int kFrames = 3;
  const Result zero_copy = run(counter, false, kFrames);
  const Result copied = run(counter, true, kFrames);
  std::printf("frames %d, blobs found %u (expected %d)\n", kFrames, static_cast<unsigned>(zero_copy.blobs),
              6 * kFrames);
  std::printf("FIGURE labeler_m4_instructions_per_pixel %.2f instructions\n", zero_copy.instructions_per_pixel);
  std::printf("FIGURE labeler_m4_instructions_per_pixel_push_row %.2f instructions\n", copied.instructions_per_pixel);
  std::printf("FIGURE labeler_ram_bytes_vga %u bytes\n", static_cast<unsigned>(sizeof(VgaLabelerBuffers)));
  std::printf("FIGURE blob_record_bytes %u bytes\n", static_cast<unsigned>(sizeof(Blob)));
  return zero_copy.blobs == 6 * kFrames && copied.blobs == 6 * kFrames ? 0 : 1;
}

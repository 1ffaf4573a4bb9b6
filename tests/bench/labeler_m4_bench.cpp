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
#include "tests/bench/vga_square_frame.hpp"

using namespace kincal::core;

namespace {

constexpr int kWidth = kincal::bench::kVgaWidth, kHeight = kincal::bench::kVgaHeight;
VgaLabelerBuffers g_buffers;
Blob g_blobs[64];
std::uint8_t g_row[kWidth];

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
        kincal::bench::render_vga_square_row(y, cx, cy, g_row);
        counter.start();
        status = labeler.push_row(g_row);
      } else {
        kincal::bench::render_vga_square_row(y, cx, cy, labeler.row_buffer().data());
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

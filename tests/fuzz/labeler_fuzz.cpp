// libFuzzer target: random rows, widths, thresholds and capacities into the streaming labeler
// (and its blobs into the FID), under ASan + UBSan. Beyond "no finding", each frame is checked
// against a flood fill of the same pixels: with no capacity overflow the labeler must report
// exactly the flood fill's components (areas, boxes, first pixels); with overflow, no blob may
// claim more pixels than exist, and every blob's centroid must lie in its bounding box.
//
// Input layout: byte 0 width-1 (mod 48) and capacity choice, byte 1 threshold, byte 2 flags
// (polarity, connectivity, refine, a width change mid-frame), byte 3 guard and window; the
// rest are pixels, row after row.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "firmware/core/blob_labeler.hpp"
#include "firmware/core/fiducial_id.hpp"

using namespace kincal::core;

namespace {

constexpr int kMaxWidth = 48;

struct Reference {
  int count = 0;
  std::int64_t foreground = 0;
  std::vector<int> area, first_x, first_y;
};

Reference flood_fill(const std::vector<std::uint8_t>& img, int width, int height, bool (*fg)(std::uint8_t, int, bool),
                     int t, bool bright, bool eight) {
  Reference r;
  std::vector<int> label(img.size(), -1), stack;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const auto at = static_cast<std::size_t>(y * width + x);
      if (!fg(img[at], t, bright)) continue;
      ++r.foreground;
      if (label[at] >= 0) continue;
      int area = 0;
      label[at] = r.count;
      stack.push_back(y * width + x);
      while (!stack.empty()) {
        const int p = stack.back();
        stack.pop_back();
        ++area;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            if ((dx == 0 && dy == 0) || (!eight && dx != 0 && dy != 0)) continue;
            const int nx = p % width + dx, ny = p / width + dy;
            if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
            const auto n = static_cast<std::size_t>(ny * width + nx);
            if (label[n] >= 0 || !fg(img[n], t, bright)) continue;
            label[n] = r.count;
            stack.push_back(ny * width + nx);
          }
      }
      r.area.push_back(area);
      r.first_x.push_back(x);
      r.first_y.push_back(y);
      ++r.count;
    }
  return r;
}

bool is_fg(std::uint8_t p, int t, bool bright) { return bright ? p > t : p < t; }

template <class Buffers>
void run(const std::uint8_t* data, std::size_t size) {
  static Buffers buffers;
  static Blob blobs[64];
  static FidVerdict verdicts[64];
  const int width = 1 + data[0] % kMaxWidth;
  LabelerConfig config;
  config.threshold = data[1];
  config.polarity = (data[2] & 1) != 0 ? Polarity::kDark : Polarity::kBright;
  config.connectivity = (data[2] & 2) != 0 ? Connectivity::kFour : Connectivity::kEight;
  config.refine = (data[2] & 4) != 0;
  const bool change_width = (data[2] & 8) != 0;
  config.background_guard_px = static_cast<std::uint8_t>(data[3] & 7);  // 0 is refused: bad config
  config.refine_half_window_px = static_cast<std::uint8_t>(2 + ((data[3] >> 3) & 7));
  config.refine_max_extent_px = static_cast<std::uint16_t>(1 + (data[3] >> 6) * 2 * config.refine_half_window_px / 3);
  data += 4;
  size -= 4;
  const int height = static_cast<int>(size / static_cast<std::size_t>(width));
  const std::vector<std::uint8_t> img(data, data + static_cast<std::size_t>(height * width));

  BlobLabeler labeler(buffers.memory());
  if (labeler.begin_frame(config, blobs) != LabelStatus::kOk) return;  // a refused configuration
  int rows = 0;  // rows labeled: a wider row at the end of the data is not pushed
  for (int y = 0; y < height; ++y) {
    const int w = change_width && y > 0 && y == height / 2 ? width + 1 : width;
    if (y * width + w > static_cast<int>(size)) break;
    const auto row = std::span<const std::uint8_t>(data + y * width, static_cast<std::size_t>(w));
    if (labeler.push_row(row) != LabelStatus::kOk) {
      if (w == width && width <= static_cast<int>(buffers.memory().max_width_px)) __builtin_trap();
      return;  // wider than the workspace or than the frame: refused, as specified
    }
    ++rows;
  }
  FrameSummary summary;
  if (labeler.end_frame(summary) != LabelStatus::kOk) __builtin_trap();

  const bool bright = config.polarity == Polarity::kBright;
  const Reference ref =
      flood_fill(img, width, rows, is_fg, config.threshold, bright, config.connectivity == Connectivity::kEight);
  std::int64_t claimed = 0;
  for (std::uint32_t i = 0; i < summary.blobs; ++i) {
    const Blob& b = blobs[i];
    claimed += b.area_px;
    if (b.x_max_px >= width || b.y_max_px >= rows || b.x_min_px > b.x_max_px || b.y_min_px > b.y_max_px) {
      __builtin_trap();
    }
    const double bx = b.binary_x_px.to_double(), by = b.binary_y_px.to_double();
    if (bx < b.x_min_px || bx > b.x_max_px || by < b.y_min_px || by > b.y_max_px) __builtin_trap();
  }
  if (claimed > ref.foreground) __builtin_trap();
  const bool lossless = summary.runs_untracked == 0 && summary.blobs_dropped_output_full == 0;
  if (lossless) {
    if (static_cast<int>(summary.blobs) != ref.count) __builtin_trap();
    for (int k = 0; k < ref.count; ++k) {
      bool found = false;
      for (std::uint32_t i = 0; i < summary.blobs && !found; ++i) {
        found = blobs[i].first_x_px == ref.first_x[static_cast<std::size_t>(k)] &&
                blobs[i].y_min_px == ref.first_y[static_cast<std::size_t>(k)] &&
                static_cast<int>(blobs[i].area_px) == ref.area[static_cast<std::size_t>(k)] &&
                (blobs[i].flags & kIncomplete) == 0;
      }
      if (!found) __builtin_trap();
    }
  }
  FidResult fid;
  (void)identify_fiducials(FidModel{}, std::span<const Blob>(blobs, summary.blobs), verdicts, fid);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 5) return 0;
  switch (data[0] / kMaxWidth % 4) {
    case 0:
      run<LabelerBuffers<kMaxWidth, 1, 1, 1>>(data, size);
      break;
    case 1:
      run<LabelerBuffers<kMaxWidth, 3, 5, 1>>(data, size);
      break;
    case 2:
      run<LabelerBuffers<kMaxWidth, 8, 13, 2>>(data, size);
      break;
    default:
      run<LabelerBuffers<kMaxWidth / 2, 64, 17, 8>>(data, size);  // rows up to 48: some too wide
      break;
  }
  return 0;
}

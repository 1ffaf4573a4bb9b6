// Streaming blob labeler: connected components of one camera frame, seen once, row by row,
// with sub-pixel centroids — the first stage of both calibration modes (Doty's fiducials,
// Kapucu & Baysec's beacon).
//
// What it does
//   Each pushed row (8-bit intensities; pixel_formats.hpp turns RGB565 and YUV422 rows into
//   luma rows, colour_class.hpp into colour-class scores) is cut into runs of foreground pixels, which are joined to
//   the runs of the previous row (8- or 4-connectivity, union-find over open components).
//   A component that no run of the current row continues is complete: it is finalized into a
//   Blob in the caller's output span at once. Nothing of the frame is stored but the last row's
//   runs, the open components and (for the refinement below) a ring of the last few rows.
//
//   Foreground: kBright means I > threshold, kDark means I < threshold.
//
// What each Blob carries (pixel (0, 0) is the centre of the top-left pixel; y grows downward)
//   area_px, bounding box, first pixel (raster order), border-touch flag;
//   binary centroid: the mean of the pixel coordinates (what OpenCV's
//     connectedComponentsWithStats reports, to the last bit of q16_16 rounding);
//   weighted centroid: intensity-weighted relative to the blob's local background b, with
//     weight (I - b) for bright and (b - I) for dark blobs. b is the mean of the background
//     pixels background_guard_px left of each run start and right of each run end (the
//     threshold when there are none). Subtracting b removes the pull of the flat pedestal
//     toward the middle of the thresholded region;
//   weighted second central moments mu20, mu11, mu02 (px^2): orientation and elongation;
//   refined centroid (kRefined): for spot-like blobs (bounding box at most
//     refine_max_extent_px), an iteratively Gaussian-weighted centroid over a
//     (2h+1)^2 window of the retained rows (h = refine_half_window_px), background from the
//     window's border, the Gaussian's width re-estimated each step (adaptive moments). At the
//     fixed point it is the Gaussian least-squares centre, whose variance for a Gaussian spot
//     in white noise is the Cramér–Rao bound to first order (DESIGN.md: thresholded centre of
//     mass ~3x, background-subtracted weighting 1.2-1.7x). Measured (tests/bench/
//     centroid_accuracy_bench.cpp, sigma 1-2 px, peak SNR 10-80): RMS error 1.01x the bound,
//     |bias| < 0.01 px; the first-pass weighted centroid is up to 6x (its truncation bias
//     dominates at high SNR). Its window needs rows up to cy + h, so it completes h rows after
//     the blob's centre, still in the same single pass.
//   x_px, y_px: the best of these: refined if kRefined, else weighted (binary if the weights
//     summed to <= 0: kWeightInvalid).
//
// Arithmetic: integers only in the pixel path (sums in 32/64 bits, exact); each ratio is
//   rounded once to q16_16 (centroids) or q24_8 (moments), ties away from zero. The same bits
//   natively and on the Cortex-M4 (tests/firmware/core/blob_labeler_test.cpp pins a digest).
//
// Memory (all caller-owned, sized at compile time by LabelerBuffers<>; no heap, no globals)
//   runs          2 x (max_width/2 + 1) x 6 bytes
//   components    kMaxOpen x sizeof(OpenComponent) (112 bytes): open at the same time
//   ring          kRingRows x max_width bytes: the retained rows (at least 1: the row buffer)
//   pending       kMaxPending refinements waiting for their window's last row
//   weights       68 bytes of Gaussian window weights (the refinement's scratch, off the stack)
//   LabelerBuffers<640, 32, 13, 8> — the VGA configuration — is labeler_ram_bytes_vga.
//
// Cost: background pixels are tested four at a time in a 32-bit word (one UQSUB8 on the M4, a
//   carry-save compare elsewhere), eight per loop; foreground pixels go one by one (three
//   sums); each run costs a union-find step, each closed blob a few 64-bit divisions, each
//   refinement up to 16 passes over its window. Measured on the M4 (tests/bench/
//   labeler_m4_bench.cpp, QEMU -icount): 2.8 instructions per pixel on 640x480
//   calibration-square frames through row_buffer()/commit_row(), 3.4 through push_row() (which
//   copies the row into the ring). No per-frame pass over the capacities.
//
// Failure modes — all defined, all reported, none corrupts memory or returns a silently wrong
// centroid:
//   * more simultaneously open components than kMaxOpen: the runs that find no slot are not
//     tracked; a tracked blob that touches an untracked run gets kIncomplete; the frame
//     summary counts untracked runs;
//   * output span full: further blobs are dropped and counted (blobs_dropped_output_full);
//   * pending-refinement queue full, window clipped by the frame or rows already overwritten:
//     the blob keeps its weighted centroid (no kRefined) and the summary counts it;
//   * a row wider than the workspace, a row of another width than the frame's first, more
//     than kMaxRows rows, a call out of order: a LabelStatus error; the frame is then failed
//     and further rows are refused until begin_frame.
//   * sums cannot overflow: width and height are limited to 4096 (static_assert / kTooManyRows).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "firmware/core/fixed_point.hpp"

namespace kincal::core {

enum class [[nodiscard]] LabelStatus : std::uint8_t{
    kOk,
    kBadWorkspace,     // memory spans inconsistent with each other (a programming error)
    kBadConfig,        // refinement window too large for the ring or smaller than its blobs, guard 0
    kNotInFrame,       // push/end without begin_frame, or after the frame failed
    kRowTooWide,       // row wider than the workspace's max_width
    kRowWidthChanged,  // every row of a frame must have the width of its first row
    kEmptyRow,         // width 0
    kTooManyRows,      // more than kMaxRows rows in one frame
};

enum class Polarity : std::uint8_t { kBright, kDark };
enum class Connectivity : std::uint8_t { kEight, kFour };

struct LabelerConfig {
  Polarity polarity = Polarity::kBright;
  std::uint8_t threshold = 128;  // foreground: I > threshold (bright), I < threshold (dark)
  Connectivity connectivity = Connectivity::kEight;
  std::uint8_t background_guard_px = 3;    // distance of the local-background samples from a run
  std::uint32_t min_area_px = 1;           // smaller components are dropped (and counted)
  bool refine = true;                      // the Gaussian-window refinement of spot-like blobs
  std::uint8_t refine_half_window_px = 6;  // h: window (2h+1)^2, needs ring rows >= 2h+1
  std::uint16_t refine_max_extent_px = 9;  // refine blobs whose bounding box fits this square (<= 2h+1)
};

// Blob::flags bits.
inline constexpr std::uint8_t kTouchesBorder = 1u << 0;      // a pixel on the frame's edge
inline constexpr std::uint8_t kIncomplete = 1u << 1;         // joined an untracked run: pixels missing
inline constexpr std::uint8_t kRefined = 1u << 2;            // x_px, y_px are the refined centroid
inline constexpr std::uint8_t kWeightInvalid = 1u << 3;      // weights summed to <= 0: binary centroid used
inline constexpr std::uint8_t kBackgroundDefault = 1u << 4;  // no guard samples: background = threshold

struct Blob {
  q16_16 x_px, y_px;                    // best centroid (see header comment)
  q16_16 weighted_x_px, weighted_y_px;  // background-relative intensity-weighted centroid
  q16_16 binary_x_px, binary_y_px;      // mean pixel coordinate
  q24_8 mu20_px2, mu11_px2, mu02_px2;   // weighted central second moments
  std::uint32_t area_px = 0;
  std::uint32_t weight_sum_dn = 0;  // sum of the weights, DN (saturated)
  uq8_8 background_dn;              // local background level
  std::uint16_t x_min_px = 0, x_max_px = 0, y_min_px = 0, y_max_px = 0;
  std::uint16_t first_x_px = 0;  // leftmost pixel of the top row: raster-order key
  std::uint8_t flags = 0;
};

struct FrameSummary {
  std::uint32_t blobs = 0;  // written to the output span
  std::uint32_t blobs_dropped_output_full = 0;
  std::uint32_t blobs_dropped_small = 0;  // below min_area_px
  std::uint32_t runs_untracked = 0;       // found no free component slot
  std::uint32_t refinements = 0;          // blobs refined
  std::uint32_t refinements_skipped = 0;  // eligible, but queue full / window clipped / lost rows / diverged
  std::uint16_t width_px = 0, rows = 0;
};

// ---- Workspace ---------------------------------------------------------------------------
// The parts below are the labeler's state; callers only allocate them (LabelerBuffers) and
// pass them in. Their layout is not an interface.

struct LabelRun {
  std::uint16_t x_begin, x_end;  // inclusive
  std::uint16_t slot;            // component slot, kUntrackedSlot when none was free
};

struct OpenComponent {
  // Exact integer moments of the binary mask (b*) and of the intensity (t*), absolute coordinates.
  std::uint32_t n;
  std::uint64_t bx, by, bxx, bxy, byy;
  std::uint32_t t0;
  std::uint64_t tx, ty, txx, txy, tyy;
  std::uint32_t background_sum_dn, background_count;
  std::uint16_t x_min, x_max, y_min, y_max, first_x;
  std::uint16_t parent;    // union-find: itself when a root
  std::uint16_t last_row;  // the last row a run joined it: open while it is the previous row
  std::uint8_t flags;
};

struct PendingRefinement {
  std::uint32_t blob_index;
  std::int16_t centre_x, centre_y;  // window centre (integer pixel)
  std::uint16_t sigma2_q8;          // first-guess Gaussian variance, px^2 in q8
};

struct LabelerMemory {
  std::span<LabelRun> runs_a, runs_b;  // each >= max_width/2 + 1
  std::span<OpenComponent> components;
  std::span<std::uint16_t> free_slots, merged_slots;  // each == components.size()
  std::span<std::uint8_t> ring;                       // ring_rows x max_width
  std::span<PendingRefinement> pending;
  std::span<std::uint16_t> window_weights;  // kWindowWeights: the refinement's scratch
  std::uint16_t max_width_px = 0;
  std::uint16_t ring_rows = 0;
};

inline constexpr int kLabelerMaxRows = 4096;
inline constexpr int kMaxRefineHalfWindow_px = 8;
inline constexpr std::size_t kWindowWeights = 2 * (2 * kMaxRefineHalfWindow_px + 1);
inline constexpr std::uint16_t kUntrackedSlot = 0xFFFFu;

template <std::size_t kMaxWidth_px, std::size_t kMaxOpen, std::size_t kRingRows, std::size_t kMaxPending>
struct LabelerBuffers {
  static_assert(kMaxWidth_px >= 1 && kMaxWidth_px <= 4096, "sums are sized for rows of at most 4096 pixels");
  static_assert(kMaxWidth_px % 4 == 0, "ring rows are word-aligned");
  static_assert(kMaxOpen >= 1 && kMaxOpen < 0xFFFF, "slots are 16-bit, 0xFFFF means untracked");
  static_assert(kRingRows >= 1 && kRingRows <= 64, "at least the row buffer; refinement needs 2h+1");
  static_assert(kMaxPending >= 1);

  LabelRun runs_a[kMaxWidth_px / 2 + 1];
  LabelRun runs_b[kMaxWidth_px / 2 + 1];
  OpenComponent components[kMaxOpen];
  std::uint16_t free_slots[kMaxOpen];
  std::uint16_t merged_slots[kMaxOpen];
  alignas(4) std::uint8_t ring[kRingRows * kMaxWidth_px];
  PendingRefinement pending[kMaxPending];
  std::uint16_t window_weights[kWindowWeights];

  LabelerMemory memory() {
    return {runs_a,
            runs_b,
            components,
            free_slots,
            merged_slots,
            ring,
            pending,
            window_weights,
            static_cast<std::uint16_t>(kMaxWidth_px),
            static_cast<std::uint16_t>(kRingRows)};
  }
};

// The VGA configuration of the sensor platform: 640-pixel rows, 32 open components, a
// 13-row ring (refinement windows up to 13x13, Gaussian spots up to sigma ~2 px).
using VgaLabelerBuffers = LabelerBuffers<640, 32, 13, 8>;

// One labeler works on one frame at a time; not thread- or ISR-safe (one producer).
// Sequence: begin_frame, then per row either push_row(row) or row_buffer() + commit_row(width),
// then end_frame. Blobs appear in `out` as they complete (refined ones change in place until
// end_frame); read them after end_frame.
class BlobLabeler {
 public:
  explicit BlobLabeler(LabelerMemory memory) noexcept : m_(memory) {}

  // Starts a frame. kBadWorkspace / kBadConfig leave the labeler refusing rows.
  LabelStatus begin_frame(const LabelerConfig& config, std::span<Blob> out) noexcept;

  // Labels one row of 8-bit intensities. Copies it into the ring when refinement needs it
  // (ring_rows > 1), else reads it in place. Cost O(width).
  LabelStatus push_row(std::span<const std::uint8_t> row) noexcept;

  // Zero-copy input: the ring slot for the next row (max_width bytes; a DMA or a format
  // converter writes the row there), then commit_row labels its first width_px bytes.
  std::span<std::uint8_t> row_buffer() noexcept;
  LabelStatus commit_row(std::uint16_t width_px) noexcept;

  // Completes the frame: closes the blobs open in the last row (flagged kTouchesBorder),
  // runs or abandons pending refinements, fills `summary`.
  LabelStatus end_frame(FrameSummary& summary) noexcept;

 private:
  LabelStatus check_row(std::uint16_t width_px) noexcept;
  void label_row(const std::uint8_t* row, std::uint16_t width_px) noexcept;
  void finish_row() noexcept;
  void close_component(std::uint16_t slot, bool last_row) noexcept;
  void run_due_refinements(bool frame_end) noexcept;
  bool refine(const PendingRefinement& p, Blob& blob) noexcept;
  const std::uint8_t* ring_row(int y) const noexcept;

  LabelerMemory m_;
  LabelerConfig config_{};
  std::span<Blob> out_{};
  FrameSummary summary_{};
  std::span<LabelRun> prev_{}, cur_{};
  std::uint16_t prev_count_ = 0;
  std::uint16_t free_count_ = 0;
  std::uint16_t merged_count_ = 0;
  std::uint16_t closing_begin_ = 0, closing_end_ = 0;  // slots closed by the last row, in free_slots
  std::uint16_t pending_count_ = 0;
  std::uint16_t next_ring_slot_ = 0;
  bool in_frame_ = false;
};

}  // namespace kincal::core

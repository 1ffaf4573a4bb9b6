// The streaming labeler against a flood-fill reference (same components, exact binary
// centroids), its weighted and refined centroids against known spots, every capacity and
// error path, and a digest of all outputs that must be the same natively and on the M4.
#include "firmware/core/blob_labeler.hpp"

#include <doctest.h>

#include <cstdint>
#include <cstring>
#include <span>

#include "shared/crc32.hpp"
#include "tests/firmware/core/blob_test_images.hpp"

using namespace kincal::core;
using kincal::test::Image;
using kincal::test::ReferenceLabels;
using kincal::test::Splitmix64;

namespace {

constexpr int kW = 96, kH = 72;
using TestImage = Image<kW, kH>;

struct Run {
  LabelerBuffers<kW, 128, 13, 8> buffers;
  Blob blobs[1024];
  FrameSummary summary;
  LabelStatus status = LabelStatus::kOk;

  template <int W, int H>
  void label(const Image<W, H>& img, const LabelerConfig& config, int width = W) {
    BlobLabeler labeler(buffers.memory());
    status = labeler.begin_frame(config, blobs);
    for (int y = 0; y < H && status == LabelStatus::kOk; ++y)
      status = labeler.push_row({img.px[y], static_cast<std::size_t>(width)});
    if (status == LabelStatus::kOk) status = labeler.end_frame(summary);
  }
  // The blob whose first pixel is (x, y), or nullptr.
  const Blob* at(int x, int y) const {
    for (std::uint32_t i = 0; i < summary.blobs; ++i)
      if (blobs[i].first_x_px == x && blobs[i].y_min_px == y) return &blobs[i];
    return nullptr;
  }
};

// Static: too large for the M4 test's stack.
Run g_run;
TestImage g_img;
ReferenceLabels<kW, kH, 1024> g_ref;

std::int64_t round_ratio_q16(std::int64_t n, std::int64_t d) {  // reference: exact rational, rounded
  const std::int64_t num = n * 65536;
  return num >= 0 ? (num + d / 2) / d : -((-num + d / 2) / d);
}

// Compares the labeler's blobs with the flood fill: same set of components, same areas, boxes,
// first pixels, border flags and binary centroids (q16_16-rounded exact means).
void check_against_reference(const Run& run, const TestImage& img, const LabelerConfig& config) {
  const bool bright = config.polarity == Polarity::kBright;
  const int t = config.threshold;
  g_ref.run(
      img, [&](std::uint8_t p) { return bright ? p > t : p < t; }, config.connectivity == Connectivity::kEight);
  REQUIRE_FALSE(g_ref.overflow);
  REQUIRE(run.status == LabelStatus::kOk);
  CHECK(run.summary.runs_untracked == 0);
  CHECK(run.summary.blobs == static_cast<std::uint32_t>(g_ref.count));
  int mismatches = 0;
  for (int i = 0; i < g_ref.count; ++i) {
    const auto& r = g_ref.comps[i];
    const Blob* b = run.at(r.first_x, r.y_min);
    const bool border = r.x_min == 0 || r.y_min == 0 || r.x_max == kW - 1 || r.y_max == kH - 1;
    const bool same = b != nullptr && b->area_px == r.n && b->x_min_px == r.x_min && b->x_max_px == r.x_max &&
                      b->y_max_px == r.y_max && ((b->flags & kTouchesBorder) != 0) == border &&
                      b->binary_x_px.raw() == round_ratio_q16(r.sx, r.n) &&
                      b->binary_y_px.raw() == round_ratio_q16(r.sy, r.n);
    if (!same && ++mismatches <= 3) MESSAGE("component at (", r.first_x, ", ", r.y_min, ") area ", r.n, " differs");
  }
  CHECK(mismatches == 0);
}

void random_shapes(TestImage& img, Splitmix64& rng, std::uint8_t background, std::uint8_t ink) {
  img.fill(background);
  for (int i = 0; i < 40; ++i) {
    const int x = rng.below(kW), y = rng.below(kH), w = 1 + rng.below(12), h = 1 + rng.below(12);
    switch (rng.below(3)) {
      case 0:
        img.rect(x, y, x + w, y + h, ink);
        break;
      case 1:  // U shape: two arms that merge at the bottom
        img.rect(x, y, x + 1, y + h, ink);
        img.rect(x + w + 2, y, x + w + 3, y + h, ink);
        img.rect(x, y + h, x + w + 3, y + h + 1, ink);
        break;
      default:  // a diagonal staircase: 8-connected only
        for (int k = 0; k < w; ++k) img.rect(x + k, y + k, x + k, y + k, ink);
        break;
    }
  }
}

}  // namespace

TEST_CASE("labeler: same components and binary centroids as a flood fill, on random shapes and noise") {
  Splitmix64 rng(0x1234);
  for (int trial = 0; trial < 12; ++trial) {
    LabelerConfig config;
    config.refine = trial % 2 == 0;
    config.connectivity = trial % 3 == 2 ? Connectivity::kFour : Connectivity::kEight;
    if (trial < 6) {
      const bool dark = trial % 2 == 1;
      random_shapes(g_img, rng, dark ? 200 : 30, dark ? 40 : 220);
      g_img.add_noise(rng, 10);
      config.polarity = dark ? Polarity::kDark : Polarity::kBright;
      config.threshold = 120;
    } else {
      // Random pixels: many tiny components, merges in every row, 8-neighbour diagonals.
      g_img.fill(0);
      g_img.add_noise(rng, 255);
      config.threshold = static_cast<std::uint8_t>(150 + 10 * (trial - 6));
    }
    g_run.label(g_img, config);
    check_against_reference(g_run, g_img, config);
  }
}

TEST_CASE("labeler: threshold edges, polarity and odd widths") {
  LabelerConfig config;
  config.refine = false;
  config.threshold = 100;
  g_img.fill(100);  // I == threshold is background in both polarities
  g_img.rect(10, 10, 12, 12, 101);
  g_img.rect(20, 10, 22, 12, 99);
  g_run.label(g_img, config);
  REQUIRE(g_run.summary.blobs == 1);
  CHECK(g_run.blobs[0].first_x_px == 10);
  config.polarity = Polarity::kDark;
  g_run.label(g_img, config);
  REQUIRE(g_run.summary.blobs == 1);
  CHECK(g_run.blobs[0].first_x_px == 20);
  // Every width from 1 to 13 (the word scan's tails) with a pixel in the last column.
  for (int width = 1; width <= 13; ++width) {
    g_img.fill(0);
    g_img.rect(width - 1, 3, width - 1, 3, 255);
    config.polarity = Polarity::kBright;
    g_run.label(g_img, config, width);
    REQUIRE(g_run.summary.blobs == 1);
    CHECK(g_run.blobs[0].x_min_px == width - 1);
    CHECK((g_run.blobs[0].flags & kTouchesBorder) != 0);
  }
  // Threshold 255 (bright) and 0 (dark) have no foreground at all.
  g_img.fill(255);
  config.threshold = 255;
  g_run.label(g_img, config);
  CHECK(g_run.summary.blobs == 0);
  g_img.fill(0);
  config.threshold = 0;
  config.polarity = Polarity::kDark;
  g_run.label(g_img, config);
  CHECK(g_run.summary.blobs == 0);
}

TEST_CASE("labeler: weighted centroid and moments relative to the local background") {
  LabelerConfig config;
  config.refine = false;
  config.threshold = 60;
  g_img.fill(40);
  // A 3x1 bar 50, 100, 150 above background 40: weights 10, 60, 110 at x = 20, 21, 22.
  g_img.px[30][20] = 50 + 20;  // 70 > threshold
  g_img.px[30][21] = 100;
  g_img.px[30][22] = 150;
  g_run.label(g_img, config);
  REQUIRE(g_run.summary.blobs == 1);
  const Blob& b = g_run.blobs[0];
  CHECK(b.background_dn.raw() == 40 * 256);
  // weights 30, 60, 110: x = (20*30 + 21*60 + 22*110) / 200 = 21.4
  CHECK(b.weighted_x_px.raw() == round_ratio_q16(20 * 30 + 21 * 60 + 22 * 110, 200));
  CHECK(b.weighted_y_px.raw() == 30 * 65536);
  CHECK(b.binary_x_px.raw() == 21 * 65536);
  CHECK(b.weight_sum_dn == 200);
  // mu20 = sum w (x - 21.4)^2 / sum w = (30*1.96 + 60*0.16 + 110*0.36) / 200 = 0.54
  CHECK(b.mu20_px2.raw() == 138);  // 0.54 * 256 = 138.24
  CHECK(b.mu02_px2.raw() == 0);

  // A dark 2x2 square of 0 on 200 with one 100 pixel: weights 200 - I.
  g_img.fill(200);
  g_img.rect(40, 20, 41, 21, 0);
  g_img.px[21][41] = 100;
  config.polarity = Polarity::kDark;
  config.threshold = 150;
  g_run.label(g_img, config);
  REQUIRE(g_run.summary.blobs == 1);
  // weights 200, 200, 200, 100: x = (40*400 + 41*300) / 700, y = (20*400 + 21*300) / 700
  CHECK(g_run.blobs[0].weighted_x_px.raw() == round_ratio_q16(40 * 400 + 41 * 300, 700));
  CHECK(g_run.blobs[0].weighted_y_px.raw() == round_ratio_q16(20 * 400 + 21 * 300, 700));
  // The light corner leaves mass on the anti-diagonal: mu11 = -(2/49) px^2 = -10.45 / 256.
  CHECK(g_run.blobs[0].mu11_px2.raw() == -10);
}

TEST_CASE("labeler: refined centroids of blurred spots are within 0.01 px, noise-free") {
  LabelerConfig config;
  config.threshold = 70;
  Splitmix64 rng(7);
  double worst_refined = 0, worst_binary = 0;
  int refined = 0;
  for (int i = 0; i < 16; ++i) {
    g_img.fill(20);
    const double cx = 20 + 50 * rng.unit(), cy = 15 + 40 * rng.unit();
    const double sigma = 1.0 + rng.unit();
    g_img.add_spot(cx, cy, sigma, 180);
    g_run.label(g_img, config);
    REQUIRE(g_run.summary.blobs == 1);
    const Blob& b = g_run.blobs[0];
    refined += (b.flags & kRefined) != 0 ? 1 : 0;
    const double ex = b.x_px.to_double() - cx, ey = b.y_px.to_double() - cy;
    const double bx = b.binary_x_px.to_double() - cx, by = b.binary_y_px.to_double() - cy;
    worst_refined = ex * ex + ey * ey > worst_refined ? ex * ex + ey * ey : worst_refined;
    worst_binary = bx * bx + by * by > worst_binary ? bx * bx + by * by : worst_binary;
  }
  CHECK(refined == 16);
  CHECK(worst_refined < 0.01 * 0.01);
  CHECK(worst_binary > worst_refined);  // the refinement is not a no-op
}

TEST_CASE("labeler: blobs that are too large, on the border or whose window leaves the frame are not refined") {
  LabelerConfig config;
  config.threshold = 70;
  g_img.fill(20);
  g_img.add_spot(3.2, 30.0, 1.2, 180);   // window would leave the frame on the left
  g_img.add_spot(50.0, 68.5, 1.2, 180);  // window would extend below the last row
  g_img.rect(60, 10, 80, 30, 200);       // too large
  g_run.label(g_img, config);
  REQUIRE(g_run.summary.blobs == 3);
  for (std::uint32_t i = 0; i < 3; ++i) CHECK((g_run.blobs[i].flags & kRefined) == 0);
  CHECK(g_run.summary.refinements == 0);
  CHECK(g_run.summary.refinements_skipped == 2);
}

TEST_CASE("labeler: more open components than slots are reported, never merged into wrong blobs") {
  LabelerBuffers<kW, 3, 1, 1> small;
  Blob out[16];
  LabelerConfig config;
  config.refine = false;
  g_img.fill(0);
  for (int k = 0; k < 6; ++k) g_img.rect(5 + 10 * k, 10, 7 + 10 * k, 20, 255);  // six open at once
  g_img.rect(5, 21, 65, 22, 255);                                               // a bar joins them all at the bottom
  g_img.rect(5, 40, 7, 42, 255);  // later, a separate blob: slots are free again
  BlobLabeler labeler(small.memory());
  REQUIRE(labeler.begin_frame(config, out) == LabelStatus::kOk);
  for (int y = 0; y < kH; ++y) REQUIRE(labeler.push_row({g_img.px[y], kW}) == LabelStatus::kOk);
  FrameSummary summary;
  REQUIRE(labeler.end_frame(summary) == LabelStatus::kOk);
  CHECK(summary.runs_untracked > 0);
  REQUIRE(summary.blobs == 2);
  CHECK((out[0].flags & kIncomplete) != 0);  // the comb, with columns it could not track
  CHECK(out[0].area_px < 6 * 3 * 11 + 61 * 2);
  CHECK((out[1].flags & kIncomplete) == 0);
  CHECK(out[1].area_px == 9);
}

TEST_CASE("labeler: a full output span drops and counts; small blobs are filtered") {
  Blob out[2];
  LabelerConfig config;
  config.refine = false;
  config.min_area_px = 4;
  g_img.fill(0);
  for (int k = 0; k < 5; ++k) g_img.rect(5 + 10 * k, 10, 6 + 10 * k, 11, 255);  // 2x2: kept
  g_img.rect(5, 30, 5, 30, 255);                                                // 1 pixel: dropped
  BlobLabeler labeler(g_run.buffers.memory());
  REQUIRE(labeler.begin_frame(config, out) == LabelStatus::kOk);
  for (int y = 0; y < kH; ++y) REQUIRE(labeler.push_row({g_img.px[y], kW}) == LabelStatus::kOk);
  FrameSummary summary;
  REQUIRE(labeler.end_frame(summary) == LabelStatus::kOk);
  CHECK(summary.blobs == 2);
  CHECK(summary.blobs_dropped_output_full == 3);
  CHECK(summary.blobs_dropped_small == 1);
}

TEST_CASE("labeler: misuse and bad rows are refused with a status") {
  BlobLabeler labeler(g_run.buffers.memory());
  FrameSummary summary;
  std::uint8_t row[kW + 1] = {};
  CHECK(labeler.push_row({row, 10}) == LabelStatus::kNotInFrame);
  CHECK(labeler.end_frame(summary) == LabelStatus::kNotInFrame);
  LabelerConfig config;
  config.refine_half_window_px = 7;  // 15 rows > the 13-row ring
  CHECK(labeler.begin_frame(config, g_run.blobs) == LabelStatus::kBadConfig);
  config.refine_half_window_px = 3;  // a 7x7 window cannot refine blobs up to 9 px wide
  CHECK(labeler.begin_frame(config, g_run.blobs) == LabelStatus::kBadConfig);
  config.refine_half_window_px = 6;
  config.background_guard_px = 0;
  CHECK(labeler.begin_frame(config, g_run.blobs) == LabelStatus::kBadConfig);
  config.background_guard_px = 3;
  REQUIRE(labeler.begin_frame(config, g_run.blobs) == LabelStatus::kOk);
  CHECK(labeler.push_row({row, kW + 1}) == LabelStatus::kRowTooWide);
  CHECK(labeler.push_row({row, 10}) == LabelStatus::kNotInFrame);  // the frame failed
  REQUIRE(labeler.begin_frame(config, g_run.blobs) == LabelStatus::kOk);
  CHECK(labeler.push_row({row, 10}) == LabelStatus::kOk);
  CHECK(labeler.push_row({row, 11}) == LabelStatus::kRowWidthChanged);
  REQUIRE(labeler.begin_frame(config, g_run.blobs) == LabelStatus::kOk);
  CHECK(labeler.push_row({row, 0}) == LabelStatus::kEmptyRow);
  LabelerMemory broken = g_run.buffers.memory();
  broken.free_slots = broken.free_slots.first(3);
  BlobLabeler bad(broken);
  CHECK(bad.begin_frame(config, g_run.blobs) == LabelStatus::kBadWorkspace);
  CHECK(bad.push_row({row, 10}) == LabelStatus::kNotInFrame);
}

TEST_CASE("labeler: zero-copy rows give the same blobs as copied rows") {
  LabelerConfig config;
  config.threshold = 70;
  g_img.fill(20);
  g_img.add_spot(30.3, 20.7, 1.5, 180);
  g_img.add_spot(60.6, 40.2, 2.0, 120);
  g_run.label(g_img, config);
  REQUIRE(g_run.summary.blobs == 2);
  Blob copy[2];
  std::memcpy(copy, g_run.blobs, sizeof copy);
  BlobLabeler labeler(g_run.buffers.memory());
  REQUIRE(labeler.begin_frame(config, g_run.blobs) == LabelStatus::kOk);
  for (int y = 0; y < kH; ++y) {
    std::memcpy(labeler.row_buffer().data(), g_img.px[y], kW);
    REQUIRE(labeler.commit_row(kW) == LabelStatus::kOk);
  }
  REQUIRE(labeler.end_frame(g_run.summary) == LabelStatus::kOk);
  CHECK(std::memcmp(copy, g_run.blobs, sizeof copy) == 0);
}

namespace {
// zlib's crc32(crc, data, size): the running CRC-32 continued over `data`.
std::uint32_t crc32_bytes(std::uint32_t crc, const void* data, std::size_t size) {
  return ~kincal::shared::crc32_update(~crc, std::span(static_cast<const std::uint8_t*>(data), size));
}
template <class T>
std::uint32_t crc_value(std::uint32_t crc, T v) {
  return crc32_bytes(crc, &v, sizeof v);
}
std::uint32_t crc_blob(std::uint32_t crc, const Blob& b) {
  const std::int32_t fields[] = {b.x_px.raw(),          b.y_px.raw(),        b.weighted_x_px.raw(),
                                 b.weighted_y_px.raw(), b.binary_x_px.raw(), b.binary_y_px.raw(),
                                 b.mu20_px2.raw(),      b.mu11_px2.raw(),    b.mu02_px2.raw()};
  for (const std::int32_t f : fields) crc = crc_value(crc, f);
  const std::uint32_t more[] = {b.area_px,  b.weight_sum_dn, b.background_dn.raw(), b.x_min_px, b.x_max_px,
                                b.y_min_px, b.y_max_px,      b.first_x_px,          b.flags};
  for (const std::uint32_t f : more) crc = crc_value(crc, f);
  return crc;
}
}  // namespace

// Every output bit of the labeler over a fixed set of synthetic frames: spots (refined), noisy
// shapes in both polarities, random pixels. The constant was taken from the native run; the M4
// run must reproduce it bit for bit (the test's images use only integer and + - * / arithmetic).
TEST_CASE("labeler: output digest is the same natively and on the M4") {
  Splitmix64 rng(0xD16E57);
  std::uint32_t crc = 0;
  for (int frame = 0; frame < 8; ++frame) {
    LabelerConfig config;
    if (frame < 3) {
      g_img.fill(static_cast<std::uint8_t>(15 + 5 * frame));
      for (int s = 0; s < 6; ++s) {
        // One draw per statement: the order of evaluation of arguments differs between targets.
        const double x = 10 + 76 * rng.unit();
        const double y = 10 + 52 * rng.unit();
        const double sigma = 1.0 + rng.unit();
        g_img.add_spot(x, y, sigma, 80 + 150 * rng.unit());
      }
      g_img.add_noise(rng, 6);
      config.threshold = 60;
    } else if (frame < 6) {
      const bool dark = frame % 2 == 1;
      random_shapes(g_img, rng, dark ? 210 : 25, dark ? 35 : 230);
      g_img.add_noise(rng, 20);
      config.polarity = dark ? Polarity::kDark : Polarity::kBright;
      config.threshold = 128;
    } else {
      g_img.fill(0);
      g_img.add_noise(rng, 255);
      config.threshold = 170;
      config.connectivity = frame == 7 ? Connectivity::kFour : Connectivity::kEight;
    }
    g_run.label(g_img, config);
    REQUIRE(g_run.status == LabelStatus::kOk);
    crc = crc_value(crc, g_run.summary.blobs);
    crc = crc_value(crc, g_run.summary.refinements);
    for (std::uint32_t i = 0; i < g_run.summary.blobs; ++i) crc = crc_blob(crc, g_run.blobs[i]);
  }
  MESSAGE("labeler digest ", crc);
  CHECK(crc == 976846385u);
}

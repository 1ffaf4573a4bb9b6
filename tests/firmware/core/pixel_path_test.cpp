// Row formats, colour classes and the automatic threshold in front of the labeler: exact
// luma and cell indices, the parameter block's checks, Otsu against a double reference, and
// a colour beacon found through the labeler from RGB565 and YUV422 rows.
#include <doctest.h>

#include <cstdint>

#include "firmware/core/auto_threshold.hpp"
#include "firmware/core/blob_labeler.hpp"
#include "firmware/core/colour_class.hpp"
#include "firmware/core/pixel_formats.hpp"
#include "shared/crc32.hpp"
#include "tests/firmware/core/blob_test_images.hpp"

using namespace kincal::core;

namespace {
constexpr std::uint16_t pack565(int r8, int g8, int b8) {
  return static_cast<std::uint16_t>((r8 >> 3) << 11 | (g8 >> 2) << 5 | (b8 >> 3));
}
ColourClassTable g_table;
std::uint8_t g_block[kColourTableBlockBytes];
}  // namespace

TEST_CASE("pixel formats: RGB565 and YUV422 luma") {
  CHECK(rgb565_luma(0xFFFF) == 255);
  CHECK(rgb565_luma(0x0000) == 0);
  CHECK(rgb565_luma(0xF800) == 77);   // (77 * 255 + 128) >> 8 = 77
  CHECK(rgb565_luma(0x07E0) == 149);  // (150 * 255 + 128) >> 8 = 149
  CHECK(rgb565_luma(0x001F) == 29);
  const std::uint16_t rgb[3] = {0xFFFF, 0xF800, 0x001F};
  std::uint8_t out[3] = {};
  CHECK(rgb565_to_luma(rgb, out) == PixelStatus::kOk);
  CHECK((out[0] == 255 && out[1] == 77 && out[2] == 29));
  CHECK(rgb565_to_luma(rgb, std::span<std::uint8_t>(out, 2)) == PixelStatus::kOutputTooShort);
  const std::uint8_t yuyv[6] = {10, 128, 20, 128, 30, 128};
  CHECK(yuv422_to_luma(yuyv, out) == PixelStatus::kOk);
  CHECK((out[0] == 10 && out[1] == 20 && out[2] == 30));
  CHECK(yuv422_to_luma(std::span<const std::uint8_t>(yuyv, 5), out) == PixelStatus::kOddYuvRow);
}

TEST_CASE("colour classes: cell indices, the parameter block round trip and its checks") {
  CHECK(rgb565_cell(0xFFFF) == 4095);
  CHECK(rgb565_cell(pack565(255, 0, 0)) == 0xF00);
  CHECK(rgb565_cell(pack565(0, 255, 0)) == 0x0F0);
  CHECK(yuv_cell(0x12, 0x34, 0x56) == 0x135);
  g_table = ColourClassTable{};
  g_table.space = ColourSpace::kYuv422;
  g_table.threshold = 7;
  for (std::size_t i = 0; i < kColourCells; ++i) g_table.score[i] = static_cast<std::uint8_t>(i * 31);
  serialize_colour_table(g_table, g_block);
  ColourClassTable back;
  REQUIRE(parse_colour_table(g_block, back) == ColourTableStatus::kOk);
  CHECK(back.space == ColourSpace::kYuv422);
  CHECK(back.threshold == 7);
  CHECK(back.score == g_table.score);
  CHECK(parse_colour_table(std::span<const std::uint8_t>(g_block, 100), back) == ColourTableStatus::kWrongSize);
  g_block[100] ^= 1;
  CHECK(parse_colour_table(g_block, back) == ColourTableStatus::kBadCrc);
  g_block[100] ^= 1;
  // The reserved byte set, under a valid CRC: refused, as the block would not serialize back.
  g_block[7] = 1;
  const std::uint32_t crc = kincal::shared::crc32(std::span<const std::uint8_t>(g_block, kColourTableBlockBytes - 4));
  for (std::size_t i = 0; i < 4; ++i)
    g_block[kColourTableBlockBytes - 4 + i] = static_cast<std::uint8_t>(crc >> (8 * i));
  CHECK(parse_colour_table(g_block, back) == ColourTableStatus::kReservedNotZero);
  g_block[7] = 0;
  g_block[0] = 'X';
  CHECK(parse_colour_table(g_block, back) == ColourTableStatus::kBadMagic);
}

TEST_CASE("Otsu threshold: the optimum of the between-class variance, as a double reference finds it") {
  kincal::test::Splitmix64 rng(99);
  for (int trial = 0; trial < 20; ++trial) {
    GreyHistogram h;
    std::uint8_t row[200];
    const int lo = 20 + rng.below(60), hi = 150 + rng.below(80), spread = 2 + rng.below(20);
    for (int y = 0; y < 50; ++y) {
      for (auto& p : row) {
        const bool upper = rng.below(100) < 10 + 3 * trial;
        p = static_cast<std::uint8_t>((upper ? hi : lo) + rng.below(2 * spread + 1) - spread);
      }
      REQUIRE(h.add_row(row) == ThresholdStatus::kOk);
    }
    std::uint8_t t = 0;
    REQUIRE(otsu_threshold(h, t) == ThresholdStatus::kOk);
    // Double reference: sigma_B^2(t) = w0 w1 (mu1 - mu0)^2; ours must be optimal to 1e-4.
    double best = 0, mine = 0;
    for (int k = 0; k < 255; ++k) {
      double n0 = 0, s0 = 0, n1 = 0, s1 = 0;
      for (int i = 0; i < 256; ++i) (i <= k ? n0 : n1) += h.counts[static_cast<std::size_t>(i)];
      for (int i = 0; i < 256; ++i)
        (i <= k ? s0 : s1) += i * static_cast<double>(h.counts[static_cast<std::size_t>(i)]);
      if (n0 == 0 || n1 == 0) continue;
      const double n = n0 + n1, d = s1 / n1 - s0 / n0;
      const double v = n0 / n * n1 / n * d * d;
      best = v > best ? v : best;
      if (k == t) mine = v;
    }
    CHECK(mine >= best * (1 - 1e-4));
    CHECK(t >= lo);
    CHECK(t < hi);
  }
  GreyHistogram flat;
  std::uint8_t same[10] = {5, 5, 5, 5, 5, 5, 5, 5, 5, 5};
  REQUIRE(flat.add_row(same) == ThresholdStatus::kOk);
  std::uint8_t t = 0;
  CHECK(otsu_threshold(flat, t) == ThresholdStatus::kUniform);
  CHECK(otsu_threshold(GreyHistogram{}, t) == ThresholdStatus::kEmpty);
  CHECK(flat.add_row(same, 0) == ThresholdStatus::kBadStep);
  CHECK(dark_threshold(254) == 255);
  CHECK(dark_threshold(255) == 255);
}

namespace {
constexpr int kW = 64, kH = 40;
std::uint16_t g_rgb[kH][kW];
std::uint8_t g_yuyv[kH][2 * kW];
LabelerBuffers<kW, 16, 13, 4> g_buffers;
Blob g_blobs[8];
}  // namespace

TEST_CASE("colour classes: a red disc on grey clutter is the only blob, from RGB565 and from YUV422") {
  // Table: red (R high, G and B low) scores 255, everything else 0.
  g_table = ColourClassTable{};
  g_table.threshold = 127;
  for (std::size_t r = 12; r < 16; ++r)
    for (std::size_t g = 0; g < 4; ++g)
      for (std::size_t b = 0; b < 5; ++b) g_table.score[r << 8 | g << 4 | b] = 255;
  // Grey clutter, a bright white square (bright in luma, not red), and a red disc centred on (40.0, 20.0).
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const int grey = 60 + (x * 7 + y * 3) % 50;
      const bool disc = (x - 40) * (x - 40) + (y - 20) * (y - 20) <= 16;
      const bool white = x >= 8 && x < 16 && y >= 8 && y < 16;
      g_rgb[y][x] = disc ? pack565(220, 20, 30) : (white ? pack565(255, 255, 255) : pack565(grey, grey, grey));
    }
  LabelerConfig config;
  config.threshold = g_table.threshold;
  config.refine = false;
  BlobLabeler labeler(g_buffers.memory());
  REQUIRE(labeler.begin_frame(config, g_blobs) == LabelStatus::kOk);
  for (int y = 0; y < kH; ++y) {
    REQUIRE(classify_rgb565(g_rgb[y], g_table, labeler.row_buffer()) == PixelStatus::kOk);
    REQUIRE(labeler.commit_row(kW) == LabelStatus::kOk);
  }
  FrameSummary summary;
  REQUIRE(labeler.end_frame(summary) == LabelStatus::kOk);
  REQUIRE(summary.blobs == 1);
  CHECK(g_blobs[0].area_px == 49);
  CHECK(g_blobs[0].x_px.raw() == 40 * 65536);
  CHECK(g_blobs[0].y_px.raw() == 20 * 65536);

  // The same scene as YUV422 (BT.601, integer): a table over Y, U, V that marks high V (red).
  g_table.space = ColourSpace::kYuv422;
  g_table.score = {};
  for (std::size_t y = 0; y < 16; ++y)
    for (std::size_t u = 0; u < 16; ++u)
      for (std::size_t v = 12; v < 16; ++v) g_table.score[y << 8 | u << 4 | v] = 200;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; x += 2) {
      auto yuv = [](std::uint16_t p, int& Y, int& U, int& V) {
        const int r = (p >> 11) << 3, g = ((p >> 5) & 0x3F) << 2, b = (p & 0x1F) << 3;
        Y = (66 * r + 129 * g + 25 * b + 128) / 256 + 16;
        U = (-38 * r - 74 * g + 112 * b + 128) / 256 + 128;
        V = (112 * r - 94 * g - 18 * b + 128) / 256 + 128;
      };
      int y0, u0, v0, y1, u1, v1;
      yuv(g_rgb[y][x], y0, u0, v0);
      yuv(g_rgb[y][x + 1], y1, u1, v1);
      g_yuyv[y][2 * x] = static_cast<std::uint8_t>(y0);
      g_yuyv[y][2 * x + 1] = static_cast<std::uint8_t>((u0 + u1) / 2);
      g_yuyv[y][2 * x + 2] = static_cast<std::uint8_t>(y1);
      g_yuyv[y][2 * x + 3] = static_cast<std::uint8_t>((v0 + v1) / 2);
    }
  REQUIRE(labeler.begin_frame(config, g_blobs) == LabelStatus::kOk);
  for (int y = 0; y < kH; ++y) {
    REQUIRE(classify_yuv422(g_yuyv[y], g_table, labeler.row_buffer()) == PixelStatus::kOk);
    REQUIRE(labeler.commit_row(kW) == LabelStatus::kOk);
  }
  REQUIRE(labeler.end_frame(summary) == LabelStatus::kOk);
  REQUIRE(summary.blobs == 1);
  // Chroma is shared by pixel pairs, so the rim is decided per pair: the disc stays centred in
  // y and within half a pixel in x.
  CHECK(g_blobs[0].y_px.raw() == 20 * 65536);
  CHECK(g_blobs[0].x_px.to_double() == doctest::Approx(40.0).epsilon(0.0125));
  std::uint8_t out[kW];
  CHECK(classify_yuv422(std::span<const std::uint8_t>(g_yuyv[0], 6), g_table, out) == PixelStatus::kOddYuvRow);
}

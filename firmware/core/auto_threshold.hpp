// Automatic threshold for the blob labeler: a grey-level histogram and Otsu's threshold.
//
// Why: the fiducials' contrast and the beacon's brightness change with lighting and exposure;
// a fixed threshold that works in the lab fails at the rig. Otsu's method picks the threshold
// that maximizes the between-class variance of the histogram, with no parameter to tune.
//
// Streaming use: the labeler sees each frame once, so the threshold for frame k comes from the
// histogram of frame k-1 (add_row with a step of 4 samples every 4th pixel for 1/4 of the cost;
// sample every 4th row too and it is 1/16). The host tools, which hold the whole image, make
// one histogram pass and then label the same image.
//
// Threshold convention: Otsu splits the histogram into [0, t] and [t+1, 255]; the labeler's
// bright foreground (I > t) is the upper class. For dark blobs pass dark_threshold(t) = t + 1
// (I < t + 1, i.e. I <= t): the lower class. Same t as OpenCV's THRESH_OTSU.
//
// Arithmetic: integers only. The criterion n0 n1 (mu1 - mu0)^2 = d^2 / (n0 n1), with
// d = sum n0 - n s0, is compared between thresholds exactly, in 128-bit products, for up to
// 2^19 samples (a VGA frame); beyond, every candidate drops the same low bits (relative
// 2^-44). Ties: the first threshold wins, as in OpenCV. The same bits on both targets.
//
// Cost: add_row one increment per sampled pixel (a load, an add, a store); otsu_threshold
// 256 steps of a few 64-bit multiplications (no division). Memory: the 1 KiB histogram, caller-owned.
// Failure: fewer than 2 distinct grey levels has no threshold (kUniform); more than 2^26
// samples (a 4096 x 4096 frame is 2^24) would overflow the criterion's sums: kTooManySamples,
// and the row is not added.
#pragma once

#include <array>
#include <cstdint>
#include <span>

namespace kincal::core {

inline constexpr std::uint32_t kMaxHistogramSamples = 1u << 26;

enum class [[nodiscard]] ThresholdStatus : std::uint8_t{kOk, kUniform, kEmpty, kTooManySamples, kBadStep};

struct GreyHistogram {
  std::array<std::uint32_t, 256> counts{};
  std::uint32_t total = 0;

  // Adds every step-th pixel of the row (step >= 1).
  ThresholdStatus add_row(std::span<const std::uint8_t> row, std::uint32_t step = 1) noexcept;
  void clear() noexcept {
    counts = {};
    total = 0;
  }
};

// Otsu's threshold t of the histogram (upper class: I > t).
ThresholdStatus otsu_threshold(const GreyHistogram& histogram, std::uint8_t& threshold) noexcept;

// The labeler's dark-polarity threshold that selects Otsu's lower class (I <= t).
constexpr std::uint8_t dark_threshold(std::uint8_t otsu) noexcept {
  return static_cast<std::uint8_t>(otsu == 255 ? 255 : otsu + 1);
}

}  // namespace kincal::core

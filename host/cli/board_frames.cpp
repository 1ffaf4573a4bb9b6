#include "host/cli/board_frames.hpp"

#include <algorithm>
#include <iostream>
#include <memory>
#include <optional>
#include <utility>

#include <opencv2/core/utility.hpp>

#include "host/files/input_limits.hpp"

namespace kincal::cli {

BoardFrames::BoardFrames(const camera::Board& board, int min_corners)
    : board_(board),
      min_corners_(min_corners),
      batch_frames_(2 * static_cast<std::size_t>(std::max(1, cv::getNumThreads()))) {}

void BoardFrames::add(capture::Frame frame) {
  queued_pixels_ += static_cast<std::int64_t>(frame.image.total());
  images_.push_back(std::move(frame.image));
  views_.push_back(std::move(frame.origin));
  if (images_.size() >= batch_frames_ || queued_pixels_ >= files::kMaxImagePixels) detect_queued();
}

void BoardFrames::detect_queued() {
  const std::size_t before = detections_.size();
  for (camera::BoardDetection& d : camera::detect_boards(board_, images_, views_, min_corners_)) {
    found_ += d.found ? 1 : 0;
    detections_.push_back(std::move(d));
  }
  images_.clear();
  views_.clear();
  queued_pixels_ = 0;
  if (detections_.size() / 100 > before / 100)
    std::cerr << "kincal camera: " << detections_.size() << " images read, the board found in " << found_ << std::endl;
}

std::vector<camera::BoardDetection> BoardFrames::finish() {
  if (!images_.empty()) detect_queued();
  return std::move(detections_);
}

std::vector<camera::BoardDetection> detect_in_frames(const camera::Board& board, const std::vector<std::string>& inputs,
                                                     int min_corners) {
  std::unique_ptr<capture::FrameSource> source = capture::open_source(inputs);
  BoardFrames frames(board, min_corners);
  while (std::optional<capture::Frame> f = source->next()) frames.add(std::move(*f));
  return frames.finish();
}

}  // namespace kincal::cli

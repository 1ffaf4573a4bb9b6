// The board in frames as a command reads them (camera calibrate, stereo, hand-eye, board-poses):
// frames are queued and each batch's boards detected side by side (camera::detect_boards, on
// OpenCV's threads), so a command reading tens of large views or a long video uses every core
// while it holds only a batch of frames: about two per thread, at most
// files::kMaxImagePixels pixels together (one frame of any size at least).
// Every 100 frames detected a line on standard error: a video of thousands of frames is read for
// minutes.
#pragma once

#include <string>
#include <vector>

#include "host/camera/board.hpp"
#include "host/capture/frame_source.hpp"

namespace kincal::cli {

class BoardFrames {
 public:
  BoardFrames(const camera::Board& board, int min_corners);
  // Queues a frame; detects the queue when it is a full batch.
  void add(capture::Frame frame);
  // Detects what is queued; every frame's detection, in the order added.
  std::vector<camera::BoardDetection> finish();

 private:
  void detect_queued();
  const camera::Board& board_;
  int min_corners_;
  std::size_t batch_frames_;
  std::vector<cv::Mat> images_;
  std::vector<std::string> views_;
  std::int64_t queued_pixels_ = 0;
  std::vector<camera::BoardDetection> detections_;
  std::size_t found_ = 0;
};

// Every frame of the source's inputs (files, a directory or a video), detected as above.
std::vector<camera::BoardDetection> detect_in_frames(const camera::Board& board, const std::vector<std::string>& inputs,
                                                     int min_corners);

}  // namespace kincal::cli

// Frames per second of the streaming labeler against OpenCV's threshold +
// connectedComponentsWithStats on the same 640x480 frames, in one run, one thread each.
//
// Frames: 8 synthetic calibration-square views (light vellum with noise, six dark fiducials,
// blurred rims, shifted per frame) — the platform's workload. The labeler runs its full
// default path: rows copied into its ring, weighted moments, refinement eligibility; OpenCV
// computes a binary image, a label image and binary statistics. OpenCV is limited to one
// thread (cv::setNumThreads(1)) so that the ratio compares algorithms, not core counts; its
// multi-threaded rate (all cores, OpenCV's default) is a second ratio. Each side runs for at
// least 0.5 s, best of 3.
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <vector>

#include "firmware/core/blob_labeler.hpp"

using namespace kincal::core;

namespace {

constexpr int kWidth = 640, kHeight = 480, kFrames = 8;

cv::Mat render(int frame) {
  cv::Mat img(kHeight, kWidth, CV_8UC1);
  cv::RNG rng(static_cast<std::uint64_t>(frame) + 1);
  rng.fill(img, cv::RNG::NORMAL, 200, 6);
  const int cx = 300 + 9 * frame, cy = 235 + 5 * frame, s = 30, d = 210;
  const cv::Rect boxes[6] = {{cx - d - s / 2, cy - d - s / 2, s, s}, {cx - s / 2, cy - d - s / 2, s, s},
                             {cx - d - s / 2, cy - s / 2, s, s},     {cx - s / 2, cy - s, s, 2 * s},
                             {cx + d - s / 2, cy - s / 2, s, s},     {cx - s / 2, cy + d - s / 2, s, s}};
  for (const cv::Rect& r : boxes) cv::rectangle(img, r, cv::Scalar(40), cv::FILLED);
  cv::GaussianBlur(img, img, cv::Size(5, 5), 1.0);
  return img;
}

template <class F>
double frames_per_second(F run_all_frames) {
  using clock = std::chrono::steady_clock;
  double best = 0;
  for (int attempt = 0; attempt < 3; ++attempt) {
    int rounds = 0;
    const auto start = clock::now();
    double seconds = 0;
    while (seconds < 0.5) {
      run_all_frames();
      ++rounds;
      seconds = std::chrono::duration<double>(clock::now() - start).count();
    }
    const double fps = rounds * kFrames / seconds;
    best = fps > best ? fps : best;
  }
  return best;
}

}  // namespace

int main() {
  std::vector<cv::Mat> frames;
  for (int i = 0; i < kFrames; ++i) frames.push_back(render(i));

  auto buffers = std::make_unique<VgaLabelerBuffers>();
  Blob blobs[256];
  LabelerConfig config;
  config.polarity = Polarity::kDark;
  config.threshold = 128;
  std::uint32_t ours = 0;
  bool ok = true;
  const double labeler_fps = frames_per_second([&] {
    BlobLabeler labeler(buffers->memory());
    for (const cv::Mat& f : frames) {
      ok = ok && labeler.begin_frame(config, blobs) == LabelStatus::kOk;
      for (int y = 0; y < kHeight; ++y)
        ok = ok && labeler.push_row({f.ptr<std::uint8_t>(y), static_cast<std::size_t>(kWidth)}) == LabelStatus::kOk;
      FrameSummary summary;
      ok = ok && labeler.end_frame(summary) == LabelStatus::kOk;
      ours = summary.blobs;
    }
  });

  cv::Mat binary, labels, stats, centroids;
  int theirs = 0;
  auto opencv = [&] {
    for (const cv::Mat& f : frames) {
      cv::threshold(f, binary, 127, 255, cv::THRESH_BINARY_INV);  // I <= 127: the labeler's I < 128
      theirs = cv::connectedComponentsWithStats(binary, labels, stats, centroids, 8, CV_32S) - 1;
    }
  };
  const int threads = cv::getNumThreads();
  const double opencv_parallel_fps = frames_per_second(opencv);
  cv::setNumThreads(1);
  const double opencv_fps = frames_per_second(opencv);
  cv::setNumThreads(threads);

  std::printf("blobs in the last frame: labeler %u, OpenCV %d\n", static_cast<unsigned>(ours), theirs);
  std::printf("labeler %.0f fps, OpenCV (1 thread) %.0f fps, OpenCV (%d threads) %.0f fps\n", labeler_fps, opencv_fps,
              threads, opencv_parallel_fps);
  std::printf("FIGURE labeler_fps_vga %.0f fps\n", labeler_fps);
  std::printf("FIGURE opencv_threshold_ccstats_fps_vga %.0f fps\n", opencv_fps);
  std::printf("FIGURE labeler_vs_opencv_speed_ratio %.2f ratio\n", labeler_fps / opencv_fps);
  std::printf("FIGURE labeler_vs_opencv_all_threads_speed_ratio %.2f ratio\n", labeler_fps / opencv_parallel_fps);
  return ok && static_cast<int>(ours) == theirs ? 0 : 1;
}

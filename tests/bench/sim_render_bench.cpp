// Issue #6, the simulator: how long one rendered VGA frame of the calibration strip takes
// (supersampling 3 x 3, default blur, lighting and noise), on all of OpenCV's threads. The demo
// renders a few hundred frames and must finish in under 2 minutes on 2 cores.
//
// FIGURE sim_render_vga_ms: the median of 21 frames (after one that fills the ray cache) over
// tilted views of the strip; sim_ray_cache_vga_ms: the first frame's extra cost (the undistorted
// rays of a new camera).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <numbers>
#include <vector>

#include "host/sim/render.hpp"
#include "host/sim/strip.hpp"

int main() {
  using namespace kincal::sim;
  using Clock = std::chrono::steady_clock;
  CameraSpec camera;
  camera.distortion = {-0.1, 0.02, 0.0005, -0.0003, 0.0};
  const StripSpec strip;
  const PlanarTarget target = strip_target(strip);
  ImagingConditions conditions;
  const auto ms_since = [](Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  };
  const auto view = [&](int i) {
    const double tilt_rad = (i % 7 - 3) * 5 * std::numbers::pi / 180;
    return facing_camera(Eigen::Vector3d(0.01, 0, 0.3), tilt_rad, -tilt_rad / 2,
                         Eigen::Vector3d(0.1016 * (i % 3), 0, 0));
  };
  Clock::time_point start = Clock::now();
  std::size_t checksum = static_cast<std::size_t>(cv::sum(render_plane(camera, view(0), target, conditions))[0]);
  const double first_ms = ms_since(start);
  std::vector<double> ms;
  for (int i = 1; i <= 21; ++i) {
    conditions.seed = static_cast<std::uint64_t>(i);
    start = Clock::now();
    const cv::Mat image = render_plane(camera, view(i), target, conditions);
    ms.push_back(ms_since(start));
    checksum += static_cast<std::size_t>(cv::sum(image)[0]);
  }
  std::nth_element(ms.begin(), ms.begin() + 10, ms.end());
  std::printf("# %d threads, checksum %zu\n", cv::getNumThreads(), checksum);
  std::printf("FIGURE sim_render_vga_ms %.1f ms\n", ms[10]);
  std::printf("FIGURE sim_ray_cache_vga_ms %.1f ms\n", first_ms - ms[10]);
  return 0;
}

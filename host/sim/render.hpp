// Rendered camera images of planar targets (issue #6): what the simulated sensor platform's
// camera, the simulated stereo pair and the camera-calibration tests see.
//
// Model: an ideal pinhole with OpenCV's radial-tangential distortion (k1 k2 p1 p2 k3) looking at
// a plane (the target's z = 0 plane, reflectance given by the target); every output pixel is
// traced backwards (undistort -> ray -> plane -> reflectance), averaged over supersampling^2
// sub-pixel rays (anti-aliasing: edges are area-weighted), then blurred (defocus, Gaussian),
// lit (a linear gradient and a cos^4-like vignetting), given shot and read noise and quantized to
// 8 bits. Pixel (0, 0) is the centre of the top-left pixel, as in OpenCV, so a target point
// projected with cv::projectPoints lands where the renderer draws it.
//
// Rays that miss the plane (it is behind the camera or parallel to the ray) see reflectance 0.
// The image is rendered with a margin of ceil(3 blur sigma) pixels, so the blur near the border
// is that of a larger sensor, not of a replicated edge.
//
// Cost: supersampling^2 plane intersections and reflectance calls per pixel, then a separable
// blur (cv::GaussianBlur), on all of OpenCV's threads (cv::parallel_for_; the reflectance
// function must be safe to call concurrently): tens of milliseconds for VGA at 3x3 in Release
// (tests/bench/sim_render_bench.cpp). The undistorted rays of the pixel corners (Newton's method
// on OpenCV's model, at most 50 steps, each answer re-distorted and checked to 1e-6 px; sub-pixel
// rays are bilinear between corners, which is 1 / (8 f) px from exact) are computed once per
// camera and kept in a small process-wide cache (the 8 most recent cameras, guarded by a mutex,
// 16 bytes per pixel).
// Determinism: the same inputs and seed give the same image, bit for bit, whatever the thread
// count (one noise generator per row, seeded from the seed and the row).
// Errors: std::invalid_argument naming the field: image size 0 or above 8192, non-finite or
// non-positive focal length, non-finite principal point or distortion, a distortion that folds
// (or whose inverse does not converge) somewhere in the image, supersampling outside 1..8,
// negative noise, exposure or black level, blur sigma outside 0..20 px, |gradient| > 1,
// vignetting outside [0, 1), a non-finite pose, an empty reflectance function or one that
// returns a non-finite value.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace kincal::sim {

// Intrinsics in OpenCV's convention; distortion k1 k2 p1 p2 k3.
struct CameraSpec {
  int width_px = 640, height_px = 480;
  double fx_px = 600, fy_px = 600, cx_px = 319.5, cy_px = 239.5;
  std::array<double, 5> distortion{};
};

// A planar target in its own frame: reflectance in [0, 1] at (x, y) metres on the z = 0 plane,
// seen from +z or -z alike.
struct PlanarTarget {
  std::function<double(double x_m, double y_m)> reflectance;
};

struct ImagingConditions {
  double exposure_dn = 200;       // digital number at reflectance 1 in the image centre
  double black_level_dn = 12;     // digital number at reflectance 0
  double blur_sigma_px = 0.7;     // defocus, Gaussian sigma
  double gradient = 0.15;         // relative illumination change across the image width
  double vignetting = 0.2;        // relative fall-off in the corners
  double read_noise_dn = 1.5;     // Gaussian, per pixel
  double shot_noise_gain = 0.05;  // variance of shot noise in DN^2 per DN of signal
  int supersampling = 3;
  std::uint64_t seed = 1;
};

// The image (CV_8UC1, height x width) of `target` seen from a camera at camera_T_target.
cv::Mat render_plane(const CameraSpec& camera, const Eigen::Isometry3d& camera_T_target, const PlanarTarget& target,
                     const ImagingConditions& conditions);

// A chessboard of inner_cols x inner_rows inner corners (squares of square_m), white border of
// one square; inner corner (i, j) at (i * square_m, j * square_m, 0) in the target frame, in
// the order cv::findChessboardCorners reports them for this pattern size when the board is
// seen from its -z side (Facing::kZAway below: OpenCV's object-point convention; checked in
// tests/host/sim/render_test.cpp with a 9 x 6 board tilted up to 0.4 rad). Square (-1, -1), the
// one left of and above corner (0, 0), is black; beyond the white border reflectance is 0.5.
PlanarTarget chessboard(int inner_cols, int inner_rows, double square_m);

// A target from a grey texture image (CV_8UC1, e.g. an ArUco or ChArUco board drawn by
// OpenCV), metres_per_pixel across, with the texture's pixel (0, 0) centred at (0, 0) of the
// target frame, x along the texture's columns and y along its rows; outside it: `outside`.
// Errors (all three): std::invalid_argument naming the argument (fewer than 2 inner corners
// per side, a non-positive size, an empty or non-CV_8UC1 texture, `outside` outside [0, 1]).
PlanarTarget texture(const cv::Mat& grey, double metres_per_pixel, double outside = 1.0);

// Where the camera sees target points: cv::projectPoints with the camera's intrinsics and
// distortion (an implementation independent of the renderer's, which inverts the distortion).
// Points behind the camera are projected all the same (OpenCV does). Errors: as render_plane's
// for the camera.
std::vector<cv::Point2d> project_points(const CameraSpec& camera, const Eigen::Isometry3d& camera_T_target,
                                        std::span<const Eigen::Vector3d> points_target_m);

// Which side of a target faces the camera in facing_camera().
enum class Facing {
  kZToward,  // +z toward the camera, x right and y up in the image: a sheet of paper held upright
             // in front of the lens, read from its printed side (Doty's squares, the strip)
  kZAway,    // +z away from the camera, x right and y down in the image: OpenCV's convention for
             // calibration targets (chessboard(), ChArUco boards), object points in its order
};

// A pose that shows a target to the camera: target point `target_point_m` at `point_camera_m`
// (camera frame), the target turned as `facing` says, then tilted by tilt_x_rad about the
// target's x axis and tilt_y_rad about its y axis (through that point). Cost: a few flops;
// cannot fail.
Eigen::Isometry3d facing_camera(const Eigen::Vector3d& point_camera_m, double tilt_x_rad, double tilt_y_rad,
                                const Eigen::Vector3d& target_point_m = Eigen::Vector3d::Zero(),
                                Facing facing = Facing::kZToward);

}  // namespace kincal::sim

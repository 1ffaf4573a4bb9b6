// Kapucu & Baysec's rig, simulated (issue #6): a bright beacon on the robot's tool watched by a
// fixed parallel stereo pair, rendered as the two cameras' images.
//
// Their rig (tests/bench/kapucu_bench.cpp, host/model/robots/stanford_rrp.yaml): two identical
// cameras, f = 1 cm, 11 um x 13 um cells grabbed at 640 x 480 (fx = 909.1 px, fy = 769.2 px),
// baseline 12.6 cm, about 4.54 m from the robot.
// Frames: the device frame is the right camera's as in their paper and stanford_rrp.yaml: Z the
// optical axis, Y up, X = Y x Z (toward the left camera). The right camera's OpenCV frame (x
// right, y down) is the device frame turned half a turn about Z; the left camera sits at
// X = +baseline, i.e. the right camera is at +baseline along the left camera's OpenCV x axis,
// as core::triangulate_parallel (firmware/core/stereo.hpp) expects.
// The beacon: a bright disc of radius_m facing the rig (parallel to the image planes; a lamp's
// silhouette), on a darker background at the beacon's depth. The disc's image is then an
// ellipse centred on the projection of its centre (no distortion in their rig), so the true
// centroid is the returned projection.
//
// Cost: two render_plane calls (see render.hpp). Errors: std::invalid_argument naming the
// field: a beacon not in front of both cameras, a non-positive radius or baseline, reflectances
// outside [0, 1], and render_plane's.
#pragma once

#include <opencv2/core.hpp>

#include <Eigen/Core>

#include "firmware/core/stereo.hpp"
#include "host/sim/render.hpp"

namespace kincal::sim {

struct StereoRigSpec {
  CameraSpec camera{640, 480, 0.01 / 11e-6, 0.01 / 13e-6, 319.5, 239.5, {}};  // both cameras
  double baseline_m = 0.126;
};

struct BeaconSpec {
  double radius_m = 0.01;
  double beacon = 1.0;       // reflectance (radiance relative to the exposure) of the disc
  double background = 0.15;  // around it
};

struct StereoFrame {
  cv::Mat left, right;            // CV_8UC1 (render_beacon) or CV_8UC3 BGR (render_colour_beacon)
  cv::Point2d left_px, right_px;  // true projections of the beacon's centre
};

// The two images of a beacon at beacon_device_m. The right image's noise is seeded with
// conditions.seed, the left's with a seed derived from it (independent noise, reproducible).
StereoFrame render_beacon(const StereoRigSpec& rig, const BeaconSpec& beacon, const Eigen::Vector3d& beacon_device_m,
                          const ImagingConditions& conditions);

// A crimson beacon of radius_m on a grey background, as colour frames: each frame is two
// renders, the red channel with the disc bright (0.95 on 0.3), green and blue with it dark (0.08
// on 0.3), each with its own noise. lit = false renders the background alone (a beacon that is
// off or hidden). Errors: render_beacon's.
StereoFrame render_colour_beacon(const StereoRigSpec& rig, double radius_m, const Eigen::Vector3d& beacon_device_m,
                                 const ImagingConditions& conditions, bool lit = true);

// The rendered pair as a calibrated one (firmware/core/stereo.hpp): both cameras' intrinsics and
// distortion, the right camera one baseline along the left camera's x.
core::StereoPair stereo_pair_of(const StereoRigSpec& rig);

}  // namespace kincal::sim

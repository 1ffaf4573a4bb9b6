// Issue #7: Kapucu & Baysec's rig simulated as in their paper, their method against ours on the
// same data.
//
// Rig (their section 2.2 and 4): a Stanford-type RRP arm (their Table 1b, host/model/robots/
// stanford_rrp.yaml), a parallel stereo pair 4.54 m away (right camera at the device origin, Z
// along its optical axis, Y up, left camera 12.6 cm to the left), f = 1 cm, 11 um pixels. A
// beacon on the tip; 10 readings per joint, one joint swept at a time around a home
// configuration. Pixel centroids get Gaussian noise of sigma_px in u and v in both images;
// points are triangulated, and their first-order covariance (depth about 18 cm per pixel of
// disparity) goes into the dataset.
//
// Their method, as the paper describes it: the beacon's world coordinates through the (here
// exact) camera-to-world transform; for each sweep every triple of points gives a circle
// (centre, radius, plane normal; for the prismatic joint the direction of the line through the
// first two); Chauvenet's criterion discards triples whose centre (direction) coordinates or
// radius deviate too far; the means give the axis; DH frames by their steps 8-11 on the axes
// found (the same construction as ours, model/axes.hpp); the joint variable of the last
// (prismatic) joint and the beacon from the first reading of its sweep.
//
// The stereo noise is not in the paper; it is set here so that their method reproduces their
// Table 1 error level: the median, over 31 seeds, of their worst DH length error (over a1, d1,
// a2, d2) equals the paper's, 6.29 cm (d1: 120.71 found, 127 true), by bisection on sigma_px.
//
// Ours: cpa (statistical fits over all points with the commanded increments, robust rejection,
// the triangulation covariance), and full (Ceres, whitened by the triangulation covariance,
// started from cpa). Compared on held-out random configurations within the joint limits (RMS of
// the predicted beacon against the truth) and as the worst DH length error.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "host/identify/cpa.hpp"
#include "host/identify/identify.hpp"
#include "host/identify/statistics.hpp"
#include "host/model/axes.hpp"
#include "host/model/model_file.hpp"
#include "tests/bench/kapucu_rig.hpp"
#include "tests/host/identify/simulation.hpp"

namespace {

using namespace kincal;
using kapucu::kDeg;
using kapucu::kHome;
using kapucu::measure;
using kapucu::sweep_configurations;
using model::RobotModel;
using model::Vector3;

// Chauvenet's criterion on one coordinate: keep[k] stays true when n * P(|z| > |x_k - mean|/s) >= 0.5.
void chauvenet(const std::vector<double>& x, std::vector<bool>& keep) {
  const double n = static_cast<double>(x.size());
  double mean = 0, var = 0;
  for (double v : x) mean += v;
  mean /= n;
  for (double v : x) var += (v - mean) * (v - mean);
  const double s = std::sqrt(var / (n - 1));
  if (!(s > 0)) return;
  for (std::size_t k = 0; k < x.size(); ++k)
    if (n * std::erfc(std::abs(x[k] - mean) / (s * std::numbers::sqrt2)) < 0.5) keep[k] = false;
}

// Kapucu & Baysec: triples + Chauvenet per sweep, then the DH table from the axes.
RobotModel their_method(const RobotModel& template_model, const model::Dataset& d) {
  // Their world coordinates are the camera's through an exact hand-eye transform here; circles,
  // lines and the DH construction do not depend on the frame they are computed in, so the
  // camera frame is used throughout and frame 0 comes from the template's (exact) world frame.
  std::vector<model::AxisLine> axes;
  for (int j = 0; j < 3; ++j) {
    std::vector<Vector3> p;
    for (int k = 0; k < 10; ++k) p.push_back(d.rows[static_cast<std::size_t>(10 * j + k)].position);
    const bool revolute = template_model.joints[static_cast<std::size_t>(j)].type == core::JointType::revolute;
    std::vector<Vector3> centres, normals, directions;
    std::vector<double> radii;
    for (int a = 0; a < 10; ++a)
      for (int b = a + 1; b < 10; ++b)
        for (int c = b + 1; c < 10; ++c) {
          const Vector3 &p1 = p[static_cast<std::size_t>(a)], &p2 = p[static_cast<std::size_t>(b)],
                        &p3 = p[static_cast<std::size_t>(c)];
          directions.push_back((p2 - p1).normalized());
          // Circumcentre of the triangle.
          const Vector3 u = p2 - p1, v = p3 - p1, w = u.cross(v);
          const Vector3 centre =
              p1 + (v.squaredNorm() * w.cross(u) + u.squaredNorm() * v.cross(w)) / (2 * w.squaredNorm());
          centres.push_back(centre);
          radii.push_back((centre - p1).norm());
          normals.push_back(w.normalized());  // points ordered by reading: positive rotation
        }
    std::vector<bool> keep(centres.size(), true);
    for (int i = 0; i < 3; ++i) {
      std::vector<double> x;
      for (std::size_t k = 0; k < centres.size(); ++k) x.push_back(revolute ? centres[k](i) : directions[k](i));
      chauvenet(x, keep);
    }
    if (revolute) chauvenet(radii, keep);
    Vector3 centre = Vector3::Zero(), normal = Vector3::Zero(), direction = Vector3::Zero(), mean = Vector3::Zero();
    int kept = 0;
    for (std::size_t k = 0; k < centres.size(); ++k) {
      if (!keep[k]) continue;
      centre += centres[k];
      normal += normals[k];
      direction += directions[k];
      ++kept;
    }
    for (const Vector3& x : p) mean += x / 10.0;
    model::AxisLine axis;
    axis.type = revolute ? core::JointType::revolute : core::JointType::prismatic;
    axis.point = revolute ? Vector3(centre / kept) : mean;
    axis.direction = revolute ? normal.normalized() : direction.normalized();
    axes.push_back(axis);
  }
  // The beacon at home: the first reading of the prismatic sweep moved along its axis to home.
  const model::Measurement& first = d.rows[20];
  model::Transform tool_home;
  tool_home.translation = first.position + (kHome[2] - first.q[2]) * axes[2].direction;
  return model::chain_from_axes(template_model, axes, kHome, tool_home);
}

// Worst error of the DH lengths a1, d1, a2, d2 against the truth, both written as DH on their
// axes at home with the truth's world frame as frame 0.
double worst_dh_length_error(const RobotModel& m, const RobotModel& truth) {
  const RobotModel a =
      model::chain_from_axes(truth, model::joint_axes(m, kHome), kHome, model::forward_kinematics(m, kHome));
  const RobotModel b =
      model::chain_from_axes(truth, model::joint_axes(truth, kHome), kHome, model::forward_kinematics(truth, kHome));
  double worst = 0;
  for (std::size_t i = 0; i < 2; ++i) {
    worst = std::max(worst, std::abs(a.joints[i].parameters.a_m - b.joints[i].parameters.a_m));
    const bool rev = a.joints[i].type == core::JointType::revolute;
    const double da = a.joints[i].parameters.d_m + (rev ? 0 : a.joints[i].offset);
    const double db = b.joints[i].parameters.d_m + (rev ? 0 : b.joints[i].offset);
    worst = std::max(worst, std::abs(da - db));
  }
  return worst;
}

}  // namespace

int main() {
  const RobotModel truth = model::load_model(std::string(KINCAL_ROBOTS_DIR) + "/stanford_rrp.yaml");
  const auto qs = sweep_configurations();
  // The template handed to every method: the nominal table off by 2 cm / 2 deg (their method and
  // cpa take only conventions and free choices from it).
  sim::ErrorScale rough;
  rough.length_m = 0.02;
  rough.angle_rad = 2 * kDeg;
  rough.base_length_m = 0.0;
  rough.base_angle_rad = 0.0;
  const double paper_worst_m = 1.2700 - 1.2071;

  // Stereo noise such that their method's median worst DH length error matches the paper's.
  const int calibration_seeds = 31;
  const auto their_median = [&](double sigma_px) {
    std::vector<double> e;
    for (int s = 0; s < calibration_seeds; ++s) {
      std::mt19937_64 rng(500u + static_cast<unsigned>(s));
      const RobotModel guess = sim::perturbed(truth, rng, rough);
      e.push_back(worst_dh_length_error(their_method(guess, measure(truth, qs, sigma_px, rng)), truth));
    }
    return identify::median(e);
  };
  double lo = 0.001, hi = 2.0;
  for (int i = 0; i < 40; ++i) {
    const double mid = std::sqrt(lo * hi);
    (their_median(mid) < paper_worst_m ? lo : hi) = mid;
  }
  const double sigma_px = std::sqrt(lo * hi);
  std::printf("stereo noise reproducing their Table 1 (median worst DH length error %.2f cm): %.4f px\n",
              their_median(sigma_px) * 100, sigma_px);
  std::printf("FIGURE kapucu_stereo_noise_px %.4f px\n", sigma_px);

  const int seeds = 50;
  double theirs2 = 0, cpa2 = 0, full2 = 0;
  std::vector<double> theirs_dh, cpa_dh, full_dh;
  int points = 0;
  for (int s = 0; s < seeds; ++s) {
    std::mt19937_64 rng(9000u + static_cast<unsigned>(s));
    const RobotModel guess = sim::perturbed(truth, rng, rough);
    const model::Dataset d = measure(truth, qs, sigma_px, rng);
    const RobotModel theirs = their_method(guess, d);
    identify::IdentifyOptions o;
    o.method = identify::Method::cpa;
    const RobotModel cpa = identify::identify(guess, d, o).model;
    o.method = identify::Method::full;
    o.start = identify::Start::cpa;
    const RobotModel full = identify::identify(guess, d, o).model;
    for (const auto& q : sim::random_configurations(truth, 100, rng)) {
      const Vector3 t = model::forward_kinematics(truth, q).translation;
      theirs2 += (model::forward_kinematics(theirs, q).translation - t).squaredNorm();
      cpa2 += (model::forward_kinematics(cpa, q).translation - t).squaredNorm();
      full2 += (model::forward_kinematics(full, q).translation - t).squaredNorm();
      ++points;
    }
    theirs_dh.push_back(worst_dh_length_error(theirs, truth));
    cpa_dh.push_back(worst_dh_length_error(cpa, truth));
    full_dh.push_back(worst_dh_length_error(full, truth));
  }
  const double n = static_cast<double>(points);
  const double theirs_rms = std::sqrt(theirs2 / n), cpa_rms = std::sqrt(cpa2 / n), full_rms = std::sqrt(full2 / n);
  std::printf("%d seeds, 30 readings each, 100 held-out configurations per seed\n", seeds);
  std::printf("FIGURE kapucu_theirs_prediction_rms_mm %.1f mm\n", theirs_rms * 1e3);
  std::printf("FIGURE kapucu_cpa_prediction_rms_mm %.1f mm\n", cpa_rms * 1e3);
  std::printf("FIGURE kapucu_full_prediction_rms_mm %.1f mm\n", full_rms * 1e3);
  std::printf("FIGURE kapucu_theirs_worst_dh_length_error_mm %.1f mm\n", identify::median(theirs_dh) * 1e3);
  std::printf("FIGURE kapucu_cpa_worst_dh_length_error_mm %.1f mm\n", identify::median(cpa_dh) * 1e3);
  std::printf("FIGURE kapucu_full_worst_dh_length_error_mm %.1f mm\n", identify::median(full_dh) * 1e3);
  std::printf("FIGURE kapucu_theirs_over_ours_cpa %.2f ratio\n", theirs_rms / cpa_rms);
  std::printf("FIGURE kapucu_theirs_over_ours_full %.2f ratio\n", theirs_rms / full_rms);
  return 0;
}

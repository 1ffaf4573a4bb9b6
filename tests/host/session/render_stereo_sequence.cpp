// A recorded stereo session, rendered by the simulator (issue #14): what a real stereo pair
// watching a real robot would leave on disk, for `kincal session --rig stereo --left --right`
// to read back through host/capture exactly as camera frames.
//
//   render_stereo_sequence --model FILE --out DIR [--seed S] [--sweeps N] [--validation N]
//                          [--scale F] [--radius M] [--k1 K] [--missing-right POSE] [--doubled-left POSE]
//                          [--occluded-right POSE] [--drop-right POSE] [--only POSE]
//
// The robot: the model with hidden errors (sim::SimulatedRobot, as host/demo's stereo rig draws
// them from the seed). The rig: Kapucu & Baysec's parallel pair (sim::StereoRigSpec) with its
// images scaled by --scale (the same cameras at a coarser pixel: focal lengths and principal
// points scaled with the image; both with radial distortion --k1), watching a crimson beacon of --radius: each colour
// frame is two renders, the red channel with the beacon bright, green and blue with it dark, on a grey background.
// Writes to DIR:
//   plan.csv, validation.csv   the single-joint sweeps (--sweeps readings per joint, about the
//                              middle of the limits) and --validation random poses in view
//   left/NNN.png, right/NNN.png one pair per pose, the plan's poses then the validation's
//   stereo.yaml                the pair as `kincal camera stereo` writes it (left camera frame)
//   nominal.yaml, truth.yaml   the model and the simulator's truth, their base placed in the
//                              left camera's frame (the frame a real stereo session measures in)
//   beacon.png, scene.png      colour samples for `kincal colour-table`: the beacon's pixels
//                              (its disc, rim included) in the first left frames, and the rows
//                              of the first left frame away from the beacon
// Hostile variants change one pose: the beacon missing from the right frame, doubled in the
// left (a second lamp 0.2 m beside it), 70 % hidden in the right, or the right frame not
// written at all (the two cameras' counts then differ); with --only, only that pose's frames
// are written (a hostile copy of a recording made without it).
// Exit status 0, or 1 with a message.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "host/camera/calibration_file.hpp"
#include "host/model/model_file.hpp"
#include "host/session/pose_plan.hpp"
#include "host/sim/beacon.hpp"
#include "host/sim/robot.hpp"

namespace {

using namespace kincal;
namespace fs = std::filesystem;

struct Options {
  std::string model, out;
  std::uint64_t seed = 1;
  int sweeps = 8, validation = 6;
  double scale = 1, radius_m = 0.03, k1 = 0;
  int missing_right = -1, doubled_left = -1, occluded_right = -1, drop_right = -1;
  int only = -1;  // render this pose's frames only (a hostile copy of a recording)
};

// The left camera's OpenCV frame in the device frame (sim/beacon.hpp: the device frame is the
// right camera's turned half a turn about z, y up; the right camera sits one baseline along the
// left camera's x).
model::Transform device_T_left(const sim::StereoRigSpec& spec) {
  model::Transform device_T_right, right_T_left;
  device_T_right.rotation = Eigen::AngleAxisd(std::numbers::pi, model::Vector3::UnitZ()).toRotationMatrix();
  right_T_left.translation = model::Vector3(-spec.baseline_m, 0, 0);
  return device_T_right * right_T_left;
}

// Whether both cameras see the beacon at device point p, 10 % of the image in from the edges.
bool in_view(const sim::StereoRigSpec& spec, const model::Vector3& p) {
  const model::Vector3 left = device_T_left(spec).inverse() * p;
  const model::Vector3 right = left - model::Vector3(spec.baseline_m, 0, 0);
  for (const model::Vector3& c : {left, right}) {
    if (c.z() < 1.0) return false;
    const double u = spec.camera.cx_px + spec.camera.fx_px * c.x() / c.z();
    const double v = spec.camera.cy_px + spec.camera.fy_px * c.y() / c.z();
    const double mu = 0.1 * spec.camera.width_px, mv = 0.1 * spec.camera.height_px;
    if (u < mu || v < mv || u > spec.camera.width_px - mu || v > spec.camera.height_px - mv) return false;
  }
  return true;
}

void write_plan(const std::string& path, const session::Configurations& poses) {
  std::ofstream out(path);
  for (std::size_t j = 0; j < poses.front().size(); ++j) out << (j ? "," : "") << "q" << j + 1;
  out << "\n";
  out.precision(17);
  for (const std::vector<double>& q : poses) {
    for (std::size_t j = 0; j < q.size(); ++j) out << (j ? "," : "") << q[j];
    out << "\n";
  }
}

camera::StereoCalibration calibration_of(const sim::StereoRigSpec& spec) {
  camera::StereoCalibration c;
  camera::CameraModel cam;
  cam.image_size = cv::Size(spec.camera.width_px, spec.camera.height_px);
  cam.camera_matrix =
      cv::Matx33d(spec.camera.fx_px, 0, spec.camera.cx_px, 0, spec.camera.fy_px, spec.camera.cy_px, 0, 0, 1);
  cam.distortion = spec.camera.distortion;
  c.left = c.right = cam;
  c.right_R_left = cv::Matx33d::eye();
  c.right_t_left_m = cv::Vec3d(-spec.baseline_m, 0, 0);  // x_right = x_left - (b, 0, 0)
  c.baseline_m = spec.baseline_m;
  const cv::Vec3d& t = c.right_t_left_m;
  const cv::Matx33d t_cross(0, -t[2], t[1], t[2], 0, -t[0], -t[1], t[0], 0);
  c.essential = t_cross * c.right_R_left;
  c.fundamental = cam.camera_matrix.inv().t() * c.essential * cam.camera_matrix.inv();
  cv::Mat r1, r2, p1, p2, q;
  cv::stereoRectify(cam.camera_matrix, cam.distortion_mat(), cam.camera_matrix, cam.distortion_mat(), cam.image_size,
                    c.right_R_left, c.right_t_left_m, r1, r2, p1, p2, q, cv::CALIB_ZERO_DISPARITY, 0);
  c.rectify_left = cv::Matx33d(r1);
  c.rectify_right = cv::Matx33d(r2);
  c.projection_left = cv::Matx34d(p1);
  c.projection_right = cv::Matx34d(p2);
  c.disparity_to_depth = cv::Matx44d(q);
  return c;
}

// The model with its base placed in the left camera's frame.
model::RobotModel in_left_frame(model::RobotModel m, const model::Transform& device_T_left_camera) {
  m.base_T_frame0 = device_T_left_camera.inverse() * m.base_T_frame0;
  return m;
}

int run(const Options& o) {
  const model::RobotModel file = model::load_model(o.model);
  const sim::SimulatedRobot robot(file, o.seed, {}, sim::typical_imperfections(sim::reach_m(file)));
  sim::StereoRigSpec spec;
  spec.camera.width_px = static_cast<int>(std::lround(spec.camera.width_px * o.scale));
  spec.camera.height_px = static_cast<int>(std::lround(spec.camera.height_px * o.scale));
  spec.camera.fx_px *= o.scale;
  spec.camera.fy_px *= o.scale;
  spec.camera.cx_px = (spec.camera.cx_px + 0.5) * o.scale - 0.5;
  spec.camera.cy_px = (spec.camera.cy_px + 0.5) * o.scale - 0.5;
  spec.camera.distortion[0] = o.k1;

  std::vector<double> home;
  for (const model::Joint& j : file.joints) home.push_back((j.lower + j.upper) / 2);
  session::Configurations plan = session::single_joint_sweeps(file, home, o.sweeps, 0.4);
  session::Configurations validation;
  std::mt19937_64 rng(o.seed + 1000);
  for (int tries = 0; tries < 100000 && static_cast<int>(validation.size()) < o.validation; ++tries) {
    std::vector<double> q = sim::random_configuration(file, rng);
    if (in_view(spec, model::forward_kinematics(file, q).translation)) validation.push_back(std::move(q));
  }
  if (static_cast<int>(validation.size()) < o.validation) throw std::runtime_error("too few poses in view");

  fs::create_directories(o.out + "/left");
  fs::create_directories(o.out + "/right");
  write_plan(o.out + "/plan.csv", plan);
  write_plan(o.out + "/validation.csv", validation);
  camera::save_stereo(o.out + "/stereo.yaml", calibration_of(spec));
  model::save_model(in_left_frame(file, device_T_left(spec)), o.out + "/nominal.yaml");
  model::save_model(in_left_frame(robot.truth(), device_T_left(spec)), o.out + "/truth.yaml");

  session::Configurations all = plan;
  all.insert(all.end(), validation.begin(), validation.end());
  std::vector<cv::Mat> samples;
  for (std::size_t i = 0; i < all.size(); ++i) {
    const int pose = static_cast<int>(i);
    if (o.only >= 0 && pose != o.only) continue;
    const model::Vector3 p = robot.visit_pose(all[i], i).translation;
    if (!in_view(spec, p)) throw std::runtime_error("pose " + std::to_string(i) + " is out of view");
    const std::uint64_t seed = o.seed * 1000003 + i;
    sim::ImagingConditions conditions;
    conditions.supersampling = 2;
    conditions.seed = seed;
    sim::StereoFrame frames = sim::render_colour_beacon(spec, o.radius_m, p, conditions);
    if (pose == o.missing_right) frames.right = sim::render_colour_beacon(spec, o.radius_m, p, conditions, false).right;
    if (pose == o.doubled_left) {
      sim::ImagingConditions second_conditions = conditions;
      ++second_conditions.seed;
      const sim::StereoFrame second =
          sim::render_colour_beacon(spec, o.radius_m, p + model::Vector3(0.2, 0, 0), second_conditions);
      // Each pixel from the render in which it is redder: both discs, one background.
      for (int y = 0; y < frames.left.rows; ++y)
        for (int x = 0; x < frames.left.cols; ++x) {
          const cv::Vec3b a = frames.left.at<cv::Vec3b>(y, x), b = second.left.at<cv::Vec3b>(y, x);
          if (b[2] - b[1] > a[2] - a[1]) frames.left.at<cv::Vec3b>(y, x) = b;
        }
    }
    if (pose == o.occluded_right) {
      // An edge in front of the right camera hides all but the beacon's left 30 %.
      const double r_px = spec.camera.fx_px * o.radius_m / p.z() * 1.5;
      const cv::Vec3b background = frames.right.at<cv::Vec3b>(0, 0);
      const int x0 = static_cast<int>(std::floor(frames.right_px.x - 0.4 * r_px / 1.5));
      const int y0 = static_cast<int>(std::floor(frames.right_px.y - r_px)),
                y1 = static_cast<int>(std::ceil(frames.right_px.y + r_px));
      frames.right(cv::Rect(x0, y0, frames.right.cols - x0, y1 - y0 + 1)).setTo(background);
    }
    char name[32];
    std::snprintf(name, sizeof name, "/%03d.png", pose);
    cv::imwrite(o.out + "/left" + name, frames.left);
    if (pose != o.drop_right)
      cv::imwrite(o.out + "/right" + name, frames.right);
    else
      fs::remove(o.out + "/right" + name);
    if (samples.size() < 8 * 64) {
      // The beacon's pixels with their anti-aliased rim: within the disc's radius of its centre.
      const double r_px = spec.camera.fx_px * o.radius_m / p.z();
      const int reach = static_cast<int>(std::ceil(r_px));
      for (int y = -reach; y <= reach; ++y)
        for (int x = -reach; x <= reach; ++x)
          if (std::hypot(x + std::round(frames.left_px.x) - frames.left_px.x,
                         y + std::round(frames.left_px.y) - frames.left_px.y) <= r_px)
            samples.push_back(cv::Mat(1, 1, CV_8UC3,
                                      frames.left.at<cv::Vec3b>(static_cast<int>(std::lround(frames.left_px.y)) + y,
                                                                static_cast<int>(std::lround(frames.left_px.x)) + x))
                                  .clone());
    }
    if (i == 0) {
      // The scene: every row of the frame farther than three beacon radii from the beacon.
      const double band_px = 3 * spec.camera.fy_px * o.radius_m / p.z();
      std::vector<cv::Mat> rows;
      for (int y = 0; y < frames.left.rows; ++y)
        if (std::abs(y - frames.left_px.y) > band_px) rows.push_back(frames.left.row(y));
      cv::Mat scene;
      cv::vconcat(rows, scene);
      cv::imwrite(o.out + "/scene.png", scene);
    }
  }
  if (o.only >= 0) return 0;
  cv::Mat beacon;
  cv::hconcat(samples, beacon);
  cv::imwrite(o.out + "/beacon.png", beacon);
  std::cout << "rendered " << all.size() << " stereo pairs (" << plan.size() << " plan, " << validation.size()
            << " validation) of " << spec.camera.width_px << "x" << spec.camera.height_px << " px to " << o.out << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app("Render a recorded stereo session of a simulated robot");
  app.add_option("--model", o.model)->required();
  app.add_option("--out", o.out)->required();
  app.add_option("--seed", o.seed);
  app.add_option("--sweeps", o.sweeps);
  app.add_option("--validation", o.validation);
  app.add_option("--scale", o.scale);
  app.add_option("--radius", o.radius_m);
  app.add_option("--k1", o.k1);
  app.add_option("--missing-right", o.missing_right);
  app.add_option("--doubled-left", o.doubled_left);
  app.add_option("--occluded-right", o.occluded_right);
  app.add_option("--drop-right", o.drop_right);
  app.add_option("--only", o.only);
  CLI11_PARSE(app, argc, argv);
  try {
    return run(o);
  } catch (const std::exception& e) {
    std::cerr << "render_stereo_sequence: " << e.what() << "\n";
    return 1;
  }
}

// Issue #43: poses from a motion capture (timed poses at their own rate, interpolated at each
// image's time) and kincal's AprilGrid corners on real photographs against a second detector's
// (the shared aprilgrid-d435i-mocap set; its case is registered only where the set is).
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "host/camera/board.hpp"
#include "host/camera/robot_poses.hpp"
#include "tests/host/camera/error_text.hpp"

using namespace kincal::camera;

namespace {

Eigen::Isometry3d pose(double angle_rad, const Eigen::Vector3d& axis, const Eigen::Vector3d& t_m) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix();
  p.translation() = t_m;
  return p;
}

// A Vicon-style row: timestamp [ns],x,y,z,qx,qy,qz,qw.
std::string row(long long t_ns, const Eigen::Isometry3d& p) {
  const Eigen::Quaterniond q(p.linear());
  std::ostringstream out;
  out.precision(17);
  out << t_ns << ',' << p.translation().x() << ',' << p.translation().y() << ',' << p.translation().z() << ',' << q.x()
      << ',' << q.y() << ',' << q.z() << ',' << q.w() << "\n";
  return out.str();
}

std::vector<RobotPose> timed(const std::string& text) {
  std::istringstream in(text);
  return parse_timed_poses(in, "mocap.csv", RotationColumns::kUnnamed);
}

}  // namespace

TEST_CASE("timed poses: a motion capture's file is read with its times, and poses are interpolated at an image's") {
  // Three poses 50 ms apart (20 Hz), turning about a fixed axis at a constant rate and moving
  // along a line, so the pose at any time between them is known exactly.
  const Eigen::Vector3d axis(1, -2, 0.5), start(0.5, 1.0, 0.9), velocity_m_per_s(0.4, -0.2, 0.1);
  const double rate_rad_per_s = 2.0;
  const long long t0 = 1606153863362296104LL, period = 50'000'000;
  const auto truth = [&](double s) { return pose(0.3 + rate_rad_per_s * s, axis, start + s * velocity_m_per_s); };
  const std::string text = "timestamp [ns],x,y,z,qx,qy,qz,qw\n" + row(t0, truth(0)) + row(t0 + period, truth(0.05)) +
                           row(t0 + 2 * period, truth(0.1));
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "kincal_mocap_poses_test.csv";
  std::ofstream(file) << text;
  const std::vector<RobotPose> poses = read_timed_poses(file.string(), RotationColumns::kUnnamed);
  std::filesystem::remove(file);
  REQUIRE(poses.size() == 3);
  CHECK(*poses[1].time_ns == t0 + period);
  CHECK(poses[2].line == 4);

  for (const double s : {0.0, 0.0123, 0.05, 0.0731, 0.1}) {
    const long long t = t0 + std::llround(s * 1e9);
    const PoseAtTime p = pose_at_time(poses, t);
    REQUIRE_MESSAGE(p.pose, p.refusal);
    CHECK((p.pose->translation() - truth(s).translation()).norm() < 1e-9);
    CHECK(Eigen::AngleAxisd(p.pose->linear().transpose() * truth(s).linear()).angle() < 1e-9);
  }
  const PoseAtTime between = pose_at_time(poses, t0 + 70'000'000);
  CHECK(between.line_before == 3);
  CHECK(between.line_after == 4);

  // Outside the poses' span, or across a gap wider than allowed: no pose, and why.
  CHECK(contains(pose_at_time(poses, t0 - 1).refusal, "no pose before it: the poses run from 1606153863362296104"));
  CHECK(contains(pose_at_time(poses, t0 + 2 * period + 1).refusal, "no pose after it"));
  CHECK(contains(pose_at_time(poses, t0 + 10, 0.04).refusal,
                 "the poses around it (lines 2 and 3) are 0.05 s apart, more than 0.04 s"));

  // Seconds, as a column named so; the other time-column spellings.
  const std::vector<RobotPose> in_seconds =
      timed("x,y,z,qw,qx,qy,qz,time_s\n0,0,0,1,0,0,0,12.5\n0,0,0,1,0,0,0,12.500000001\n");
  CHECK(*in_seconds[0].time_ns == 12'500'000'000LL);
  CHECK(*in_seconds[1].time_ns == 12'500'000'001LL);
  CHECK(*timed("t_ns,x,y,z,qw,qx,qy,qz\n5,0,0,0,1,0,0,0\n")[0].time_ns == 5);
  CHECK(*timed("stamp[s];x;y;z;qw;qx;qy;qz\n2;0;0;0;1;0;0;0\n")[0].time_ns == 2'000'000'000LL);

  // A turn the short way: quaternions of opposite sign on either side are the same rotation.
  std::string flipped = "timestamp [ns],x,y,z,qx,qy,qz,qw\n0,0,0,0,0,0,0.0499791692,0.9987502604\n";
  flipped += "100,0,0,0,0,0,-0.0499791692,-0.9987502604\n";
  const PoseAtTime same = pose_at_time(timed(flipped), 50);
  REQUIRE(same.pose);
  CHECK(Eigen::AngleAxisd(same.pose->linear()).angle() == doctest::Approx(0.1).epsilon(1e-6));
}

TEST_CASE("timed poses: files without times or with times that go back are refused by line") {
  const auto refused = [](const std::string& text) { return error_of([&] { (void)timed(text); }); };
  CHECK(contains(refused("x,y,z,qw,qx,qy,qz\n0,0,0,1,0,0,0\n"),
                 "mocap.csv:2: the poses have no time column: name one in the header, e.g. timestamp [ns]"));
  // A plain "time" says no unit: not a time column (and files with one read as before).
  CHECK(contains(refused("time,x,y,z,qw,qx,qy,qz\n7,0,0,0,1,0,0,0\n"), "the poses have no time column"));
  CHECK(contains(refused("timestamp [ns],x,y,z,qw,qx,qy,qz\n10,0,0,0,1,0,0,0\n10,0,0,0,1,0,0,0\n"),
                 "mocap.csv:3: time 10 ns is not after the previous pose's (line 2, 10 ns)"));
  CHECK(contains(refused("timestamp [ns],x,y,z,qw,qx,qy,qz\n1.5e9,0,0,0,1,0,0,0\n"),
                 "mocap.csv:2: time '1.5e9' is not a whole number of nanoseconds"));
  CHECK(contains(refused("timestamp [ns],time_s,x,y,z,qw,qx,qy,qz\n1,1,0,0,0,1,0,0,0\n"),
                 "mocap.csv:1: the header names two time columns, timestamp [ns] and time_s"));
  // The untimed reader still reads such a file, one pose a row, its times kept.
  std::istringstream in("timestamp [ns],x,y,z,qx,qy,qz,qw\n1,0.1,0,0,0,0,0,1\n");
  const std::vector<RobotPose> untimed = parse_robot_poses(in, "mocap.csv", RotationColumns::kUnnamed);
  REQUIRE(untimed.size() == 1);
  CHECK(*untimed[0].time_ns == 1);
}

TEST_CASE("timed poses: an image's time from its file name") {
  CHECK(image_time_ns("/data/cam0/data/1606153907495166540.jpg") == 1606153907495166540LL);
  CHECK(image_time_ns("1606153907.495166540.png") == 1606153907495166540LL);
  CHECK(image_time_ns("frames/12.5.png") == 12'500'000'000LL);
  CHECK_FALSE(image_time_ns("left01.jpg"));
  CHECK_FALSE(image_time_ns("12.5e3.png"));
  CHECK_FALSE(image_time_ns("99999999999999999999.png"));  // beyond 64 bits of nanoseconds
  CHECK_FALSE(image_time_ns("1.1234567891.png"));          // finer than a nanosecond
}

#ifdef KINCAL_APRILGRID_SET
// A few views of the shared set (not slow: detection is about 0.2 s a view): kincal's corners
// against yac's, matched by tag id and corner index (host/camera/board.hpp's numbering; yac's
// corner_idx is Kalibr's lower left, lower right, upper right, upper left). Both refine with
// cv::cornerSubPix, so both put (0, 0) at the centre of the top-left pixel. Measured on all 30
// views by tests/bench/aprilgrid_real_bench.cpp: see the README's benchmarks table.
TEST_CASE("AprilGrid on real photographs: kincal's corners lie on a second detector's (yac's)") {
  // Measured on these three views: RMS 0.57 px, largest 4.5 px (a blurred corner where the two
  // refinement windows settle apart), mean offset under 0.1 px; kincal found 116 of the 140
  // corners yac found in one view (0.83), all in the others. A half-pixel convention or a corner
  // order error would move the mean by 0.5 px or the RMS by tens of pixels.
  constexpr double kRmsTolerance_px = 0.8, kLargestTolerance_px = 6.0, kMeanOffsetTolerance_px = 0.2;
  constexpr double kFewestCornersOverReference = 0.8;
  const std::string set = KINCAL_APRILGRID_SET;
  const Board board = parse_board("aprilgrid:6x6:0.088:0.3");
  int matched = 0;
  double sum_sq = 0, largest = 0, sum_dx = 0, sum_dy = 0;
  for (const char* stamp : {"1606153907495166540", "1606154004360154629", "1606154117645546675"}) {
    const std::string image = set + "/cam0/data/" + stamp + ".jpg";
    const BoardDetection d = detect_board(board, cv::imread(image, cv::IMREAD_GRAYSCALE), image);
    REQUIRE_MESSAGE(d.found, d.reason);
    std::map<int, cv::Point2f> ours;
    for (std::size_t k = 0; k < d.ids.size(); ++k) ours[d.ids[k]] = d.image_px[k];
    std::ifstream yac(set + "/grid0/cam0/data/" + stamp + ".csv");
    std::string line;
    std::getline(yac, line);
    int theirs = 0;
    while (std::getline(yac, line)) {
      std::vector<std::string> f;
      std::stringstream s(line);
      for (std::string field; std::getline(s, field, ',');) f.push_back(field);
      REQUIRE(f.size() == 12);
      ++theirs;
      const int tag = std::stoi(f[10]), corner = std::stoi(f[11]);
      const int b = (tag / 6) * 24 + (tag % 6) * 2;
      const int id = corner == 0 ? b : corner == 1 ? b + 1 : corner == 2 ? b + 13 : b + 12;
      const auto it = ours.find(id);
      if (it == ours.end()) continue;
      const double dx = static_cast<double>(it->second.x) - std::stod(f[5]);
      const double dy = static_cast<double>(it->second.y) - std::stod(f[6]);
      sum_sq += dx * dx + dy * dy;
      sum_dx += dx;
      sum_dy += dy;
      largest = std::max(largest, std::hypot(dx, dy));
      ++matched;
    }
    CAPTURE(stamp);
    CHECK(static_cast<double>(d.ids.size()) >= kFewestCornersOverReference * theirs);
  }
  REQUIRE(matched > 200);
  const double rms = std::sqrt(sum_sq / matched);
  MESSAGE("corners against yac's: RMS ", rms, " px, largest ", largest, " px over ", matched);
  CHECK(rms < kRmsTolerance_px);
  CHECK(largest < kLargestTolerance_px);
  CHECK(std::abs(sum_dx / matched) < kMeanOffsetTolerance_px);
  CHECK(std::abs(sum_dy / matched) < kMeanOffsetTolerance_px);
}
#endif

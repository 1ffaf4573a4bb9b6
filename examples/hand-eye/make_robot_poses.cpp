// Writes robot_poses.csv: the gripper poses (base_T_gripper, OpenCV's "gripper2base") under which a
// camera mounted on the gripper at GRIPPER_T_CAMERA would have taken OpenCV's sample photographs
// left01.jpg ... left14.jpg of a board standing still at BASE_T_TARGET. Synthetic: no robot
// moved; the poses exist so that `kincal camera hand-eye` can be run on real photographs and must
// find GRIPPER_T_CAMERA again.
//
// Each view's board pose is found as kincal finds it (host/camera/board.cpp: the chessboard
// detectors, corner 0 next to the dark far-corner square; cv::solvePnP with the camera file),
// then base_T_gripper = base_T_target * inverse(camera_T_target) * inverse(gripper_T_camera).
//
//   g++ -std=c++20 -O1 -Wno-deprecated-enum-enum-conversion make_robot_poses.cpp -o make_robot_poses $(pkg-config
//   --cflags --libs opencv4)
//   ./make_robot_poses camera.yaml /usr/share/doc/opencv-doc/examples/data/left0?.jpg \
//       /usr/share/doc/opencv-doc/examples/data/left1?.jpg > robot_poses.csv
// with camera.yaml from `kincal camera calibrate --board chessboard:9x6:0.025` of the same images.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/quaternion.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace {

const int kCols = 9, kRows = 6;
const double kSquareM = 0.025;

cv::Matx44d transform(const cv::Matx33d& r, const cv::Vec3d& t) {
  cv::Matx44d m = cv::Matx44d::eye();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m(i, j) = r(i, j);
    m(i, 3) = t[i];
  }
  return m;
}

cv::Matx44d inverse(const cv::Matx44d& m) {
  const cv::Matx33d r(m(0, 0), m(0, 1), m(0, 2), m(1, 0), m(1, 1), m(1, 2), m(2, 0), m(2, 1), m(2, 2));
  const cv::Vec3d t(m(0, 3), m(1, 3), m(2, 3));
  return transform(r.t(), -(r.t() * t));
}

cv::Matx33d rpy_deg(double roll, double pitch, double yaw) {
  const double k = CV_PI / 180;
  const double cr = std::cos(roll * k), sr = std::sin(roll * k), cp = std::cos(pitch * k), sp = std::sin(pitch * k);
  const double cy = std::cos(yaw * k), sy = std::sin(yaw * k);
  const cv::Matx33d rx(1, 0, 0, 0, cr, -sr, 0, sr, cr), ry(cp, 0, sp, 0, 1, 0, -sp, 0, cp),
      rz(cy, -sy, 0, sy, cy, 0, 0, 0, 1);
  return rz * ry * rx;
}

double mean_near(const cv::Mat& grey, cv::Point2f centre, float radius_px) {
  const int r = std::max(1, static_cast<int>(radius_px));
  const cv::Rect window(static_cast<int>(std::lround(centre.x)) - r, static_cast<int>(std::lround(centre.y)) - r,
                        2 * r + 1, 2 * r + 1);
  const cv::Rect clipped = window & cv::Rect(0, 0, grey.cols, grey.rows);
  return clipped.area() > 0 ? cv::mean(grey(clipped))[0] : 128.0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: make_robot_poses camera.yaml IMAGE...\n");
    return 2;
  }
  cv::FileStorage fs(argv[1], cv::FileStorage::READ);
  cv::Mat k, dist;
  fs["camera_matrix"] >> k;
  fs["distortion_coefficients"] >> dist;
  if (k.empty()) {
    std::fprintf(stderr, "%s: no camera_matrix\n", argv[1]);
    return 1;
  }
  // The camera 120 mm out along the flange's z, 50 mm and -30 mm off its axis, turned 90 deg about z.
  const cv::Matx44d gripper_T_camera = transform(rpy_deg(0, 0, 90), {0.05, -0.03, 0.12});
  // The board 700 mm in front of the base, 50 mm up, face up.
  const cv::Matx44d base_T_target = transform(rpy_deg(180, 0, 0), {0.7, 0.0, 0.05});
  std::vector<cv::Point3f> board;
  for (int id = 0; id < kCols * kRows; ++id)
    board.emplace_back(static_cast<float>((id % kCols) * kSquareM), static_cast<float>((id / kCols) * kSquareM), 0.0f);

  std::printf("q1,q2,q3,q4,q5,q6,x,y,z,qw,qx,qy,qz\n");
  for (int i = 2; i < argc; ++i) {
    const cv::Mat grey = cv::imread(argv[i], cv::IMREAD_GRAYSCALE);
    std::vector<cv::Point2f> corners;
    const cv::Size pattern(kCols, kRows);
    bool found = !grey.empty() && cv::findChessboardCornersSB(grey, pattern, corners, cv::CALIB_CB_NORMALIZE_IMAGE);
    if (!found && !grey.empty()) {
      found = cv::findChessboardCorners(grey, pattern, corners,
                                        cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
      if (found)
        cv::cornerSubPix(grey, corners, cv::Size(5, 5), cv::Size(-1, -1),
                         cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-3));
    }
    if (!found) {
      std::fprintf(stderr, "%s: board not found\n", argv[i]);
      return 1;
    }
    const std::size_t n = corners.size(), cols = kCols;
    const cv::Point2f c0 = corners[0], c_last = corners[n - 1];
    const cv::Point2f outside_first = c0 - 0.5f * (corners[1] - c0) - 0.5f * (corners[cols] - c0);
    const cv::Point2f outside_last =
        c_last + 0.5f * (c_last - corners[n - 2]) + 0.5f * (c_last - corners[n - 1 - cols]);
    const float radius = 0.15f * static_cast<float>(cv::norm(corners[1] - c0));
    if (mean_near(grey, outside_first, radius) > mean_near(grey, outside_last, radius))
      std::reverse(corners.begin(), corners.end());
    cv::Vec3d rvec, tvec;
    cv::solvePnP(board, corners, k, dist, rvec, tvec);
    cv::Matx33d r;
    cv::Rodrigues(rvec, r);
    const cv::Matx44d base_T_gripper = base_T_target * inverse(transform(r, tvec)) * inverse(gripper_T_camera);
    const cv::Matx33d rg(base_T_gripper(0, 0), base_T_gripper(0, 1), base_T_gripper(0, 2), base_T_gripper(1, 0),
                         base_T_gripper(1, 1), base_T_gripper(1, 2), base_T_gripper(2, 0), base_T_gripper(2, 1),
                         base_T_gripper(2, 2));
    cv::Quatd q = cv::Quatd::createFromRotMat(rg);
    if (q.w < 0) q = -q;
    std::printf("0,0,0,0,0,0,%.9f,%.9f,%.9f,%.12f,%.12f,%.12f,%.12f\n", base_T_gripper(0, 3), base_T_gripper(1, 3),
                base_T_gripper(2, 3), q.w, q.x, q.y, q.z);
  }
  return 0;
}

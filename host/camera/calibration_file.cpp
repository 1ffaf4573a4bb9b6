#include "host/camera/calibration_file.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <yaml-cpp/yaml.h>
#include <opencv2/core/eigen.hpp>

#include "host/files/input_file.hpp"
#include "host/files/input_limits.hpp"
#include "host/files/output_file.hpp"
#include "host/files/yaml_limits.hpp"
#include "host/model/number_text.hpp"

namespace kincal::camera {

namespace {

// The projection-uncertainty grid in camera files: coarse, a cell about 40 px wide at VGA.
constexpr int kProjectionGridCols = 16, kProjectionGridRows = 12;

// The file's text through the input layer (a regular file within kSettingsFile's limit, UTF-8).
std::string read_camera_text(const std::string& path) {
  std::string text = files::read_text_or_throw<CalibrationError>(path, files::kSettingsFile);
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) throw CalibrationError(path + ": empty file");
  return text;
}

cv::FileStorage open_for_reading(const std::string& path, const std::string& text) {
  // OpenCV's parser keeps the first of a key given twice and fails on a second document in its own
  // words: the YAML limits name both, and the node count (the "%YAML:1.0" line, which yaml-cpp
  // refuses, blanked first). What yaml-cpp cannot parse is left to OpenCV's parser.
  try {
    std::string yaml = text;
    if (yaml.rfind("%YAML:", 0) == 0) yaml.erase(0, std::min(yaml.find('\n'), yaml.size()));
    files::check_yaml_text<CalibrationError>(yaml, path);
  } catch (const YAML::Exception&) {
  }
  cv::FileStorage fs;
  try {
    fs.open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  } catch (const std::exception& e) {  // cv::Exception, and std::length_error from OpenCV 4.6's parser
    throw CalibrationError(path + ": not an OpenCV YAML file (" + e.what() + ")");
  }
  if (!fs.isOpened()) throw CalibrationError(path + ": cannot read");
  // fs[key] asserts (cv::Exception) on a document that is not a map of keys.
  if (!fs.root().isMap()) throw CalibrationError(path + ": not an OpenCV YAML file of keys (its top is not a map)");
  return fs;
}

// The node as a rows x cols matrix (CV_64F), or an empty one when it is not one. The shape is
// checked before OpenCV reads the matrix: it allocates rows x cols as the file says (a damaged
// "cols:" became 2^31 and 64 GiB, found by fuzz.camera_inputs).
cv::Mat matrix_of_shape(const cv::FileNode& node, int rows, int cols) {
  const auto is = [&](const char* field, int value) {
    return node[field].isInt() && static_cast<int>(node[field]) == value;
  };
  const bool shaped = node.isMap() && is("rows", rows) && is("cols", cols) && node["data"].isSeq() &&
                      node["data"].size() == static_cast<std::size_t>(rows * cols);
  cv::Mat m;
  try {
    if (shaped) node >> m;
  } catch (const std::exception&) {  // cv::Exception, and the std exceptions OpenCV's parser lets out
    m.release();
  }
  if (m.rows != rows || m.cols != cols) return {};
  m.convertTo(m, CV_64F);
  return m;
}

cv::Mat read_matrix(const cv::FileStorage& fs, const std::string& path, const std::string& key, int rows, int cols) {
  cv::Mat m = matrix_of_shape(fs[key], rows, cols);
  if (m.empty()) {
    throw CalibrationError(path + ": key '" + key + "' missing or not a " + std::to_string(rows) + "x" +
                           std::to_string(cols) + " matrix");
  }
  return m;
}

double read_number(const cv::FileStorage& fs, const std::string& path, const std::string& key) {
  const cv::FileNode node = fs[key];
  if (!node.isReal() && !node.isInt()) throw CalibrationError(path + ": key '" + key + "' missing or not a number");
  return static_cast<double>(node);
}

// A camera's image size as a file gives it: whole numbers of pixels, 1 to the image limit a side
// (files/input_limits.hpp; 1e300 was cast to int and named -2147483648 pixels).
cv::Size checked_size(const std::string& path, double w, double h) {
  if (!(w >= 1 && h >= 1 && w <= files::kMaxImageSide && h <= files::kMaxImageSide) || w != std::floor(w) ||
      h != std::floor(h)) {
    throw CalibrationError(path + ": image_width and image_height must be whole numbers of pixels, 1 to " +
                           std::to_string(files::kMaxImageSide));
  }
  return {static_cast<int>(w), static_cast<int>(h)};
}

cv::Size read_size(const cv::FileStorage& fs, const std::string& path) {
  return checked_size(path, read_number(fs, path, "image_width"), read_number(fs, path, "image_height"));
}

// Distortion as other tools write it. kincal's camera is plumb_bob's (k1 k2 p1 p2 k3); a file may
// give a row or a column (OpenCV's calibration sample writes 5x1) of 4 (k3 = 0), 5, 8 (k4 k5 k6:
// OpenCV's rational model, ROS's rational_polynomial), 12 (s1..s4) or 14 (tx ty) coefficients. It is
// the same lens when every term beyond k3 is 0; a term that is not is refused by name, as is a
// distortion_model other than plumb_bob or rational_polynomial (none given: plumb_bob, as ROS's
// camera_calibration_parsers read it).
constexpr std::array<const char*, 14> kDistortionNames = {"k1", "k2", "p1", "p2", "k3", "k4", "k5",
                                                          "k6", "s1", "s2", "s3", "s4", "tx", "ty"};

bool is_distortion_shape(int rows, int cols) {
  if (std::min(rows, cols) != 1) return false;  // before any product: a file's numbers may be any int
  const int n = std::max(rows, cols);
  return n == 4 || n == 5 || n == 8 || n == 12 || n == 14;
}

CalibrationError distortion_shape_error(const std::string& path, const std::string& key) {
  return CalibrationError(path + ": key '" + key + "' missing or not 4, 5, 8, 12 or 14 coefficients (1xN or Nx1)");
}

std::array<double, 5> plumb_bob_of(const cv::Mat& d, const std::string& model, const std::string& path,
                                   const std::string& key) {
  if (!model.empty() && model != "plumb_bob" && model != "rational_polynomial")
    throw CalibrationError(path + ": distortion_model '" + files::excerpt(model) +
                           "': kincal's camera is plumb_bob (k1 k2 p1 p2 k3); files of plumb_bob and of "
                           "rational_polynomial (its k4 k5 k6 0) are read");
  const int n = static_cast<int>(d.total());
  for (int i = 5; i < n; ++i)
    if (d.at<double>(i) != 0)
      throw CalibrationError(path + ": key '" + key + "': " + kDistortionNames[static_cast<std::size_t>(i)] + " = " +
                             model::shortest_number_text(d.at<double>(i)) +
                             ", not 0: kincal's camera is plumb_bob (k1 k2 p1 p2 k3), so a lens with the rational, "
                             "thin-prism or tilt terms is not read (calibrate it with kincal camera calibrate)");
  std::array<double, 5> out{};
  for (int i = 0; i < std::min(n, 5); ++i) out[static_cast<std::size_t>(i)] = d.at<double>(i);
  return out;
}

// The distortion of an OpenCV file (the key, and the file's distortion_model when it has one).
std::array<double, 5> read_distortion(const cv::FileStorage& fs, const std::string& path, const std::string& key) {
  const cv::FileNode node = fs[key];
  // node[field] asserts (cv::Exception) on a node that is not a map.
  const int rows = node.isMap() && node["rows"].isInt() ? static_cast<int>(node["rows"]) : 0;
  const int cols = node.isMap() && node["cols"].isInt() ? static_cast<int>(node["cols"]) : 0;
  const cv::Mat d = is_distortion_shape(rows, cols) ? matrix_of_shape(node, rows, cols) : cv::Mat();
  if (d.empty()) throw distortion_shape_error(path, key);
  const cv::FileNode model = fs["distortion_model"];
  if (!model.empty() && !model.isString())
    throw CalibrationError(path + ": key 'distortion_model' is not a name (plumb_bob)");
  return plumb_bob_of(d, model.empty() ? "" : static_cast<std::string>(model), path, key);
}

CameraModel camera_from(const cv::Mat& k, const std::array<double, 5>& distortion, cv::Size size) {
  CameraModel c;
  c.image_size = size;
  c.camera_matrix = cv::Matx33d(k);
  c.distortion = distortion;
  return c;
}

cv::Mat matrix_of(const Eigen::Isometry3d& m) {
  cv::Mat out;
  const Eigen::Matrix4d e = m.matrix();
  cv::eigen2cv(e, out);
  return out;
}

Eigen::Isometry3d isometry_of(const cv::Mat& m, const std::string& path, const std::string& key) {
  Eigen::Matrix4d e;
  cv::cv2eigen(m, e);
  const Eigen::Matrix3d r = e.topLeftCorner<3, 3>();
  if (!((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() < 1e-6) || !(r.determinant() > 0) ||
      !e.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1))) {
    throw CalibrationError(path + ": key '" + key + "' is not a rigid transform");
  }
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = r;
  out.translation() = e.topRightCorner<3, 1>();
  return out;
}

float to_float(double v, const char* name) {
  if (!std::isfinite(v) || std::abs(v) > static_cast<double>(std::numeric_limits<float>::max())) {
    throw CalibrationError(std::string("camera parameter ") + name + " = " + std::to_string(v) +
                           " does not fit the platform's float32");
  }
  return static_cast<float>(v);
}

std::uint16_t to_u16(int v, const char* name) {
  if (v <= 0 || v > 65535) {
    throw CalibrationError(std::string("camera ") + name + " " + std::to_string(v) + " px is outside 1..65535");
  }
  return static_cast<std::uint16_t>(v);
}

// Every calibration file is composed in memory and written whole (host/files/output_file.hpp).
void write_text(const std::string& path, const std::string& text) {
  try {
    files::write_file_atomically(path, text);
  } catch (const files::OutputError& e) {
    throw CalibrationError(e.what());
  }
}

void write_storage(cv::FileStorage& fs, const std::string& path) { write_text(path, fs.releaseAndGetString()); }

// A covariance read from a file (square CV_64F) and the corner sigma stored with it.
void check_covariance(const cv::Mat& covariance, double corner_sigma_px, const std::string& path,
                      const std::string& key) {
  bool valid = std::isfinite(corner_sigma_px) && corner_sigma_px >= 0;
  for (int i = 0; i < covariance.rows; ++i) {
    valid = valid && covariance.at<double>(i, i) >= 0;
    for (int j = 0; j < covariance.cols; ++j) {
      const double a = covariance.at<double>(i, j), b = covariance.at<double>(j, i);
      valid = valid && std::isfinite(a) && std::abs(a - b) <= 1e-9 * (std::abs(a) + std::abs(b));
    }
  }
  if (!valid) {
    throw CalibrationError(path + ": key '" + key +
                           "' is not a symmetric covariance with a non-negative diagonal, or corner_sigma_px is "
                           "negative");
  }
}

}  // namespace

void save_camera(const std::string& path, const IntrinsicCalibration& c, const std::string& board_text) {
  cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  fs << "image_width" << c.camera.image_size.width << "image_height" << c.camera.image_size.height;
  fs << "board" << board_text;
  fs << "nr_of_frames" << c.views_used;
  fs << "camera_matrix" << cv::Mat(c.camera.camera_matrix);
  fs << "distortion_coefficients" << c.camera.distortion_mat();
  fs << "avg_reprojection_error" << c.rms_px;
  std::vector<double> per_view;
  for (const ViewReport& v : c.views) {
    if (v.used) per_view.push_back(v.rms_px);
  }
  fs << "per_view_reprojection_errors" << cv::Mat(per_view, true);
  fs << "std_deviations_intrinsics" << cv::Mat(cv::Matx<double, 1, 9>(c.std_dev.data()));
  const ProjectionSigmaGrid grid =
      projection_sigma_grid(c.camera, c.uncertainty, kProjectionGridCols, kProjectionGridRows);
  fs << "intrinsics_covariance" << cv::Mat(c.uncertainty.covariance);
  fs << "intrinsics_covariance_order" << kIntrinsicsOrder;
  fs << "corner_sigma_px" << c.uncertainty.corner_sigma_px;
  fs << "projection_sigma_grid_x_px" << cv::Mat(grid.x_px, true).t();
  fs << "projection_sigma_grid_y_px" << cv::Mat(grid.y_px, true).t();
  fs << "projection_sigma_grid_px" << grid.sigma_px;
  fs << "views"
     << "[";
  for (const ViewReport& v : c.views) {
    fs << "{"
       << "image" << v.view << "used" << static_cast<int>(v.used) << "corners" << v.corners;
    if (!v.detector.empty()) fs << "detector" << v.detector;
    if (v.used || v.rms_px > 0) fs << "rms_px" << v.rms_px;
    if (!v.used) fs << "rejection" << v.rejection;
    fs << "}";
  }
  fs << "]";
  write_storage(fs, path);
}

void save_camera_ros(const std::string& path, const CameraModel& camera, const std::string& camera_name,
                     const std::vector<ViewReport>& views, const std::optional<IntrinsicsCovariance>& uncertainty) {
  const auto matrix = [](const char* key, int rows, int cols, const std::vector<double>& data) {
    std::string text =
        std::string(key) + ":\n  rows: " + std::to_string(rows) + "\n  cols: " + std::to_string(cols) + "\n  data: [";
    for (std::size_t i = 0; i < data.size(); ++i)
      text += (i ? ", " : "") + (std::isnan(data[i]) ? std::string(".nan") : model::shortest_number_text(data[i]));
    return text + "]\n";
  };
  const cv::Matx33d& k = camera.camera_matrix;
  std::string text = "image_width: " + std::to_string(camera.image_size.width) +
                     "\nimage_height: " + std::to_string(camera.image_size.height) + "\ncamera_name: " + camera_name +
                     "\n";
  text +=
      matrix("camera_matrix", 3, 3, {k(0, 0), k(0, 1), k(0, 2), k(1, 0), k(1, 1), k(1, 2), k(2, 0), k(2, 1), k(2, 2)});
  text += "distortion_model: plumb_bob\n";
  text += matrix("distortion_coefficients", 1, 5, {camera.distortion.begin(), camera.distortion.end()});
  text += matrix("rectification_matrix", 3, 3, {1, 0, 0, 0, 1, 0, 0, 0, 1});
  text += matrix("projection_matrix", 3, 4,
                 {k(0, 0), k(0, 1), k(0, 2), 0, k(1, 0), k(1, 1), k(1, 2), 0, k(2, 0), k(2, 1), k(2, 2), 0});
  if (uncertainty) {
    const ProjectionSigmaGrid grid =
        projection_sigma_grid(camera, *uncertainty, kProjectionGridCols, kProjectionGridRows);
    text += "# kincal: the intrinsics' covariance and the projection uncertainty (ROS ignores these keys)\n";
    text += matrix("intrinsics_covariance", 9, 9, {uncertainty->covariance.val, uncertainty->covariance.val + 81});
    text += std::string("intrinsics_covariance_order: \"") + kIntrinsicsOrder + "\"\n";
    text += "corner_sigma_px: " + model::shortest_number_text(uncertainty->corner_sigma_px) + "\n";
    text += matrix("projection_sigma_grid_x_px", 1, kProjectionGridCols, grid.x_px);
    text += matrix("projection_sigma_grid_y_px", 1, kProjectionGridRows, grid.y_px);
    text += matrix("projection_sigma_grid_px", kProjectionGridRows, kProjectionGridCols,
                   {grid.sigma_px.begin<double>(), grid.sigma_px.end<double>()});
  }
  for (const ViewReport& v : views) {
    text += "# view " + v.view + ": " +
            (v.used ? std::to_string(v.corners) + " corners, RMS " + model::shortest_number_text(v.rms_px) + " px, " +
                          v.detector
                    : "not used: " + v.rejection) +
            "\n";
  }
  write_text(path, text);
}

// A ROS camera_info file's YAML (no "%YAML:1.0" line, which OpenCV needs and yaml-cpp refuses).
YAML::Node parse_ros(const std::string& path, const std::string& text) {
  YAML::Node root;
  try {
    files::check_yaml_text<CalibrationError>(text, path);
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw CalibrationError(path + ": not a YAML file (" + e.what() + ")");
  }
  // root[key] throws on a scalar or a list: the class is refused here, once.
  if (!root.IsMap()) throw CalibrationError(path + ": not a camera file (its top is not a map of keys)");
  return root;
}

// The data of a {rows, cols, data} node of that shape, or none; throws YAML::Exception for a bad
// scalar.
std::vector<double> ros_data(const YAML::Node& m, int rows, int cols) {
  std::vector<double> data;
  if (m && m["rows"] && m["cols"] && m["data"] && m["rows"].as<int>() == rows && m["cols"].as<int>() == cols)
    data = m["data"].as<std::vector<double>>();
  if (data.size() != static_cast<std::size_t>(rows * cols)) data.clear();
  return data;
}

// A {rows, cols, data} matrix of a ROS file (CV_64F); throws YAML::Exception for a bad scalar.
cv::Mat ros_matrix(const YAML::Node& root, const std::string& path, const std::string& key, int rows, int cols) {
  const std::vector<double> data = ros_data(root[key], rows, cols);
  if (data.empty())
    throw CalibrationError(path + ": key '" + key + "' missing or not a " + std::to_string(rows) + "x" +
                           std::to_string(cols) + " matrix");
  return cv::Mat(data, true).reshape(1, rows);
}

// The distortion of a ROS file: {rows, cols, data} of a shape is_distortion_shape takes.
cv::Mat ros_distortion(const YAML::Node& root, const std::string& path) {
  const YAML::Node m = root["distortion_coefficients"];
  int rows = 0, cols = 0;
  if (m && m.IsMap() && m["rows"] && m["cols"] && m["data"]) {
    rows = m["rows"].as<int>();
    cols = m["cols"].as<int>();
  }
  const std::vector<double> data = is_distortion_shape(rows, cols) ? ros_data(m, rows, cols) : std::vector<double>();
  if (data.empty()) throw distortion_shape_error(path, "distortion_coefficients");
  return cv::Mat(data, true);
}

// A Kalibr camera chain of one camera (kalibr_calibrate_cameras' camchain.yaml): cam0's pinhole
// intrinsics [fu, fv, pu, pv], resolution [w, h] and radtan distortion [k1, k2, r1, r2] (OpenCV's k1
// k2 p1 p2) or none. A chain of several cameras names them (which is meant is not the file's to
// say); another camera or distortion model is refused by name.
CameraModel load_kalibr_camera(const std::string& path, const YAML::Node& root) {
  int cameras = 0;  // keys cam0, cam1, ...
  for (const auto& entry : root) {
    const std::string key = entry.first.as<std::string>();
    if (key.size() > 3 && key.rfind("cam", 0) == 0 && key.find_first_not_of("0123456789", 3) == std::string::npos)
      ++cameras;
  }
  if (cameras != 1)
    throw CalibrationError(path + ": a Kalibr camera chain of " + std::to_string(cameras) +
                           " cameras; give one camera's file (OpenCV's or ROS's YAML, or a chain of cam0 alone)");
  const YAML::Node cam = root["cam0"];
  const std::string model = cam["camera_model"] ? cam["camera_model"].as<std::string>() : "";
  if (model != "pinhole")
    throw CalibrationError(path + ": cam0: camera_model '" + files::excerpt(model) +
                           "': kincal's camera is a pinhole (with plumb_bob distortion)");
  const std::string distortion = cam["distortion_model"] ? cam["distortion_model"].as<std::string>() : "";
  if (distortion != "radtan" && distortion != "none")
    throw CalibrationError(path + ": cam0: distortion_model '" + files::excerpt(distortion) +
                           "': kincal's distortion is plumb_bob (Kalibr's radtan)");
  const auto numbers = [&](const char* key, std::size_t n) {
    std::vector<double> v;
    if (cam[key] && cam[key].IsSequence() && cam[key].size() == n) v = cam[key].as<std::vector<double>>();
    if (v.size() != n)
      throw CalibrationError(path + ": cam0: key '" + key + "' missing or not " + std::to_string(n) + " numbers");
    return v;
  };
  const std::vector<double> k = numbers("intrinsics", 4), size = numbers("resolution", 2);
  CameraModel c;
  c.image_size = checked_size(path, size[0], size[1]);
  c.camera_matrix = cv::Matx33d(k[0], 0, k[2], 0, k[1], k[3], 0, 0, 1);
  if (distortion == "radtan") {
    const std::vector<double> d = numbers("distortion_coeffs", 4);
    c.distortion = {d[0], d[1], d[2], d[3], 0.0};
  }
  return c;
}

CameraModel load_ros_camera(const std::string& path, const std::string& text) {
  const YAML::Node root = parse_ros(path, text);
  try {
    if (root["cam0"] && root["cam0"].IsMap()) return load_kalibr_camera(path, root);
    const std::string model = root["distortion_model"] ? root["distortion_model"].as<std::string>() : "";
    // No key of any camera file: another file given for a camera (a model, a geometry): the file
    // is named as such, not the first key it lacks.
    if (!root["camera_matrix"] && !root["image_width"] && !root["image_height"] && !root["distortion_coefficients"] &&
        !root["cam0"])
      throw CalibrationError(path +
                             ": not a camera file (none of camera_matrix, image_width, image_height, "
                             "distortion_coefficients): give `kincal camera calibrate`'s YAML, OpenCV's, a ROS "
                             "camera_info or a Kalibr camchain");
    if (!root["image_width"] || !root["image_height"])
      throw CalibrationError(path + ": image_width and image_height must be given");
    return camera_from(ros_matrix(root, path, "camera_matrix", 3, 3),
                       plumb_bob_of(ros_distortion(root, path), model, path, "distortion_coefficients"),
                       checked_size(path, root["image_width"].as<double>(), root["image_height"].as<double>()));
  } catch (const YAML::Exception& e) {
    throw CalibrationError(path + ": " + e.what());
  }
}

CameraModel load_camera(const std::string& path) {
  const std::string text = read_camera_text(path);
  const std::size_t start = text.find_first_not_of(" \t\r\n");
  if (text.compare(start, 5, "<?xml") == 0 || text.compare(start, 15, "<opencv_storage") == 0)
    throw CalibrationError(path +
                           ": an OpenCV XML file; kincal reads camera files in YAML, OpenCV's or ROS's "
                           "(cv::FileStorage writes YAML to a file named .yml or .yaml)");
  if (text.rfind("%YAML:", 0) != 0) return load_ros_camera(path, text);
  cv::FileStorage fs = open_for_reading(path, text);
  if (fs["camera_matrix"].empty() && !fs["M1"].empty())
    throw CalibrationError(path +
                           ": a stereo pair's file (M1 D1 M2 D2, as OpenCV's stereo_calib writes them), "
                           "not one camera's: give the camera's own file (kincal camera calibrate writes one)");
  const cv::Mat k = read_matrix(fs, path, "camera_matrix", 3, 3);
  return camera_from(k, read_distortion(fs, path, "distortion_coefficients"), read_size(fs, path));
}

std::optional<IntrinsicsCovariance> load_camera_uncertainty(const std::string& path) {
  const std::string text = read_camera_text(path);
  cv::Mat covariance;
  std::string order;
  IntrinsicsCovariance out;
  if (text.rfind("%YAML:", 0) != 0) {
    const YAML::Node root = parse_ros(path, text);
    if (!root["intrinsics_covariance"]) return std::nullopt;
    try {
      covariance = ros_matrix(root, path, "intrinsics_covariance", 9, 9);
      if (root["intrinsics_covariance_order"]) order = root["intrinsics_covariance_order"].as<std::string>();
      if (!root["corner_sigma_px"]) throw CalibrationError(path + ": key 'corner_sigma_px' missing or not a number");
      out.corner_sigma_px = root["corner_sigma_px"].as<double>();
    } catch (const YAML::Exception& e) {
      throw CalibrationError(path + ": " + e.what());
    }
  } else {
    cv::FileStorage fs = open_for_reading(path, text);
    if (fs["intrinsics_covariance"].empty()) return std::nullopt;
    covariance = read_matrix(fs, path, "intrinsics_covariance", 9, 9);
    if (fs["intrinsics_covariance_order"].isString())
      order = static_cast<std::string>(fs["intrinsics_covariance_order"]);
    out.corner_sigma_px = read_number(fs, path, "corner_sigma_px");
  }
  if (order != kIntrinsicsOrder) {
    throw CalibrationError(path + ": key 'intrinsics_covariance_order' is '" + files::excerpt(order) + "', not '" +
                           kIntrinsicsOrder + "'");
  }
  check_covariance(covariance, out.corner_sigma_px, path, "intrinsics_covariance");
  out.covariance = cv::Matx<double, 9, 9>(covariance);
  return out;
}

void save_stereo(const std::string& path, const StereoCalibration& c) {
  cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  fs << "image_width" << c.left.image_size.width << "image_height" << c.left.image_size.height;
  fs << "M1" << cv::Mat(c.left.camera_matrix) << "D1" << c.left.distortion_mat();
  fs << "M2" << cv::Mat(c.right.camera_matrix) << "D2" << c.right.distortion_mat();
  fs << "R" << cv::Mat(c.right_R_left) << "T" << cv::Mat(c.right_t_left_m);
  fs << "E" << cv::Mat(c.essential) << "F" << cv::Mat(c.fundamental);
  fs << "R1" << cv::Mat(c.rectify_left) << "R2" << cv::Mat(c.rectify_right);
  fs << "P1" << cv::Mat(c.projection_left) << "P2" << cv::Mat(c.projection_right);
  fs << "Q" << cv::Mat(c.disparity_to_depth);
  fs << "baseline_m" << c.baseline_m << "avg_reprojection_error" << c.rms_px;
  if (c.pose_uncertainty && !c.pose_uncertainty->calibration_covariance.empty()) {
    fs << "calibration_covariance" << c.pose_uncertainty->calibration_covariance;
    fs << "calibration_covariance_order" << kStereoCalibrationOrder;
    fs << "corner_sigma_px" << c.pose_uncertainty->corner_sigma_px;
  }
  write_storage(fs, path);
}

StereoCalibration load_stereo(const std::string& path) {
  cv::FileStorage fs = open_for_reading(path, read_camera_text(path));
  const cv::Size size = read_size(fs, path);
  StereoCalibration c;
  c.left = camera_from(read_matrix(fs, path, "M1", 3, 3), read_distortion(fs, path, "D1"), size);
  c.right = camera_from(read_matrix(fs, path, "M2", 3, 3), read_distortion(fs, path, "D2"), size);
  c.right_R_left = cv::Matx33d(read_matrix(fs, path, "R", 3, 3));
  c.right_t_left_m = cv::Vec3d(read_matrix(fs, path, "T", 3, 1));
  c.essential = cv::Matx33d(read_matrix(fs, path, "E", 3, 3));
  c.fundamental = cv::Matx33d(read_matrix(fs, path, "F", 3, 3));
  c.rectify_left = cv::Matx33d(read_matrix(fs, path, "R1", 3, 3));
  c.rectify_right = cv::Matx33d(read_matrix(fs, path, "R2", 3, 3));
  c.projection_left = cv::Matx34d(read_matrix(fs, path, "P1", 3, 4));
  c.projection_right = cv::Matx34d(read_matrix(fs, path, "P2", 3, 4));
  c.disparity_to_depth = cv::Matx44d(read_matrix(fs, path, "Q", 4, 4));
  c.baseline_m = cv::norm(c.right_t_left_m);
  c.rms_px = read_number(fs, path, "avg_reprojection_error");
  if (!fs["calibration_covariance"].empty()) {
    StereoPoseCovariance u;
    u.calibration_covariance = read_matrix(fs, path, "calibration_covariance", 24, 24);
    const std::string order = fs["calibration_covariance_order"].isString()
                                  ? static_cast<std::string>(fs["calibration_covariance_order"])
                                  : "";
    if (order != kStereoCalibrationOrder) {
      throw CalibrationError(path + ": key 'calibration_covariance_order' is '" + files::excerpt(order) + "', not '" +
                             kStereoCalibrationOrder + "'");
    }
    u.corner_sigma_px = read_number(fs, path, "corner_sigma_px");
    check_covariance(u.calibration_covariance, u.corner_sigma_px, path, "calibration_covariance");
    u.covariance = cv::Matx66d(u.calibration_covariance(cv::Rect(18, 18, 6, 6)));
    c.pose_uncertainty = u;
  }
  return c;
}

void save_hand_eye(const std::string& path, const HandEyeCalibration& c) {
  cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  fs << "gripper_T_camera" << matrix_of(c.gripper_T_camera);
  fs << "base_T_target" << matrix_of(c.base_T_target);
  fs << "method" << c.start_method;
  fs << "reprojection_rms_before_px" << c.rms_before_px << "reprojection_rms_after_px" << c.rms_after_px;
  fs << "poses" << c.poses_used;
  write_storage(fs, path);
}

std::string rig_hand_eye_text(bool camera_on_flange, const Eigen::Isometry3d& flange_T_tool,
                              const Eigen::Isometry3d& frame0_T_device) {
  cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  fs << (camera_on_flange ? "gripper_T_camera" : "gripper_T_target") << matrix_of(flange_T_tool);
  fs << (camera_on_flange ? "base_T_target" : "base_T_camera") << matrix_of(frame0_T_device);
  fs << "method"
     << "identify: the kinematics, the device's place and the hand-eye in one solve";
  return fs.releaseAndGetString();
}

HandEyeCalibration load_hand_eye(const std::string& path) {
  cv::FileStorage fs = open_for_reading(path, read_camera_text(path));
  HandEyeCalibration c;
  c.gripper_T_camera = isometry_of(read_matrix(fs, path, "gripper_T_camera", 4, 4), path, "gripper_T_camera");
  c.base_T_target = isometry_of(read_matrix(fs, path, "base_T_target", 4, 4), path, "base_T_target");
  c.start_method = static_cast<std::string>(fs["method"]);
  c.rms_before_px = read_number(fs, path, "reprojection_rms_before_px");
  c.rms_after_px = read_number(fs, path, "reprojection_rms_after_px");
  return c;
}

shared::CameraIntrinsics to_platform(const CameraModel& c) {
  const cv::Matx33d& k = c.camera_matrix;
  shared::CameraIntrinsics p;
  p.fx_px = to_float(k(0, 0), "fx_px");
  p.fy_px = to_float(k(1, 1), "fy_px");
  p.cx_px = to_float(k(0, 2), "cx_px");
  p.cy_px = to_float(k(1, 2), "cy_px");
  p.k1 = to_float(c.distortion[0], "k1");
  p.k2 = to_float(c.distortion[1], "k2");
  p.p1 = to_float(c.distortion[2], "p1");
  p.p2 = to_float(c.distortion[3], "p2");
  p.k3 = to_float(c.distortion[4], "k3");
  p.width_px = to_u16(c.image_size.width, "image width");
  p.height_px = to_u16(c.image_size.height, "image height");
  return p;
}

CameraModel from_platform(const shared::CameraIntrinsics& p) {
  CameraModel c;
  c.image_size = cv::Size(p.width_px, p.height_px);
  c.camera_matrix = cv::Matx33d(p.fx_px, 0, p.cx_px, 0, p.fy_px, p.cy_px, 0, 0, 1);
  c.distortion = {p.k1, p.k2, p.p1, p.p2, p.k3};
  return c;
}

}  // namespace kincal::camera

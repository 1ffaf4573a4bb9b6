// Measurement datasets (CSV): joint readings and what the measuring device saw, in the
// device's frame.
//
//   q1,q2,...,qN,x,y,z[,qw,qx,qy,qz][,cxx,cxy,cxz,cyy,cyz,czz | ,sigma][,id]
//
// One header row naming the columns (any order; q1..qN contiguous from q1), then one row per
// measurement: joint readings (rad or m), the tool point (m), optionally the tool orientation
// as a unit quaternion (device_R_tool), optionally the point's covariance (m^2, upper triangle)
// or a scalar standard deviation per axis (m), optionally the row's id: the export's time stamp
// or record number as text (`kincal import --id`), which messages naming the row quote. Blank
// lines and lines starting with '#' are skipped. Numbers are plain decimal (std::from_chars);
// fields may stand in double quotes as RFC 4180 says ("" for a quote), which an id holding a
// comma needs (write_dataset quotes it).
//
// The full pose's covariance (issue #26: board poses), with the orientation and the position
// covariance columns: cxrx,cxry,cxrz,cyrx,cyry,cyrz,czrx,czry,czrz (position x rotation, m rad)
// and crxrx,crxry,crxrz,cryry,cryrz,crzrz (rotation, rad^2) complete the upper triangle of the
// 6x6 covariance of (x, y, z, rx, ry, rz): the position error (m) and the rotation error d (rad),
// both in the device frame, d a rotation vector applied on the left, device_R_tool_measured =
// exp([d]x) device_R_tool (the rotation identify's orientation residual uses). All 15 or none;
// refused without the orientation or the position covariance, or when the 6x6 is not positive
// definite. The reader also fills `covariance` with its position block, so a reader of positions
// only weights the row as before; write_dataset writes them when every row has one.
//
// Why a small reader of our own: the format is numbers and one text column (the id, in quotes
// only where it holds a comma or a quote), and every error must carry its line number and the
// column at fault. Debian's C++ CSV
// parsers do not fit: fast-cpp-csv-parser (libfccp-dev) fixes the column count at compile time;
// libcsv is a C tokenizer with callbacks that would still leave number parsing and the line
// bookkeeping to us.
//
// Errors (InputError "FILE:LINE: what", ending "(id TEXT)" on a row with an id): missing/unknown/
// duplicate columns, more than kMaxRows data rows, a row with the wrong number of fields, a quote that is not closed, a
// field that is not a finite number, an empty id, a quaternion whose norm is not 1 within 1e-3, a covariance that is
// not positive definite, sigma <= 0.
#pragma once

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "host/model/robot_model.hpp"

namespace kincal::model {

using Matrix6 = Eigen::Matrix<double, 6, 6>;

// The most data rows a dataset or joints file may hold (and `import` writes). A calibration needs
// hundreds; `identify`'s default takes ~30 ms a row on a 2-core machine (20,000 rows: 10 min,
// 230 MB), and 7.1 M rows within the file size limit took 8.7 GB before this cap.
inline constexpr std::size_t kMaxRows = 100000;
// The message refusing the row past kMaxRows (the readers here and `import`'s).
std::string too_many_rows();

struct Measurement {
  std::vector<double> q;
  Vector3 position = Vector3::Zero();
  std::optional<Eigen::Quaterniond> orientation;  // device_R_tool
  std::optional<Matrix3> covariance;              // of position, m^2
  std::optional<Matrix6> pose_covariance;         // (x y z rx ry rz), see above
  int line = 0;                                   // 1-based line in the source
  std::string id;                                 // the export's row id or time stamp; empty: none
};

enum class NoiseColumns { none, sigma, covariance };

struct Dataset {
  std::string source;
  int joint_count = 0;
  bool has_orientation = false;
  bool has_pose_covariance = false;  // the 15 columns beyond cxx..czz
  NoiseColumns noise = NoiseColumns::none;
  std::vector<Measurement> rows;
};

Dataset read_dataset(const std::string& path);
Dataset parse_dataset(std::istream& in, const std::string& source);

// Joint readings only (`kincal predict --joints`): header q1..qN; extra columns are ignored, so a
// dataset file is also a joints file.
std::vector<std::vector<double>> read_joints(const std::string& path);
std::vector<std::vector<double>> parse_joints(std::istream& in, const std::string& source);

// Throws InputError when the data's joint count differs from the model's.
void check_joint_count(const RobotModel& model, int data_joints, const std::string& source);

// A pose measurement as a row: joint readings q, the tool's pose in the device frame and its 6 x 6
// covariance (the convention above); `covariance` gets its position block. `line` numbers the row.
Measurement pose_row(std::vector<double> q, const Eigen::Isometry3d& device_T_tool, const Matrix6& covariance,
                     int line);

// Two rows at one configuration: the same readings within kSameReading (rad or m) -- what a file
// written again with fewer digits changes (a joint in degrees to 3 decimals); a pose measured
// twice, or a file's rows given again.
inline constexpr double kSameReading = 2e-5;
bool same_readings(const Measurement& a, const Measurement& b);
// A key of the readings that rows of one configuration share within reading_key_window(joints):
// a fixed weighted sum of the readings, so that readings sorted by it are compared only within
// that window (by the first reading alone, a joint that never moved put every row in one window).
double reading_key(const std::vector<double>& q);
double reading_key_window(std::size_t joints);
// Each row's configuration (0, 1, ... in the order of their first rows): rows of one configuration
// share it. Cross-validation leaves a configuration out whole.
std::vector<int> configuration_of_rows(const Dataset& data);

// " (id TEXT)" for a row with an id, else "": what a message naming the row appends.
std::string id_suffix(const Measurement& row);

// Writes a dataset in the format above (orientation if the rows have it; covariance if every
// row has one; the id column if every row has an id). Numbers in their shortest exact form.
void write_dataset(std::ostream& out, const Dataset& data);

}  // namespace kincal::model

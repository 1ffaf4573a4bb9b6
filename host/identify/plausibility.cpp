#include "host/identify/plausibility.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <utility>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "host/identify/data_mistakes.hpp"

namespace kincal::identify {

namespace {

constexpr double kDegreesPerRadian = 180.0 / std::numbers::pi;
constexpr double kMaxRange_m = 1000.0;  // beyond any laser tracker's or camera's range

const auto number = finding_number;

double median(std::vector<double> v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

bool inside(double q, double lower, double upper) {
  const double tolerance = 0.01 * (upper - lower) + 1e-9;
  return q >= lower - tolerance && q <= upper + tolerance;
}

}  // namespace

std::vector<JointFinding> joint_readings_outside(const model::RobotModel& m,
                                                 const std::vector<std::vector<double>>& readings) {
  std::vector<JointFinding> found;
  for (std::size_t j = 0; j < m.joints.size(); ++j) {
    const model::Joint& joint = m.joints[j];
    const bool revolute = joint.type == core::JointType::revolute;
    const bool limited = std::isfinite(joint.lower) && std::isfinite(joint.upper);
    const double lower = limited ? joint.lower : -4 * std::numbers::pi;
    const double upper = limited ? joint.upper : 4 * std::numbers::pi;
    if (!limited && !revolute) continue;
    const double scale = revolute ? kDegreesPerRadian : 1000.0;
    int outside = 0, scaled_inside = 0;
    double largest = 0.0;
    for (const std::vector<double>& r : readings) {
      const double q = r[j];
      largest = std::max(largest, std::abs(q));
      if (!inside(q, lower, upper)) ++outside;
      if (inside(q / scale, lower, upper)) ++scaled_inside;
    }
    if (outside == 0) continue;
    JointFinding f;
    f.text = "joint " + std::to_string(j + 1) + " (" + joint.name + "): " + std::to_string(outside) + " of " +
             std::to_string(readings.size()) + " readings outside " + (limited ? "its limits [" : "[") + number(lower) +
             ", " + number(upper) + (revolute ? "] rad" : "] m") + " (largest magnitude " + number(largest) + ")";
    // Degrees or millimetres reach far beyond the range, not just past it (a zero a quarter turn
    // off puts a few readings past a limit, and they too fit when divided by 57.3).
    f.unit_mistake = scaled_inside == static_cast<int>(readings.size()) &&
                     largest > 2.0 * std::max(std::abs(lower), std::abs(upper));
    if (f.unit_mistake)
      f.text += revolute ? ": likely degrees given as radians" : ": likely millimetres given as metres";
    found.push_back(std::move(f));
  }
  return found;
}

namespace {

struct Predicted {
  std::vector<model::Vector3> position_m;
  std::vector<model::Matrix3> rotation;
};

// The nominal tool poses, the points moved by the measured point's offset from the tool
// (frame_check, data_mistakes.hpp): a reflector 100 mm off a flange that the model's tool is moves
// otherwise.
Predicted predict(const model::RobotModel& m, const model::Dataset& data, const model::Vector3& offset) {
  Predicted p;
  for (const model::Measurement& r : data.rows) {
    const model::Transform t = model::forward_kinematics(m, r.q);
    p.position_m.push_back(t.translation + t.rotation * offset);
    p.rotation.push_back(t.rotation);
  }
  return p;
}

model::Vector3 median_point(const std::vector<model::Vector3>& points) {
  model::Vector3 m;
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> v;
    for (const model::Vector3& x : points) v.push_back(x[axis]);
    m[axis] = median(v);
  }
  return m;
}

void check_far_points(const model::Dataset& data, const Predicted& p, std::vector<std::string>& found) {
  const model::Vector3 predicted_centre = median_point(p.position_m);
  double spread = 0.0;
  for (const model::Vector3& x : p.position_m) spread = std::max(spread, (x - predicted_centre).norm());
  std::vector<model::Vector3> measured;
  for (const model::Measurement& r : data.rows) measured.push_back(r.position);
  const model::Vector3 centre = median_point(measured);
  const double limit = 2 * spread + 0.5;
  int far = 0, remote = 0;
  std::string first, first_remote;
  for (const model::Measurement& r : data.rows) {
    const double coordinate = r.position.cwiseAbs().maxCoeff();  // the norm of 1e308s overflows
    if (coordinate > kMaxRange_m && remote++ == 0)
      first_remote =
          "line " + std::to_string(r.line) + model::id_suffix(r) + ": a coordinate of " + number(coordinate) + " m";
    const double distance = (r.position - centre).norm();
    if (distance <= limit) continue;  // NaN cannot occur: the reader takes finite numbers only
    if (far++ == 0) first = "line " + std::to_string(r.line) + model::id_suffix(r) + ": " + number(distance) + " m";
  }
  if (remote > 0)
    found.push_back(std::to_string(remote) + " measured points lie farther than " + number(kMaxRange_m) +
                    " m from the measuring device (" + first_remote + "): no instrument measures a robot there");
  if (far > 0)
    found.push_back(std::to_string(far) + " measured points lie farther than " + number(limit) +
                    " m (twice the model's spread of " + number(spread) + " m, plus 0.5 m) from the median point (" +
                    first + "): typing errors or wrong units");
}

void check_positions(const model::Dataset& data, const Predicted& p, std::vector<std::string>& found) {
  std::vector<double> ratios;
  for (std::size_t i = 1; i < data.rows.size(); ++i) {
    const double predicted = (p.position_m[i] - p.position_m[i - 1]).norm();
    if (predicted > 0.01) ratios.push_back((data.rows[i].position - data.rows[i - 1].position).norm() / predicted);
  }
  if (ratios.size() < 3) return;
  const double ratio = median(ratios);
  if (ratio >= 0.7 && ratio <= 1.4) return;
  std::string what = "the measured points move " + number(ratio) +
                     " times as far between rows as the model predicts (median over " + std::to_string(ratios.size()) +
                     " pairs of rows)";
  // Lengths a device may export in, as metres per unit: a ratio within a factor kUnitBand of
  // 1/unit names it. The ratio is the measured point's moves over the model's, whose tool is not
  // known yet: a reflector 50-150 mm off the flange of a small arm moves more than the flange (a
  // ViperX 300 s measured in inches: 45.9, 1.17 times 1/inch). 1.4 keeps the bands apart --
  // centimetres 71-140, inches 28-55, feet 2.3-4.6, and none reaches the plausible 0.7-1.4.
  constexpr double kUnitBand = 1.4;
  const std::pair<double, const char*> units[] = {{0.01, "centimetres"}, {0.0254, "inches"}, {0.3048, "feet"}};
  const char* unit = nullptr;
  for (const auto& [metres, name] : units)
    if (std::abs(std::log(ratio * metres)) < std::log(kUnitBand)) unit = name;
  if (ratio > 500 && ratio < 2000)
    what += ": likely millimetres given as metres";
  else if (unit)
    what += std::string(": likely ") + unit + " given as metres";
  else if (ratio > 0.0005 && ratio < 0.002)
    what += ": likely metres where the model's millimetres were meant, or the model in mm";
  else
    what += ": wrong units, wrong joint readings, or not this robot";
  found.push_back(what);
}

// The rotation between consecutive rows, measured M_k = R_i R_(i-1)^T and predicted P_k, must be
// M_k = B P_k B^T for the one unknown registration rotation B. B is fitted to the pairs' rotation
// vectors (Kabsch); the median angle of M_k^T B P_k B^T (rad) and B, or nothing when too few pairs
// turn by 5..150 degrees to compare. (The turns alone cannot tell every quaternion convention: a
// signed permutation of the four components that is a rotation of 4-space, as JPL's x,y,z,w order
// with the inverse rotation, is a fixed rotation on each side, q -> a q b, which turns M_k by a
// alone; B is then the positions' registration turned by a.)
inline constexpr double kTurnSpread = 0.05;
struct OrientationFit {
  double median_rad = 0.0;
  model::Matrix3 registration = model::Matrix3::Identity();
  double turn_spread = 0.0;  // the predicted turns' axes: smallest over largest eigenvalue of their scatter
};

std::optional<OrientationFit> orientation_mismatch(const std::vector<Eigen::Quaterniond>& measured,
                                                   const Predicted& p) {
  std::vector<model::Matrix3> seen, predicted;
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero(), scatter = Eigen::Matrix3d::Zero();
  for (std::size_t i = 1; i < measured.size(); ++i) {
    const model::Matrix3 pk = p.rotation[i] * p.rotation[i - 1].transpose();
    const Eigen::AngleAxisd turn(pk);
    if (turn.angle() < 5.0 / kDegreesPerRadian || turn.angle() > 150.0 / kDegreesPerRadian) continue;
    const model::Matrix3 mk = (measured[i] * measured[i - 1].conjugate()).toRotationMatrix();
    const Eigen::AngleAxisd seen_turn(mk);
    h += (turn.angle() * turn.axis()) * (seen_turn.angle() * seen_turn.axis()).transpose();
    scatter += turn.axis() * turn.axis().transpose();
    seen.push_back(mk);
    predicted.push_back(pk);
  }
  if (seen.size() < 3) return std::nullopt;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d b = svd.matrixV() * d * svd.matrixU().transpose();
  std::vector<double> residuals;
  for (std::size_t k = 0; k < seen.size(); ++k)
    residuals.push_back(Eigen::AngleAxisd(seen[k].transpose() * b * predicted[k] * b.transpose()).angle());
  const Eigen::Vector3d spread = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvalues();
  return OrientationFit{median(residuals), b, spread(0) / spread(2)};
}

// How far the orientations miss (rad): the turns' misfit, or, where the positions fitted a
// registration of their own (data_mistakes.hpp) and the tool turned about every axis (a sweep of
// one joint trades the registration's turn about it for the measured point's offset), the larger
// of that and the angle between the two registrations.
double orientation_misfit(const OrientationFit& fit, const std::optional<model::Matrix3>& position_registration) {
  if (!position_registration || fit.turn_spread < kTurnSpread) return fit.median_rad;
  const double between = Eigen::AngleAxisd(fit.registration.transpose() * *position_registration).angle();
  return std::max(fit.median_rad, between);
}

// Beyond kConventionMisfit_deg the other quaternion conventions are tried, and one that fits is
// named; beyond kMisfit_deg the orientations are refused though none fits. Between the two, a
// model whose angles are a few degrees off: the zoo's arms with every angle up to 4 deg off (every
// length 20 mm) missed by 12-16 deg, its mistakes (joints swapped, reversed, turned, degrees
// as radians, logs out of step) by 75-137.
inline constexpr double kConventionMisfit_deg = 10.0;
inline constexpr double kMisfit_deg = 30.0;

void check_orientations(const model::Dataset& data, const Predicted& p,
                        const std::optional<model::Matrix3>& position_registration, std::vector<std::string>& found) {
  if (!data.has_orientation) return;
  // The quaternions as given and as other conventions would have written them: x,y,z,w order, the
  // inverse rotation (a JPL quaternion: the conjugate of the Hamilton one kincal reads), or both.
  std::vector<Eigen::Quaterniond> as_given, as_xyzw, as_inverse, as_inverse_xyzw;
  for (const model::Measurement& r : data.rows) {
    if (!r.orientation) return;
    const Eigen::Quaterniond& q = *r.orientation;               // read as w,x,y,z
    const Eigen::Quaterniond xyzw(q.z(), q.w(), q.x(), q.y());  // the columns were x,y,z,w
    as_given.push_back(q);
    as_xyzw.push_back(xyzw);
    as_inverse.push_back(q.conjugate());
    as_inverse_xyzw.push_back(xyzw.conjugate());
  }
  const std::optional<OrientationFit> turns = orientation_mismatch(as_given, p);
  if (!turns) return;
  const double given = orientation_misfit(*turns, position_registration);
  if (given <= kConventionMisfit_deg / kDegreesPerRadian) return;
  std::string what =
      turns->median_rad > kConventionMisfit_deg / kDegreesPerRadian
          ? "the measured orientations turn between rows differently from the model's, by " +
                number(turns->median_rad * kDegreesPerRadian) + " degrees (median after the best registration)"
          : "the measured orientations turn between rows as the model's, but in a frame " +
                number(given * kDegreesPerRadian) + " degrees from the one the positions are measured in";
  const std::pair<const std::vector<Eigen::Quaterniond>*, const char*> others[] = {
      {&as_xyzw, "quaternions in x,y,z,w order (the columns qw,qx,qy,qz are w first"},
      {&as_inverse,
       "each quaternion the inverse rotation (the JPL convention: the conjugate of the Hamilton one "
       "kincal reads"},
      {&as_inverse_xyzw,
       "JPL quaternions (x,y,z,w order and the inverse rotation; the columns qw,qx,qy,qz are "
       "Hamilton's, w first"}};
  double best = 0.25 * given;
  std::string cause = ": wrong orientation columns or not this robot";
  bool named = false;
  for (const auto& [quaternions, words] : others) {
    const std::optional<OrientationFit> fit = orientation_mismatch(*quaternions, p);
    if (!fit) continue;
    const double other = orientation_misfit(*fit, position_registration);
    if (other < best) {
      best = other;
      named = true;
      cause = std::string(": likely ") + words + "; read so they differ by " + number(other * kDegreesPerRadian) +
              " degrees)";
    }
  }
  if (named || given > kMisfit_deg / kDegreesPerRadian) found.push_back(what + cause);
}

void check_exact_fit(const model::Dataset& data, const Predicted& p, const PlausibilityOptions& options,
                     std::vector<std::string>& found) {
  if (options.noise_given || data.noise != model::NoiseColumns::none || data.rows.empty()) return;
  double largest = 0.0;
  for (std::size_t i = 0; i < data.rows.size(); ++i)
    largest = std::max(largest, (data.rows[i].position - p.position_m[i]).norm());
  if (largest > 1e-9) return;
  found.push_back("the nominal model reproduces every measured point within " + number(largest) +
                  " m: data without noise (made by `kincal predict`?) give no noise level and no uncertainty; "
                  "state the instrument noise (--sigma) if the data are real");
}

}  // namespace

std::vector<std::string> implausibilities(const model::RobotModel& nominal, const model::Dataset& data,
                                          const PlausibilityOptions& options) {
  std::vector<std::string> found;
  if (data.joint_count != nominal.joint_count()) return found;  // check_joint_count says so
  std::vector<std::vector<double>> readings;
  for (const model::Measurement& r : data.rows) readings.push_back(r.q);
  for (JointFinding& f : joint_readings_outside(nominal, readings)) found.push_back(std::move(f.text));
  FrameCheck frame = frame_check(nominal, data);
  const Predicted p = predict(nominal, data, frame.measured_point_offset);
  check_far_points(data, p, found);
  check_positions(data, p, found);
  check_orientations(data, p, frame.registration_rotation, found);
  check_exact_fit(data, p, options, found);
  for (std::string& f : frame.mistakes) found.push_back(std::move(f));
  return found;
}

std::vector<std::string> implausibilities(const model::Dataset& data) {
  std::vector<model::Vector3> measured;
  for (const model::Measurement& r : data.rows) measured.push_back(r.position);
  if (measured.size() < 3) return {};
  const model::Vector3 centre = median_point(measured);
  std::vector<double> distance;
  for (const model::Vector3& x : measured) distance.push_back((x - centre).norm());
  const double spread = median(distance);
  if (spread <= kMaxSpread_m) return {};
  return {"the measured points lie a median " + number(spread) +
          " m from their median point, beyond any arm's reach (" + number(kMaxSpread_m) +
          " m); millimetres given as metres? (--model checks the data against the robot)"};
}

void require_plausible(const model::RobotModel& nominal, const model::Dataset& data, const std::string& override_flag,
                       const PlausibilityOptions& options) {
  const std::vector<std::string> found = implausibilities(nominal, data, options);
  if (found.empty()) return;
  std::string message = data.source + ": implausible for " + nominal.name + ":";
  for (const std::string& f : found) message += "\n  - " + f;
  message += "\n  (" + override_flag + " proceeds anyway)";
  throw model::InputError(message);
}

}  // namespace kincal::identify

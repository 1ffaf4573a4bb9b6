#include "zoo_world.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace zoo {

namespace {

constexpr double kDeg = M_PI / 180.0;

double uniform(std::mt19937& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

// A magnitude in [lo, hi] with a random sign.
double signed_uniform(std::mt19937& rng, double lo, double hi) {
  return (std::bernoulli_distribution(0.5)(rng) ? 1.0 : -1.0) * uniform(rng, lo, hi);
}

Eigen::Vector3d random_direction(std::mt19937& rng) {
  std::normal_distribution<double> n;
  Eigen::Vector3d v(n(rng), n(rng), n(rng));
  return v.normalized();
}

Eigen::Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n;
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
}

std::vector<double> uniform_configuration(const Chain& chain, std::mt19937& rng) {
  std::vector<double> q;
  for (const ChainJoint& j : chain.joints) {
    const double margin = 0.05 * (j.upper - j.lower);
    q.push_back(uniform(rng, j.lower + margin, j.upper - margin));
  }
  return q;
}

// The reflector or target: 50-150 mm from the flange, at least 20 mm off the last joint's axis.
Pose marker_on_flange(const Chain& chain, bool pose, std::mt19937& rng) {
  const Pose flange_T_last = chain.last_T_flange.inverse();
  const Eigen::Vector3d on_axis = flange_T_last.translation();
  const Eigen::Vector3d axis = flange_T_last.linear() * chain.joints.back().axis;
  Pose marker = Pose::Identity();
  if (pose) marker.linear() = random_rotation(rng);
  for (;;) {
    marker.translation() = random_direction(rng) * uniform(rng, 0.05, 0.15);
    const Eigen::Vector3d r = marker.translation() - on_axis;
    if ((r - r.dot(axis) * axis).norm() >= 0.02) return marker;
  }
}

void set_geometry_errors(Truth& t, const Chain& chain, double lo_m, double hi_m, double lo_rad, double hi_rad,
                         std::mt19937& rng) {
  for (std::size_t i = 0; i < chain.joints.size(); ++i) {
    for (int k = 0; k < 3; ++k) t.errors.origin[i](k) = signed_uniform(rng, lo_m, hi_m);
    for (int k = 3; k < 6; ++k) t.errors.origin[i](k) = signed_uniform(rng, lo_rad, hi_rad);
    t.errors.zero[i] =
        chain.joints[i].prismatic ? signed_uniform(rng, lo_m, hi_m) : signed_uniform(rng, lo_rad, hi_rad);
  }
}

// The frame the last axis and the one before it define (standard DH's frame n-1): z along the
// last axis, x along their common normal (u_{n-1} x u_n), the origin at the normal's foot on the
// last axis. It is fixed in the next-to-last body and depends on nothing but the two axis lines.
Pose last_axes_frame(const Chain& chain, const ChainErrors& errors) {
  const std::size_t n = chain.joints.size();
  if (n < 2 || chain.joints[n - 1].prismatic || chain.joints[n - 2].prismatic)
    throw std::runtime_error(chain.urdf_path + ": the zoo needs two revolute joints last");
  const std::vector<Pose> f = joint_frames(chain, errors, std::vector<double>(n, 0.0));
  const Eigen::Vector3d u = f[n - 2].linear() * chain.joints[n - 2].axis,
                        w = f[n - 1].linear() * chain.joints[n - 1].axis;
  const Eigen::Vector3d x = u.cross(w);
  if (x.norm() < 0.1) throw std::runtime_error(chain.urdf_path + ": the last two axes are near parallel");
  // The closest point to the line through f[n-2] along u on the line through f[n-1] along w.
  const Eigen::Vector3d d = f[n - 2].translation() - f[n - 1].translation();
  const double b = u.dot(w), s = (w.dot(d) - b * u.dot(d)) / (1.0 - b * b);
  Pose frame = Pose::Identity();
  frame.linear().col(0) = x.normalized();
  frame.linear().col(1) = w.cross(x.normalized());
  frame.linear().col(2) = w;
  frame.translation() = f[n - 1].translation() + s * w;
  return frame;
}

// The flange in last_axes_frame.
Pose flange_placement(const Chain& chain, const ChainErrors& errors) {
  const Pose flange =
      joint_frames(chain, errors, std::vector<double>(chain.joints.size(), 0.0)).back() * chain.last_T_flange;
  return last_axes_frame(chain, errors).inverse() * flange;
}

// Compliance on every revolute joint whose gravity torque reaches 10 % of the largest: 0.05-0.2 deg
// of deflection at its largest torque over the joint space. A revolute joint gravity barely loads
// (a vertical first axis, tilted only by its origin's errors) gets the most loaded joint's
// compliance: a base bearing about as stiff as the shoulder's, whose small sag is a real arm's too.
void set_compliance(Truth& t, const Chain& chain, std::mt19937& rng) {
  std::vector<double> largest(chain.joints.size(), 0.0);
  for (int k = 0; k < 300; ++k) {
    const std::vector<double> tau = gravity_torques(chain, t.errors, uniform_configuration(chain, rng));
    for (std::size_t i = 0; i < tau.size(); ++i) largest[i] = std::max(largest[i], std::abs(tau[i]));
  }
  const auto top = std::max_element(largest.begin(), largest.end());
  if (*top <= 0.0) return;
  for (std::size_t i = 0; i < largest.size(); ++i)
    if (largest[i] >= 0.1 * *top) t.errors.compliance_rad_per_nm[i] = uniform(rng, 0.05, 0.2) * kDeg / largest[i];
  const double top_joint = t.errors.compliance_rad_per_nm[static_cast<std::size_t>(top - largest.begin())];
  for (std::size_t i = 0; i < largest.size(); ++i)
    if (largest[i] < 0.1 * *top && !chain.joints[i].prismatic) {
      t.errors.compliance_rad_per_nm[i] = top_joint;
      t.compliance_known[i] = true;
    }
}

std::vector<int> revolute_joints(const Chain& chain) {
  std::vector<int> r;
  for (std::size_t i = 0; i < chain.joints.size(); ++i)
    if (!chain.joints[i].prismatic) r.push_back(static_cast<int>(i));
  return r;
}

Eigen::Vector3d mean_flange(const Chain& chain, std::mt19937& rng) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (int k = 0; k < 400; ++k) {
    const Eigen::Vector3d p =
        forward(chain, ChainErrors(chain.joints.size()), uniform_configuration(chain, rng)).translation();
    if (p.z() > 0.05) sum += p, ++n;
  }
  return n > 0 ? Eigen::Vector3d(sum / n) : Eigen::Vector3d::Zero();
}

// The device `distance` from the workspace centre; trackers and mocap in any orientation, the
// camera looking at the centre (z its line of sight) with a random roll.
Pose place_device(const Eigen::Vector3d& centre, Instrument instrument, std::mt19937& rng) {
  const double elevation = uniform(rng, -10.0, 40.0) * kDeg, azimuth = uniform(rng, -M_PI, M_PI);
  const double distance = instrument == Instrument::camera ? uniform(rng, 1.2, 2.0) : uniform(rng, 2.0, 4.0);
  const Eigen::Vector3d from =
      centre + distance * Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth),
                                          std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
  Pose root_T_device = Pose::Identity();
  root_T_device.translation() = from;
  if (instrument == Instrument::camera) {
    const Eigen::Vector3d z = (centre - from).normalized();
    const Eigen::Vector3d x = z.unitOrthogonal();
    Eigen::Matrix3d r;
    r << x, z.cross(x), z;
    root_T_device.linear() = r * Eigen::AngleAxisd(uniform(rng, -M_PI, M_PI), Eigen::Vector3d::UnitZ());
  } else {
    root_T_device.linear() = random_rotation(rng);
  }
  return root_T_device.inverse();
}

bool in_sight(const Chain& chain, const Truth& t, const std::vector<double>& q) {
  const Pose root_T_flange = forward(chain, t.errors, q);
  if (root_T_flange.translation().z() < 0.05) return false;
  const Pose root_T_device = t.device_T_root.inverse();
  const Pose root_T_marker = root_T_flange * t.flange_T_marker;
  const Eigen::Vector3d to_marker = (root_T_marker.translation() - root_T_device.translation()).normalized();
  const Eigen::Vector3d to_centre = (t.workspace_centre_root - root_T_device.translation()).normalized();
  switch (t.instrument) {
    case Instrument::mocap:
      return true;
    case Instrument::tracker_point:
    case Instrument::tracker_6dof:
      return to_marker.dot(to_centre) >= std::cos(40.0 * kDeg);
    case Instrument::camera:
      return to_marker.dot(to_centre) >= std::cos(25.0 * kDeg) &&
             (-to_marker).dot(root_T_marker.linear().col(2)) >= std::cos(70.0 * kDeg);
  }
  return false;
}

std::string number(double v) {
  std::ostringstream s;
  s.precision(12);
  s << v;
  return s.str();
}

}  // namespace

// Exactly, not to first order: no slide or turn in the last joint's origin error (the rule before)
// left the flange up to 0.02 mm from anywhere a fit could put it with degree-sized errors -- the
// TCP's error 3.3 times the measured point's, from a choice no measurement can show. kincal holds
// DH's theta_n and d_n, the same place.
void place_flange_as_nominal(Truth& t, const Chain& chain) {
  const Pose nominal = flange_placement(chain, ChainErrors(chain.joints.size()));
  int column = 0;  // the flange's axis farthest from the last axis: its turn about it is best defined
  nominal.linear().row(2).cwiseAbs().minCoeff(&column);
  const auto slide_and_turn = [&](const Pose& actual) {
    const Eigen::Vector3d a = nominal.linear().col(column), b = actual.linear().col(column);
    return Eigen::Vector2d(nominal.translation().z() - actual.translation().z(),
                           std::remainder(std::atan2(a.y(), a.x()) - std::atan2(b.y(), b.x()), 2.0 * M_PI));
  };
  const Eigen::Vector3d axis = chain.joints.back().axis;
  Vector6& last = t.errors.origin.back();
  const auto set_last = [&](const Pose& origin_error) {
    const Eigen::AngleAxisd turn(origin_error.linear());
    last << origin_error.translation(), turn.angle() * turn.axis();
  };
  // The last joint's zero turns the flange about the same axis: folded into its origin first.
  set_last(small_motion(last) * Eigen::AngleAxisd(t.errors.zero.back(), axis));
  t.errors.zero.back() = 0.0;
  const Eigen::Vector2d change = slide_and_turn(flange_placement(chain, t.errors));
  set_last(small_motion(last) * Eigen::AngleAxisd(change(1), axis) * Eigen::Translation3d(change(0) * axis));
  if (slide_and_turn(flange_placement(chain, t.errors)).norm() > 1e-12)
    throw std::logic_error("place_flange_as_nominal: the flange did not come back to its nominal place");
}

// Names in the enums' order.
const char* name(Instrument i) {
  static constexpr const char* names[] = {"tracker-point", "tracker-6dof", "mocap", "camera-board"};
  return names[static_cast<std::size_t>(i)];
}

const char* name(ErrorClass c) {
  static constexpr const char* names[] = {"precise", "service", "scaled", "coupled"};
  return names[static_cast<std::size_t>(c)];
}

const char* name(Mistake m) {
  static constexpr const char* names[] = {
      "-",       "mirrored-xy", "joints-swapped", "positions-swapped", "validate=train", "mm-as-m",     "deg-as-rad",
      "shifted", "moved",       "joint-reversed", "joint-zero-turned", "inches",         "marker-moved"};
  return names[static_cast<std::size_t>(m)];
}

bool measures_pose(Instrument i) { return i == Instrument::tracker_6dof || i == Instrument::camera; }

Truth make_truth(const Chain& chain, Instrument instrument, ErrorClass error_class, std::mt19937& rng,
                 const TruthScales& scales) {
  Truth t(chain.joints.size());
  t.instrument = instrument;
  const double f = scales.errors;
  if (error_class == ErrorClass::service)
    set_geometry_errors(t, chain, f * 1e-3, f * 5e-3, f * 0.2 * kDeg, f * 1.0 * kDeg, rng);
  else
    set_geometry_errors(t, chain, f * 0.1e-3, f * 0.5e-3, f * 0.01 * kDeg, f * 0.05 * kDeg, rng);
  place_flange_as_nominal(t, chain);
  if (error_class == ErrorClass::service) set_compliance(t, chain, rng);
  const std::vector<int> revolute = revolute_joints(chain);
  if (error_class == ErrorClass::scaled)
    t.errors.scale[static_cast<std::size_t>(revolute[std::uniform_int_distribution<std::size_t>(0, 2)(rng)])] =
        signed_uniform(rng, 0.002, 0.005);
  if (error_class == ErrorClass::coupled) {  // the elbow reads J3 + k J2 (Fanuc's J2 + J3 with a ratio off)
    t.errors.coupled_from = revolute[1];
    t.errors.coupled_to = revolute[2];
    t.errors.coupling = signed_uniform(rng, 0.002, 0.005);
  }
  t.flange_T_marker = marker_on_flange(chain, measures_pose(instrument), rng);
  t.workspace_centre_root = mean_flange(chain, rng);
  t.device_T_root = place_device(t.workspace_centre_root, instrument, rng);
  switch (instrument) {
    case Instrument::tracker_point:
      t.position_sigma_m.setConstant(0.02e-3);
      break;
    case Instrument::tracker_6dof:
      t.position_sigma_m.setConstant(0.02e-3);
      t.rotation_sigma_rad = 0.005 * kDeg;
      break;
    case Instrument::mocap:
      t.position_sigma_m.setConstant(0.2e-3);
      break;
    case Instrument::camera:
      t.position_sigma_m = Eigen::Vector3d(0.05e-3, 0.05e-3, 0.05e-3 * uniform(rng, 5.0, 10.0));
      t.rotation_sigma_rad = 0.02 * kDeg;
      break;
  }
  t.position_sigma_m *= scales.noise;
  t.rotation_sigma_rad *= scales.noise;
  return t;
}

std::vector<std::vector<double>> configurations(const Chain& chain, const Truth& truth, int n, std::mt19937& rng) {
  std::vector<std::vector<double>> out;
  for (int tries = 0; static_cast<int>(out.size()) < n; ++tries) {
    if (tries > 1000 * n + 100000)
      throw std::runtime_error(chain.urdf_path + ": too few configurations in the device's sight");
    std::vector<double> q = uniform_configuration(chain, rng);
    if (in_sight(chain, truth, q)) out.push_back(std::move(q));
  }
  return out;
}

Pose measured_truth(const Chain& chain, const Truth& truth, const std::vector<double>& q) {
  return truth.device_T_root * forward(chain, truth.errors, q) * truth.flange_T_marker;
}

std::vector<Row> measure(const Chain& chain, const Truth& truth, const std::vector<std::vector<double>>& qs,
                         std::mt19937& rng) {
  std::normal_distribution<double> n;
  std::vector<Row> rows;
  for (const std::vector<double>& q : qs) {
    Row r{q, Pose::Identity(), measured_truth(chain, truth, q)};
    r.measured = r.truth;
    for (int k = 0; k < 3; ++k) r.measured.translation()(k) += truth.position_sigma_m(k) * n(rng);
    if (truth.rotation_sigma_rad > 0.0) {
      Vector6 turn = Vector6::Zero();
      for (int k = 3; k < 6; ++k) turn(k) = truth.rotation_sigma_rad * n(rng);
      r.measured.linear() = small_motion(turn).linear() * r.measured.linear();
    }
    rows.push_back(std::move(r));
  }
  return rows;
}

std::string dataset_csv(const Chain& chain, const Truth& truth, const std::vector<Row>& rows,
                        const std::string& id_prefix, Mistake mistake) {
  const bool pose = measures_pose(truth.instrument), covariance = truth.instrument == Instrument::camera;
  std::ostringstream out;
  for (std::size_t j = 1; j <= chain.joints.size(); ++j) out << 'q' << j << ',';
  out << "x,y,z" << (pose ? ",qw,qx,qy,qz" : "") << (covariance ? ",cxx,cxy,cxz,cyy,cyz,czz" : "") << ",id\n";
  Eigen::Matrix3d mirror = Eigen::Matrix3d::Identity();
  if (mistake == Mistake::mirrored) mirror << 0, 1, 0, 1, 0, 0, 0, 0, 1;
  if (mistake == Mistake::positions_swapped) mirror << 1, 0, 0, 0, 0, 1, 0, 1, 0;
  const bool shifted = mistake == Mistake::out_of_step;
  Pose moved = Pose::Identity();  // the device after its move
  moved.linear() = Eigen::AngleAxisd(kDeg, Eigen::Vector3d(1.0, 2.0, 3.0).normalized()).toRotationMatrix();
  moved.translation() = Eigen::Vector3d(0.003, -0.004, 0.0);
  const std::vector<int> revolute = revolute_joints(chain);
  for (std::size_t r = 0; r + (shifted ? 1 : 0) < rows.size(); ++r) {
    std::vector<double> q = rows[r].q;
    if (mistake == Mistake::joints_swapped) std::swap(q[1], q[2]);
    if (mistake == Mistake::joint_reversed) q[static_cast<std::size_t>(revolute[1])] *= -1.0;
    if (mistake == Mistake::joint_zero_turned) q[static_cast<std::size_t>(revolute[2])] += 90.0 * kDeg;
    for (std::size_t j = 0; j < q.size(); ++j)
      out << number(mistake == Mistake::deg_as_rad && !chain.joints[j].prismatic ? q[j] / kDeg : q[j]) << ',';
    Pose measured = rows[shifted ? r + 1 : r].measured;
    if (mistake == Mistake::instrument_moved && 5 * r >= 3 * rows.size()) measured = moved * measured;
    if (mistake == Mistake::marker_moved && 5 * r >= 3 * rows.size())  // re-seated in another nest
      measured.translation() += measured.linear() * Eigen::Vector3d(0.032, -0.019, 0.014);
    Eigen::Vector3d p = mirror * measured.translation();
    if (mistake == Mistake::mm_as_m) p *= 1000.0;
    if (mistake == Mistake::inches) p /= 0.0254;
    out << number(p.x()) << ',' << number(p.y()) << ',' << number(p.z());
    if (pose) {
      // A mirrored frame turns the rotation as M R M; swapped position columns leave it alone.
      const Eigen::Matrix3d m = mistake == Mistake::mirrored ? mirror : Eigen::Matrix3d::Identity();
      Eigen::Quaterniond o(Eigen::Matrix3d(m * measured.linear() * m));
      if (o.w() < 0) o.coeffs() *= -1.0;
      out << ',' << number(o.w()) << ',' << number(o.x()) << ',' << number(o.y()) << ',' << number(o.z());
    }
    if (covariance) {
      const double unit = mistake == Mistake::mm_as_m ? 1e3 : mistake == Mistake::inches ? 1 / 0.0254 : 1.0;
      const Eigen::Vector3d v = truth.position_sigma_m.cwiseAbs2() * unit * unit;
      out << ',' << number(v.x()) << ",0,0," << number(v.y()) << ",0," << number(v.z());
    }
    out << ',' << id_prefix << r + 1 << '\n';
  }
  return out.str();
}

}  // namespace zoo

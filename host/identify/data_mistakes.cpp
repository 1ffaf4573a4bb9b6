#include "host/identify/data_mistakes.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <numbers>
#include <utility>

#include <Eigen/SVD>

#include "host/identify/statistics.hpp"

namespace kincal::identify {

std::string finding_number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", v);
  return text;
}

namespace {

const auto number = finding_number;

// The rows the fits use: every row, or kMistakeRows spread evenly over the file.
std::vector<std::size_t> sampled_rows(std::size_t count) {
  std::vector<std::size_t> rows;
  const std::size_t n = std::min<std::size_t>(count, kMistakeRows);
  for (std::size_t i = 0; i < n; ++i) rows.push_back(i * count / n);
  return rows;
}

struct ToolPoses {
  std::vector<model::Vector3> position_m;
  std::vector<model::Matrix3> rotation;
};

// A way the file's joint readings may differ from the model's convention: the readings as the
// model takes them, what was changed and what that likely means.
struct Convention {
  std::function<void(std::vector<double>&)> reading;
  std::string change;  // "joint columns 2 (a) and 3 (b) exchanged"
  std::string cause;   // "likely two joint columns swapped"
};

// The conventions tried, the simplest first (the first of those that fit as well is named): a
// joint read with its sign reversed; from a zero a quarter or half turn from the model's (not the
// first joint's nor the last's: the registration and the measured point's offset take those); two
// joint columns of one type exchanged; every column in reverse order; a sign and a zero; a
// revolute joint read relative to the one before it (a parallelogram arm's controller reports J3
// against the horizon, the model against J2's link), either way round.
std::vector<Convention> conventions(const model::RobotModel& nominal) {
  std::vector<Convention> out;
  const auto named = [&](std::size_t j) { return std::to_string(j + 1) + " (" + nominal.joints[j].name + ")"; };
  const std::size_t n = nominal.joints.size();
  const auto turnable = [&](std::size_t j) {
    return j > 0 && j + 1 < n && nominal.joints[j].type == core::JointType::revolute;
  };
  const auto one_joint = [&](std::size_t j, double sign, double turn, const char* words) {
    const std::string joint = "joint " + std::to_string(j + 1);
    std::string change = "joint " + named(j) + " read " + (sign < 0 ? "with its sign reversed" : "");
    if (turn != 0.0) change += std::string(sign < 0 ? " and " : "") + words;
    std::string cause = "likely the controller counts " + joint;
    if (sign < 0) cause += " the other way round from the model";
    if (sign < 0 && turn != 0.0) cause += ", and";
    if (turn != 0.0)
      cause += std::string(" from a zero ") + (std::abs(turn) < 3 ? "a quarter" : "a half") + " turn from the model's";
    out.push_back({[j, sign, turn](std::vector<double>& q) { q[j] = sign * q[j] + turn; }, change, cause});
  };
  const std::pair<double, const char*> turns[] = {{std::numbers::pi / 2, "plus 90 deg"},
                                                  {-std::numbers::pi / 2, "minus 90 deg"},
                                                  {std::numbers::pi, "plus 180 deg"}};
  for (std::size_t j = 0; j < n; ++j) one_joint(j, -1.0, 0.0, "");
  for (std::size_t j = 0; j < n; ++j)
    for (const auto& [turn, words] : turns)
      if (turnable(j)) one_joint(j, 1.0, turn, words);
  for (std::size_t j = 0; j < n; ++j)
    for (std::size_t k = j + 1; k < n; ++k)
      if (nominal.joints[j].type == nominal.joints[k].type)
        out.push_back({[j, k](std::vector<double>& q) { std::swap(q[j], q[k]); },
                       "joint columns " + named(j) + " and " + named(k) + " exchanged",
                       "likely two joint columns swapped"});
  bool reversible = n > 2;  // the columns in reverse order (a log that lists the joints from the tool)
  for (std::size_t j = 0; j < n; ++j)
    reversible = reversible && nominal.joints[j].type == nominal.joints[n - 1 - j].type;
  if (reversible)
    out.push_back({[](std::vector<double>& q) { std::reverse(q.begin(), q.end()); },
                   "the joint columns in reverse order", "likely the joints listed from the tool to the base"});
  for (std::size_t j = 0; j < n; ++j)
    for (const auto& [turn, words] : turns)
      if (turnable(j)) one_joint(j, -1.0, turn, words);
  for (std::size_t j = 1; j < n; ++j)
    for (const double sign : {1.0, -1.0}) {
      if (nominal.joints[j].type != core::JointType::revolute ||
          nominal.joints[j - 1].type != core::JointType::revolute)
        continue;
      out.push_back({[j, sign](std::vector<double>& q) { q[j] += sign * q[j - 1]; },
                     "joint " + named(j) + " read " + (sign > 0 ? "plus" : "minus") + " joint " + std::to_string(j) +
                         "'s reading",
                     "likely the controller reports joint " + std::to_string(j + 1) + " relative to joint " +
                         std::to_string(j) +
                         " where the model does not (or the other way round: a parallelogram arm's coupled joints)"});
    }
  return out;
}

// The nominal tool poses at the sampled rows, the readings taken by `convention` when given.
ToolPoses tool_poses(const model::RobotModel& nominal, const model::Dataset& data, const std::vector<std::size_t>& rows,
                     const Convention* convention = nullptr) {
  ToolPoses poses;
  std::vector<double> q;
  for (const std::size_t i : rows) {
    q = data.rows[i].q;
    if (convention) convention->reading(q);
    const model::Transform t = model::forward_kinematics(nominal, q);
    poses.position_m.push_back(t.translation);
    poses.rotation.push_back(t.rotation);
  }
  return poses;
}

// The alternation of the header: the registration (Kabsch with the determinant's sign chosen)
// given the offset, then the offset given the registration, until the RMS settles.
struct PointFit {
  double rms_m = std::numeric_limits<double>::infinity();
  model::Vector3 offset = model::Vector3::Zero();        // of the measured point, in the tool frame (the first part's)
  model::Matrix3 rotation = model::Matrix3::Identity();  // measured = rotation point + b (the first part's)
};

// The rows before and from `split` as two parts of the session, each with a registration of its
// own (the instrument moved), an offset of its own (the measured point moved on the arm), or both;
// split 0: one part.
struct Parts {
  std::size_t split = 0;
  bool own_registration = false;
  bool own_offset = false;
};

PointFit fitted(const ToolPoses& poses, const std::vector<model::Vector3>& measured, bool reflected,
                const Parts& parts = {}) {
  const std::size_t n = measured.size();
  const auto second = [&](std::size_t i) { return parts.split > 0 && i >= parts.split ? 1 : 0; };
  const auto registration_of = [&](std::size_t i) { return parts.own_registration ? second(i) : 0; };
  const auto offset_of = [&](std::size_t i) { return parts.own_offset ? second(i) : 0; };
  PointFit fit;
  model::Vector3 offset[2] = {model::Vector3::Zero(), model::Vector3::Zero()};
  Eigen::Matrix3d r[2] = {Eigen::Matrix3d::Identity(), Eigen::Matrix3d::Identity()};  // measured = r point + b
  model::Vector3 b[2] = {model::Vector3::Zero(), model::Vector3::Zero()};
  std::vector<model::Vector3> points(n);
  for (int pass = 0; pass < 100; ++pass) {
    for (std::size_t i = 0; i < n; ++i) points[i] = poses.position_m[i] + poses.rotation[i] * offset[offset_of(i)];
    for (int g = 0; g < 2; ++g) {
      model::Vector3 mean = model::Vector3::Zero(), measured_mean = model::Vector3::Zero();
      double count = 0.0;
      for (std::size_t i = 0; i < n; ++i)
        if (registration_of(i) == g) mean += points[i], measured_mean += measured[i], count += 1.0;
      if (count == 0.0) continue;
      mean /= count;
      measured_mean /= count;
      Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
      for (std::size_t i = 0; i < n; ++i)
        if (registration_of(i) == g) h += (points[i] - mean) * (measured[i] - measured_mean).transpose();
      const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
      Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
      const bool improper = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0;
      d(2, 2) = improper != reflected ? -1.0 : 1.0;
      r[g] = svd.matrixV() * d * svd.matrixU().transpose();
      b[g] = measured_mean - r[g] * mean;
    }
    // Each offset: r (p_i + R_i t) + b = m_i in least squares over its rows; r and R_i orthogonal,
    // so the normal matrix is a multiple of I.
    for (int g = 0; g < 2; ++g) {
      model::Vector3 sum = model::Vector3::Zero();
      double count = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        if (offset_of(i) != g) continue;
        const int k = registration_of(i);
        sum += poses.rotation[i].transpose() * (r[k].transpose() * (measured[i] - b[k]) - poses.position_m[i]);
        count += 1.0;
      }
      if (count > 0.0) offset[g] = sum / count;
    }
    double squares = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const int k = registration_of(i);
      squares +=
          (r[k] * (poses.position_m[i] + poses.rotation[i] * offset[offset_of(i)]) + b[k] - measured[i]).squaredNorm();
    }
    const double next = std::sqrt(squares / static_cast<double>(n));
    if (!(next < fit.rms_m * (1.0 - 1e-9))) {
      if (next < fit.rms_m) fit = {next, offset[0], r[0]};
      return fit;
    }
    fit = {next, offset[0], r[0]};
  }
  return fit;
}

double fitted_rms(const ToolPoses& poses, const std::vector<model::Vector3>& measured, bool reflected,
                  const Parts& parts = {}) {
  return fitted(poses, measured, reflected, parts).rms_m;
}

std::vector<model::Vector3> measured_points(const model::Dataset& data, const std::vector<std::size_t>& rows) {
  std::vector<model::Vector3> points;
  for (const std::size_t i : rows) points.push_back(data.rows[i].position);
  return points;
}

// The logs joined out of step: the readings of each sampled row with the position `shift` rows
// later in the file (earlier for a negative shift); the best shift within kMaxShiftRows and its RMS.
std::pair<double, int> best_shift(const ToolPoses& poses, const model::Dataset& data,
                                  const std::vector<std::size_t>& rows) {
  std::pair<double, int> best{std::numeric_limits<double>::infinity(), 0};
  for (int shift = -kMaxShiftRows; shift <= kMaxShiftRows; ++shift) {
    if (shift == 0) continue;
    ToolPoses paired;
    std::vector<model::Vector3> measured;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const auto at = static_cast<std::ptrdiff_t>(rows[i]) + shift;
      if (at < 0 || at >= static_cast<std::ptrdiff_t>(data.rows.size())) continue;
      paired.position_m.push_back(poses.position_m[i]);
      paired.rotation.push_back(poses.rotation[i]);
      measured.push_back(data.rows[static_cast<std::size_t>(at)].position);
    }
    if (measured.size() < 6) continue;
    const double rms = fitted_rms(paired, measured, false);
    if (rms < best.first) best = {rms, shift};
  }
  return best;
}

// Every joint moves over at least a quarter of its span in the file within the sampled rows
// [begin, end): a part where a joint stays still (a sweep of the wrist alone) cannot tell that
// joint's errors from a registration of its own.
bool moves_every_joint(const model::Dataset& data, const std::vector<std::size_t>& rows, std::size_t begin,
                       std::size_t end) {
  const auto span = [&](std::size_t j, std::size_t from, std::size_t to) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (std::size_t i = from; i < to; ++i) {
      lo = std::min(lo, data.rows[rows[i]].q[j]);
      hi = std::max(hi, data.rows[rows[i]].q[j]);
    }
    return hi - lo;
  };
  for (std::size_t j = 0; j < static_cast<std::size_t>(data.joint_count); ++j)
    if (!(span(j, begin, end) >= 0.25 * span(j, 0, rows.size()))) return false;
  return true;
}

// The instrument moved during the session: a registration of its own (and a measured point's
// offset) for the sampled rows before and from index k, at least kSplitRows each side and each
// moving every joint. The tenths of the file first, then every index within a tenth of the best
// one (a hundredth of the rows apart at most). The best k and the RMS over both parts.
std::pair<double, std::size_t> best_split(const ToolPoses& poses, const std::vector<model::Vector3>& measured,
                                          const model::Dataset& data, const std::vector<std::size_t>& rows) {
  const std::size_t n = measured.size();
  std::pair<double, std::size_t> best{std::numeric_limits<double>::infinity(), 0};
  const auto try_split = [&](std::size_t k) {
    if (k < kSplitRows || n - k < kSplitRows) return;
    if (!moves_every_joint(data, rows, 0, k) || !moves_every_joint(data, rows, k, n)) return;
    const double rms = fitted_rms(poses, measured, false, {k, true, true});
    if (rms < best.first) best = {rms, k};
  };
  for (std::size_t tenth = 1; tenth < 10; ++tenth) try_split(n * tenth / 10);
  if (best.second == 0) return best;
  const std::size_t centre = best.second, reach = n / 10, step = std::max<std::size_t>(1, n / 100);
  for (std::size_t k = centre > reach ? centre - reach : 0; k <= std::min(n, centre + reach); k += step) try_split(k);
  return best;
}

// The sentence for a move found at sampled row `from` (best_split's), the parts fitting to `split`
// m RMS where one registration leaves `one`: which moved -- the instrument (a registration of its
// own, the same measured point) or the measured point on the arm (its own offset, the same
// registration); each fits as well as both together where it is the cause. Neither alone: both
// moved, or a wrong model's error.
std::string move_finding(const ToolPoses& poses, const std::vector<model::Vector3>& measured,
                         const model::Dataset& data, const std::vector<std::size_t>& rows, double split,
                         std::size_t from, double one) {
  const int first = data.rows.front().line, at = data.rows[rows[from]].line, before = data.rows[rows[from] - 1].line,
            last = data.rows.back().line;
  const double instrument = fitted_rms(poses, measured, false, {from, true, false});
  const double point = fitted_rms(poses, measured, false, {from, false, true});
  const bool point_moved = point < instrument && point <= kSameFit * split;
  const bool instrument_moved = instrument <= point && instrument <= kSameFit * split;
  const std::string what = point_moved        ? "an offset of their own from the tool"
                           : instrument_moved ? "a registration of their own"
                                              : "a registration and an offset from the tool of their own";
  const std::string cause =
      point_moved ? "the measured point moved on the arm during the session (a reflector re-seated in another "
                    "nest, a marker knocked)"
      : instrument_moved
          ? "the instrument (or the robot's base) moved during the session"
          : "the instrument and the measured point moved during the session (or a model far off the arm)";
  return "the positions fit far better with " + what + " from about line " + std::to_string(at) +
         " on: " + number(split * 1e3) + " mm RMS against " + number(one * 1e3) + " mm with one: likely " + cause +
         "; calibrate with the rows of one part (lines " + std::to_string(first) + "-" + std::to_string(before) +
         " or " + std::to_string(at) + "-" + std::to_string(last) + ")";
}

}  // namespace

FrameCheck frame_check(const model::RobotModel& nominal, const model::Dataset& data) {
  FrameCheck out;
  if (data.rows.size() < 6 || data.joint_count != nominal.joint_count()) return out;
  const std::vector<std::size_t> rows = sampled_rows(data.rows.size());
  const std::vector<model::Vector3> measured = measured_points(data, rows);
  const ToolPoses poses = tool_poses(nominal, data, rows);
  const PointFit fit = fitted(poses, measured, false);
  if (fit.offset.norm() <= kMaxMeasuredPointOffset_m) out.measured_point_offset = fit.offset;
  const double rotated = fit.rms_m;
  if (!(rotated > kMistakeFloor_m)) {
    out.registration_rotation = fit.rotation;
    return out;
  }
  const double mirrored = fitted_rms(poses, measured, true);
  if (mirrored * 5.0 < rotated)
    out.mistakes.push_back(
        "the measured points are a mirror image of the model's: registered by a rotation they leave " +
        number(rotated * 1e3) + " mm RMS, by a reflection " + number(mirrored * 1e3) +
        " mm: likely two position columns swapped or an axis flipped (a left-handed device frame)");
  // The joint readings in another convention than the model's: when the best fits far better, the
  // simplest of those that fit as well is named, and up to three others beside it (a spherical
  // wrist's fifth joint counted the other way round is its fourth half a turn on, the last joint's
  // turn taken by the measured point).
  const std::vector<Convention> tried = conventions(nominal);
  std::vector<double> rms(tried.size());
  for (std::size_t c = 0; c < tried.size(); ++c)
    rms[c] = fitted_rms(tool_poses(nominal, data, rows, &tried[c]), measured, false);
  const auto best = std::min_element(rms.begin(), rms.end());
  if (best != rms.end() && *best * 5.0 < rotated) {
    std::size_t found = tried.size(), as_well = 0;
    std::string others;
    for (std::size_t c = 0; c < tried.size(); ++c) {
      if (!(rms[c] <= kSameFit * *best)) continue;
      if (found == tried.size())
        found = c;
      else if (as_well++ < 3)
        others += (others.empty() ? " (as well: " : "; ") + tried[c].change;
    }
    out.mistakes.push_back("the readings fit far better with " + tried[found].change +
                           (others.empty() ? "" : others + ")") + ": " + number(rms[found] * 1e3) + " mm RMS against " +
                           number(rotated * 1e3) + " mm as given: " + tried[found].cause);
  }
  const auto [shifted, shift] = best_shift(poses, data, rows);
  if (shifted * 5.0 < rotated) {
    const std::string by = std::to_string(std::abs(shift)) + (std::abs(shift) == 1 ? " row " : " rows ");
    out.mistakes.push_back("the positions fit far better " + by + (shift > 0 ? "later" : "earlier") +
                           " in the file than their readings: " + number(shifted * 1e3) + " mm RMS against " +
                           number(rotated * 1e3) +
                           " mm as given: likely the robot's and the instrument's logs joined out of step by " + by +
                           "(each row's position measured at another row's readings)");
  }
  // Two registrations absorb some of a wrong model's error too: the move's must fit the points to
  // an arm's accuracy (below kMistakeFloor_m), not merely better.
  const auto [split, from] = best_split(poses, measured, data, rows);
  if (split * kMovedRatio < rotated && split < kMistakeFloor_m)
    out.mistakes.push_back(move_finding(poses, measured, data, rows, split, from, rotated));
  return out;
}

std::optional<std::string> moved_against(const model::RobotModel& calibrated, const model::Dataset& data,
                                         bool fit_unexplained, int identified_parameters) {
  if (data.rows.size() < 2 * kSplitRows || data.joint_count != calibrated.joint_count()) return std::nullopt;
  const std::vector<std::size_t> rows = sampled_rows(data.rows.size());
  const std::vector<model::Vector3> measured = measured_points(data, rows);
  const ToolPoses poses = tool_poses(calibrated, data, rows);
  const double one = fitted(poses, measured, false).rms_m;
  const auto [split, from] = best_split(poses, measured, data, rows);
  // The F test of the second part's 9 parameters: the sums of squares are the rows' count times
  // the RMS squared, the count cancels.
  const auto significant = [&, split = split] {
    const double rest = 3.0 * static_cast<double>(rows.size()) - identified_parameters - 9.0;
    if (!(rest >= 1.0) || !(split > 0.0)) return false;
    const double f = ((one * one - split * split) / 9.0) / (split * split / rest);
    return 1.0 - fisher_cdf(f, 9.0, rest) < kMoveSignificance;
  };
  const bool found =
      split * kCalibratedMovedRatio < one || (fit_unexplained && split * kUnexplainedMovedRatio < one && significant());
  if (!found) return std::nullopt;
  return move_finding(poses, measured, data, rows, split, from, one);
}

std::optional<std::string> unexplained_fit(double rms_m, double instrument_sigma_m) {
  if (!(rms_m > kMistakeFloor_m)) return std::nullopt;
  if (instrument_sigma_m > 0.0 && rms_m <= kMistakeNoiseRatio * instrument_sigma_m) return std::nullopt;
  std::string what = "the calibrated model leaves " + number(rms_m * 1e3) + " mm RMS";
  if (instrument_sigma_m > 0.0) what += ", " + number(rms_m / instrument_sigma_m) + " times the instrument's noise";
  return what +
         ": no arm deviates so far from its geometry, so the data do not fit this model -- likely a mirrored "
         "or swapped position column, swapped joint columns, a joint counted the other way round or from another zero, "
         "joints or positions in other units, the robot's and "
         "the instrument's logs joined out of step, the instrument or the measured point moved during the "
         "session, another robot's model, or the wrong --tip-link";
}

std::optional<std::string> overstated_noise(double rms_m, double instrument_sigma_m, int equations, int parameters) {
  if (!(instrument_sigma_m > 0.0) || equations - parameters < kMinNoiseDegrees) return std::nullopt;
  // The residuals' expected RMS per axis with that noise: sigma sqrt(dof / equations).
  const double expected_m =
      instrument_sigma_m * std::sqrt(static_cast<double>(equations - parameters) / static_cast<double>(equations));
  const double per_axis_m = rms_m / std::sqrt(3.0);
  if (!(per_axis_m * kOverstatedNoiseRatio < expected_m)) return std::nullopt;
  return "the residuals, " + number(per_axis_m * 1e3) + " mm RMS per axis, are " + number(expected_m / per_axis_m) +
         " times smaller than the instrument noise given (" + number(instrument_sigma_m * 1e3) +
         " mm per axis) allows: no data scatter so far below their noise -- likely --sigma, or the data's sigma or "
         "covariance columns, in mm (mm^2) where kincal takes m (m^2); the standard deviations, the priors' weight "
         "against the data, the outlier test and correct's spreads took the noise as given: give it in m";
}

std::optional<std::string> unexplained_orientations(double rms_rad, double instrument_sigma_rad) {
  if (!(rms_rad > kOrientationFloor_rad)) return std::nullopt;
  if (instrument_sigma_rad > 0.0 && rms_rad <= kMistakeNoiseRatio * instrument_sigma_rad) return std::nullopt;
  return "the calibrated model leaves " + number(rms_rad * 180.0 / std::numbers::pi) +
         " deg RMS in orientation: no arm turns so far from its model, so the orientations do not fit it -- likely "
         "another Euler convention than the export's (intrinsic for extrinsic, another order of the axes), "
         "quaternions in another order or inverted, or the orientation of another frame than the positions'; the "
         "solve weighed them by their misfit, so the positions' fit stands on its own";
}

SharedRows training_rows_in(const model::Dataset& held_out, const model::Dataset& training) {
  // The training rows sorted by their readings' key: each held-out row compares with those within
  // the key's window of it only.
  std::vector<std::pair<double, const model::Measurement*>> sorted;
  for (const model::Measurement& r : training.rows) sorted.emplace_back(model::reading_key(r.q), &r);
  std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  const double window = model::reading_key_window(static_cast<std::size_t>(training.joint_count));
  SharedRows shared;
  for (const model::Measurement& r : held_out.rows) {
    const double key = model::reading_key(r.q);
    auto it = std::lower_bound(sorted.begin(), sorted.end(), key - window,
                               [](const auto& a, double v) { return a.first < v; });
    bool configuration = false, row = false;
    for (; it != sorted.end() && it->first <= key + window && !row; ++it) {
      if (!model::same_readings(r, *it->second)) continue;
      configuration = true;
      row = (it->second->position - r.position).cwiseAbs().maxCoeff() <= kSamePosition_m;
    }
    shared.configurations += configuration ? 1 : 0;
    shared.rows += row ? 1 : 0;
  }
  return shared;
}

}  // namespace kincal::identify

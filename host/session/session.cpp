#include "host/session/session.hpp"

#include <filesystem>
#include <optional>
#include <ostream>

#include "host/session/journal.hpp"
#include "host/session/progress.hpp"

namespace kincal::session {

namespace {

// Rows of `all` (in plan order, complete) split into calibration and validation datasets.
SessionData split(const model::Dataset& all, std::size_t calibration_count) {
  SessionData out;
  out.calibration = all;
  out.validation = all;
  out.calibration.rows.assign(all.rows.begin(), all.rows.begin() + static_cast<std::ptrdiff_t>(calibration_count));
  out.validation.rows.assign(all.rows.begin() + static_cast<std::ptrdiff_t>(calibration_count), all.rows.end());
  return out;
}

}  // namespace

SessionData run_session(const model::RobotModel& nominal, const SessionPlan& plan, RobotDriver& driver, Sensor& sensor,
                        const SessionOptions& options, std::ostream& log) {
  if (plan.calibration.empty()) throw SessionError("the session's plan has no calibration poses");
  JournalIdentity identity;
  identity.joint_count = nominal.joint_count();
  identity.orientation = sensor.gives_orientation();
  identity.covariance = sensor.gives_covariance();
  identity.pose_covariance = sensor.gives_pose_covariance();
  identity.items = options.identity;
  identity.items["poses"] = std::to_string(plan.total());
  std::optional<Journal> journal;
  if (options.resume) {
    journal.emplace(Journal::resume(options.journal_path, identity));
    for (const std::string& note : journal->notes()) log << "journal: " << note << "\n";
  } else {
    if (std::filesystem::exists(options.journal_path))
      throw SessionError(options.journal_path + ": a journal already exists (add --resume to continue it)");
    journal.emplace(Journal::create(options.journal_path, identity));
  }

  const int total = plan.total();
  int already = 0;
  for (int i = 0; i < total; ++i) already += journal->done(i);
  Progress progress(log, options.progress_terminal, "measuring", total, already);
  for (int i = 0; i < total; ++i) {
    if (journal->done(i)) continue;
    const auto index = static_cast<std::size_t>(i);
    const std::vector<double>& target =
        index < plan.calibration.size() ? plan.calibration[index] : plan.validation[index - plan.calibration.size()];
    const std::vector<double> readings = driver.move_to(i, target);
    if (readings.size() != target.size())
      throw SessionError("pose " + std::to_string(i) + ": the robot driver gave " + std::to_string(readings.size()) +
                         " readings for " + std::to_string(target.size()) + " joints");
    const Observation o = sensor.measure(i, model::forward_kinematics(nominal, readings));
    JournalRecord record;
    record.pose_index = i;
    record.sequence = o.sequence;
    record.platform_time_us = static_cast<std::uint64_t>(o.timestamp_s * 1e6);
    record.q = readings;
    record.position_m = o.position;
    record.orientation = o.orientation;
    record.covariance_m2 = o.covariance;
    record.pose_covariance = o.pose_covariance;
    journal->append(record);
    progress.step(o.note);
  }
  progress.finish();
  SessionData data = split(journal->dataset(), plan.calibration.size());
  data.resumed = already;
  return data;
}

Calibration calibrate(const model::RobotModel& nominal, const SessionData& data,
                      const identify::IdentifyOptions& options) {
  Calibration c;
  c.result = identify::identify(nominal, data.calibration, options);
  if (!data.validation.rows.empty()) {
    c.before = identify::accuracy(nominal, data.validation);
    c.after = identify::accuracy(c.result.model, data.validation);
  }
  return c;
}

}  // namespace kincal::session

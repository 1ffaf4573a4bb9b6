// `kincal session`: a calibration session (host/session/session.hpp) from the command line.
//
//   kincal session --model FILE [--rig platform|stereo] [--plan FILE | --sweeps N [--home Q] | --poses N]
//                  [--validation N | --validation-plan FILE]
//                  [--robot sim|manual | --robot-cmd 'CMD {q}'] [--can IF [--fd]] [--squares N]
//                  [--journal FILE] [--resume] [--out FILE] [--report FILE] [--dataset FILE] [--seed S]
//
// The simulated robot (the default) comes with its simulated rig: the model file with hidden
// errors, the platform's firmware in-process on a loopback bus or the stereo pair. A real robot
// (--robot manual or --robot-cmd) is measured by the sensor platform on a SocketCAN interface
// (--can, required) looking at a strip of --squares calibration squares; it visits only the
// poses of plan files (--plan, --validation-plan), never random ones.
// Exit status 0, or 1 with a message naming what failed (and, for a stopped session, the pose and
// how to resume).
#include "host/cli/session_command.hpp"

#include <unistd.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <random>
#include <sstream>

#include "host/can/socketcan.hpp"
#include "host/cli/model_option.hpp"
#include "host/demo/simulated_rig.hpp"
#include "host/files/output_file.hpp"
#include "host/identify/plausibility.hpp"
#include "host/model/model_file.hpp"
#include "host/report/report.hpp"
#include "host/session/online_correction.hpp"
#include "host/session/session.hpp"
#include "host/session/session_report.hpp"
#include "host/sim/robot.hpp"

namespace kincal::cli {

namespace {

struct SessionArgs {
  ModelOption model;
  std::string rig = "platform", plan, validation_plan, home, robot = "sim", robot_cmd, can, journal = "session.journal";
  std::string out, report, dataset;
  int sweeps = 0, poses = 40, validation = 20, squares = 8;
  bool fd = false, resume = false, accept_implausible = false;
  std::uint64_t seed = 1;
};

std::vector<double> parse_home(const std::string& text, const model::RobotModel& m) {
  const std::vector<double> q = session::parse_readings(text, static_cast<std::size_t>(m.joint_count()));
  if (q.empty())
    throw model::InputError("--home '" + text + "': not " + std::to_string(m.joint_count()) + " joint readings");
  return q;
}

// The middle of each joint's limits (0 without limits): the sweeps' default home.
std::vector<double> mid_range(const model::RobotModel& m) {
  std::vector<double> q;
  for (const model::Joint& j : m.joints)
    q.push_back(std::isfinite(j.lower) && std::isfinite(j.upper) ? (j.lower + j.upper) / 2 : 0.0);
  return q;
}

// `count` random configurations the simulated rig can measure, drawn within the joint limits. The
// draws are bounded: a robot whose workspace the rig cannot see fails with the numbers instead of
// drawing forever.
std::vector<std::vector<double>> random_observable(const model::RobotModel& nominal, const session::SimulatedRig& rig,
                                                   int count, std::mt19937_64& rng, const char* what) {
  const long attempts = 1000 + 200L * count;
  std::vector<std::vector<double>> poses;
  for (long i = 0; i < attempts && static_cast<int>(poses.size()) < count; ++i) {
    std::vector<double> q = sim::random_configuration(nominal, rng);
    if (rig.observable(q)) poses.push_back(std::move(q));
  }
  if (static_cast<int>(poses.size()) < count)
    throw model::InputError(std::string(what) + ": " + std::to_string(poses.size()) + " of " +
                            std::to_string(attempts) + " random configurations of " + nominal.name +
                            " within its joint limits are in view of the simulated rig, " + std::to_string(count) +
                            " needed: the rig cannot see this robot's workspace (give --plan/--validation-plan "
                            "with poses it can see, or fewer poses)");
  return poses;
}

// A plan file read against the rig's model. A simulated rig may narrow joint limits (the ARID rig
// keeps its rail within 0.1 m so that the camera stays over the strip): a plan made from the
// model file then fails, and the error says which limits the rig narrowed and why.
std::vector<std::vector<double>> read_plan_for(const model::RobotModel& file, const model::RobotModel& nominal,
                                               const std::string& path) {
  try {
    return session::read_plan(nominal, path);
  } catch (const model::InputError& e) {
    std::string narrowed;
    for (std::size_t j = 0; j < nominal.joints.size() && j < file.joints.size(); ++j) {
      const model::Joint &rig = nominal.joints[j], &given = file.joints[j];
      if (rig.lower != given.lower || rig.upper != given.upper) {
        std::ostringstream text;
        text << (narrowed.empty() ? "" : ", ") << rig.name << " [" << rig.lower << ", " << rig.upper << "] instead of ["
             << given.lower << ", " << given.upper << "]";
        narrowed += text.str();
      }
    }
    if (narrowed.empty()) throw;
    throw model::InputError(std::string(e.what()) + "\n  the simulated rig narrows its model's limits (SI units) to " +
                            narrowed +
                            " so that the sensor sees the target; make the plan within these limits, or "
                            "leave --plan out to let the rig draw poses it can see");
  }
}

int run(const SessionArgs& a) {
  files::refuse_overwriting({{"--out", a.out}, {"--report", a.report}, {"--dataset", a.dataset}},
                            {{"--journal", a.journal},
                             {"--model", a.model.path},
                             {"--plan", a.plan},
                             {"--validation-plan", a.validation_plan}});
  const model::RobotModel file = a.model.load();
  const bool simulated = a.robot == "sim" && a.robot_cmd.empty();
  const bool platform = a.rig == "platform";

  std::unique_ptr<session::SimulatedRig> rig;
  std::unique_ptr<can::Transport> transport;
  std::unique_ptr<can::PlatformClient> client;
  std::unique_ptr<session::RobotDriver> driver;
  std::unique_ptr<session::Sensor> sensor;
  if (simulated) {
    if (!a.can.empty())
      throw model::InputError(
          "--can: the simulated robot brings its own simulated platform; use --robot manual or "
          "--robot-cmd with a real platform");
    session::RigOptions o;
    o.seed = a.seed;
    o.fd = a.fd;
    rig = session::make_simulated_rig(platform ? session::RigKind::platform : session::RigKind::stereo, file, o);
  } else {
    if (!platform)
      throw model::InputError(
          "--rig stereo: a real stereo pair is calibrated with `kincal camera`; "
          "sessions with real cameras run the platform rig");
    if (a.can.empty()) throw model::InputError("a real robot is measured by the platform: --can IF is required");
    if (a.plan.empty()) throw model::InputError("a real robot visits only planned poses: --plan FILE is required");
    transport = std::make_unique<can::SocketCanTransport>(a.can, can::SocketCanOptions{a.fd, true, {}});
    client = std::make_unique<can::PlatformClient>(*transport);
    sensor = std::make_unique<session::PlatformPoseSensor>(*client, session::strip_square_poses(a.squares));
    if (!a.robot_cmd.empty())
      driver = std::make_unique<session::CommandRobotDriver>(a.robot_cmd);
    else
      driver = std::make_unique<session::ManualRobotDriver>(std::cin, std::cerr);
  }
  const model::RobotModel& nominal = rig ? rig->nominal() : file;
  session::RobotDriver& robot = rig ? rig->driver() : *driver;
  session::Sensor& measure = rig ? rig->sensor() : *sensor;

  session::SessionPlan plan;
  std::mt19937_64 rng(a.seed);
  if (!a.plan.empty()) {
    plan.calibration = read_plan_for(file, nominal, a.plan);
  } else if (a.sweeps > 0 || !platform) {
    const std::vector<double> home = a.home.empty() ? mid_range(nominal) : parse_home(a.home, nominal);
    plan.calibration = session::single_joint_sweeps(nominal, home, a.sweeps > 0 ? a.sweeps : 10, 0.4);
  } else {
    plan.calibration = random_observable(nominal, *rig, a.poses, rng, "--poses");
  }
  if (!a.validation_plan.empty()) {
    plan.validation = read_plan_for(file, nominal, a.validation_plan);
  } else if (rig) {
    plan.validation = random_observable(nominal, *rig, a.validation, rng, "--validation");
  }

  session::SessionOptions options;
  options.journal_path = a.journal;
  options.resume = a.resume;
  options.progress_terminal = ::isatty(STDERR_FILENO) != 0;
  std::ostringstream identity;
  identity << "model=" << a.model.path << " rig=" << a.rig << " robot=" << (simulated ? "sim" : "real")
           << " seed=" << a.seed << " plan=" << (a.plan.empty() ? "generated" : a.plan) << " sweeps=" << a.sweeps
           << " home=" << a.home
           << " validation=" << (a.validation_plan.empty() ? std::to_string(a.validation) : a.validation_plan);
  options.identity = identity.str();
  const session::SessionData data = session::run_session(nominal, plan, robot, measure, options, std::cerr);
  if (!a.dataset.empty()) {
    std::ostringstream csv;
    model::Dataset all = data.calibration;
    all.rows.insert(all.rows.end(), data.validation.rows.begin(), data.validation.rows.end());
    model::write_dataset(csv, all);
    files::write_file_atomically(a.dataset, csv.str());
  }

  if (!a.accept_implausible) identify::require_plausible(nominal, data.calibration, "--accept-implausible");
  identify::IdentifyOptions io;
  if (!platform) io.start = identify::Start::cpa;
  const session::Calibration calibration = session::calibrate(nominal, data, io);
  std::cout << identify::format_report(calibration.result);
  if (!data.validation.rows.empty())
    std::cout << "validation (" << data.validation.rows.size() << " poses): nominal RMS "
              << calibration.before.rms_m * 1e3 << " mm, identified RMS " << calibration.after.rms_m * 1e3 << " mm\n";
  if (!a.out.empty()) model::save_model(calibration.result.model, a.out);

  std::optional<session::CorrectionCheck> check;
  can::PlatformClient* platform_client = rig ? rig->platform() : client.get();
  if (platform && platform_client && !data.validation.rows.empty()) {
    check = session::verify_online_correction(*platform_client, a.fd, calibration, data, robot, measure, std::cout);
    std::cout << "online correction on the validation targets: RMS " << check->before.rms_m * 1e3 << " mm -> "
              << check->after.rms_m * 1e3 << " mm\n";
  }
  if (!a.report.empty()) {
    session::RunDescription d;
    d.title = "Calibration session: " + file.name;
    d.robot = file.name;
    d.method = platform ? "full nonlinear least squares" : "circle-point analysis, then full least squares";
    d.data = a.journal;
    d.simulated = simulated;
    report::Report r;
    r.title = "kincal session";
    r.runs.push_back(session::report_run(d, nominal, data, calibration,
                                         rig ? std::optional<model::RobotModel>(rig->truth()) : std::nullopt, nullptr));
    report::write_html(r, a.report);
    std::cout << "report: " << a.report << "\n";
  }
  return 0;
}

}  // namespace

void add_session_command(CLI::App& app, int& status) {
  auto a = std::make_shared<SessionArgs>();
  auto* cmd = app.add_subcommand("session", "Run a calibration session: move, measure, journal, identify, upload");
  add_model_option(*cmd, a->model, "robot model");
  cmd->add_option("--rig", a->rig, "platform (camera + rangers over CAN) or stereo (beacon and stereo pair)")
      ->check(CLI::IsMember({"platform", "stereo"}))
      ->capture_default_str();
  cmd->add_option("--plan", a->plan, "calibration poses (joints CSV, e.g. from `kincal plan`)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--sweeps", a->sweeps, "single-joint sweeps with this many readings per joint")
      ->check(CLI::Range(4, 1000));
  cmd->add_option("--poses", a->poses, "random calibration poses in view (simulated robot, platform rig)")
      ->check(CLI::Range(1, 10000))
      ->capture_default_str();
  cmd->add_option("--home", a->home, "home readings of the sweeps, comma-separated (rad, m)");
  cmd->add_option("--validation", a->validation, "random validation poses (simulated robot)")
      ->check(CLI::Range(0, 10000))
      ->capture_default_str();
  cmd->add_option("--validation-plan", a->validation_plan, "validation poses (joints CSV)")->check(CLI::ExistingFile);
  cmd->add_option("--robot", a->robot, "sim or manual")->check(CLI::IsMember({"sim", "manual"}))->capture_default_str();
  cmd->add_option("--robot-cmd", a->robot_cmd, "command that moves the robot; {q} = the joint values");
  cmd->add_option("--can", a->can, "SocketCAN interface of a real platform (e.g. can0, vcan0)");
  cmd->add_flag("--fd", a->fd, "CAN FD");
  cmd->add_option("--squares", a->squares, "calibration squares on the strip (real platform)")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  cmd->add_option("--journal", a->journal, "the session's measurement journal")->capture_default_str();
  cmd->add_flag("--resume", a->resume, "continue the journal of a stopped session");
  cmd->add_option("--out", a->out, "write the identified model here (YAML)");
  cmd->add_option("--report", a->report, "write the HTML report here");
  cmd->add_option("--dataset", a->dataset, "write the measurements here (dataset CSV)");
  cmd->add_flag("--accept-implausible", a->accept_implausible,
                "identify even when the measurements look wrong for the model (units, quaternion order)");
  cmd->add_option("--seed", a->seed, "seed of the simulated robot's hidden errors and noise")->capture_default_str();
  cmd->callback([a, &status] {
    try {
      status = run(*a);
    } catch (const std::exception& e) {
      std::cerr << "\nkincal session: " << e.what() << "\n";
      if (dynamic_cast<const session::SessionError*>(&e))
        std::cerr << "kincal session: the journal " << a->journal
                  << " keeps every measurement so far; run again with --resume to continue\n";
      status = 1;
    }
  });
}

}  // namespace kincal::cli

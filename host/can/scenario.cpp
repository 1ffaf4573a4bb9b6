#include "host/can/scenario.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include <Eigen/Cholesky>

#include "firmware/app/correction_chain.hpp"
#include "firmware/core/correction.hpp"

namespace kincal::can {

shared::CorrectionParameters scenario_correction_parameters() {
  shared::CorrectionParameters c;
  c.joint_count = 6;
  const float half_pi = 1.5707964f;
  // {a_m, alpha_rad, d_m, theta_rad, beta_rad}; link i holds Craig's alpha_{i-1}, a_{i-1}.
  const shared::DhValues puma[6] = {
      {0, 0, 0, 0, 0},       {0, -half_pi, 0, 0, 0}, {0.4318f, 0, 0.15005f, 0, 0}, {0.0203f, -half_pi, 0.4318f, 0, 0},
      {0, half_pi, 0, 0, 0}, {0, -half_pi, 0, 0, 0}};
  const shared::DhValues errors[6] = {{0, 0, 0, 5.0e-4f, 0},
                                      {2.0e-4f, 3.0e-4f, -1.0e-4f, -3.0e-4f, 0},
                                      {-3.0e-4f, -2.0e-4f, 2.0e-4f, 2.0e-4f, 0},
                                      {1.0e-4f, 1.5e-4f, -2.0e-4f, -1.0e-4f, 0},
                                      {-1.0e-4f, -2.5e-4f, 1.0e-4f, 5.0e-5f, 0},
                                      {5.0e-5f, 1.0e-4f, 3.0e-4f, 4.0e-4f, 0}};
  for (std::size_t j = 0; j < shared::kJoints; ++j) {
    c.joints[j].nominal = puma[j];
    c.joints[j].error = errors[j];
  }
  c.tool_offset = {0.0f, 0.0f, 0.12f, 0.0f, 0.0f, 0.0f};
  c.tool_error = {1.0e-4f, -1.0e-4f, 2.0e-4f, 1.0e-4f, 2.0e-4f, -1.0e-4f};
  // The joint map: the controller reports the elbow relative to the shoulder (Fanuc-style: the
  // chain's joint 3 is reading 2 + reading 3), the gears of joints 1-3 are off by a few hundred
  // ppm, and shoulder and elbow give way under gravity (the controller's model knows none of it:
  // nominal compliance 0). Masses after Armstrong et al.'s PUMA 560, a 2 kg payload.
  c.joint_maps[2].coupled = true;
  c.joint_maps[2].coupling = {0.0f, 1.0f, 1.0f, 0.0f, 0.0f, 0.0f};
  const float scale_errors[6] = {3.0e-4f, -2.0e-4f, 4.0e-4f, 0.0f, 0.0f, 0.0f};
  const float compliance_errors[6] = {0.0f, 1.5e-5f, 2.5e-5f, 0.0f, 0.0f, 0.0f};  // rad/(N m)
  const float mass_kg[6] = {0.0f, 17.4f, 4.8f, 0.82f, 0.34f, 0.09f};
  const std::array<float, 3> centre_m[6] = {
      {0, 0, 0}, {0.068f, 0.006f, -0.016f}, {0, -0.07f, 0.014f}, {0, 0, -0.019f}, {0, 0, 0}, {0, 0, 0.032f}};
  for (std::size_t j = 0; j < shared::kJoints; ++j) {
    c.joint_maps[j].scale_error = scale_errors[j];
    c.joint_maps[j].compliance_error = compliance_errors[j];
    c.joint_maps[j].mass_kg = mass_kg[j];
    c.joint_maps[j].centre_of_mass_m = centre_m[j];
  }
  c.payload_mass_kg = 2.0f;
  c.payload_centre_of_mass_m = {0.0f, 0.0f, 0.1f};
  return c;
}

std::array<double, shared::kJoints> reference_correction(const shared::CorrectionParameters& parameters,
                                                         const std::array<std::int32_t, shared::kJoints>& joints) {
  core::ChainModel<double> nominal, calibrated;
  core::ParameterSet ids;
  core::ErrorVector<double> errors;
  if (app::correction_chain(parameters, nominal, ids, errors) != app::ChainStatus::kOk ||
      core::apply_parameter_errors(nominal, ids, errors, calibrated) != core::ErrorModelStatus::ok)
    throw std::invalid_argument("reference_correction: the correction block does not describe a chain");
  core::JointMap<double> nominal_map, identified_map;
  core::MassModel<double> masses;
  core::CouplingMatrix<double> scratch, inverse_coupling;
  if (app::correction_joint_maps(parameters, nominal_map, identified_map, masses) != app::ChainStatus::kOk ||
      !core::invert_coupling(identified_map, scratch, inverse_coupling))
    throw std::invalid_argument("reference_correction: the correction block's joint map cannot be inverted");
  core::PreparedChain<double> nominal_chain, calibrated_chain;
  core::prepare_chain(nominal, nominal_chain);
  core::prepare_chain(calibrated, calibrated_chain);
  const int n = nominal.joint_count;
  core::JointVector<double> readings = core::JointVector<double>::Zero();
  for (int i = 0; i < n; ++i) readings(i) = shared::joint_angle_rad<double>(joints[static_cast<std::size_t>(i)]);
  // The nominal joint map (core::correct_joint_readings): readings -> the nominal chain's variables.
  core::DeflectionWorkspace<double> deflection;
  core::JointVector<double> coupled, q;
  core::coupled_values(nominal_map, readings, coupled);
  core::deflect(nominal_chain, masses, nominal_map.compliance, coupled, deflection, q);

  std::array<core::SinCos<double>, core::kMaxJoints> trig;
  core::joint_trig(nominal_chain, q, trig);
  core::RigidTransform<double> base_T_target, base_T_tool;
  core::tool_pose(nominal_chain, q, trig, base_T_target);
  core::ChainFrames<double> frames;
  core::forward_kinematics(calibrated_chain, q, trig, frames);
  core::JointJacobian<double> jacobian;
  core::joint_jacobian(calibrated_chain, frames, jacobian);

  // The damped step of correction.hpp: (J^T W J + lambda^2 I) dq = J^T W e, then chord steps
  // with the same matrix.
  const core::CorrectionOptions options;
  const double weight = static_cast<double>(options.rotation_weight_m), weight2 = weight * weight;
  const double damping = static_cast<double>(options.damping_m);
  const Eigen::Matrix<double, 6, 1> w(1, 1, 1, weight2, weight2, weight2);
  const Eigen::MatrixXd j = jacobian.leftCols(n);
  const Eigen::MatrixXd normal =
      j.transpose() * w.asDiagonal() * j + Eigen::MatrixXd::Identity(n, n) * (damping * damping);
  const Eigen::LLT<Eigen::MatrixXd> factor(normal);
  core::JointVector<double> target = q;
  core::Twist<double> error = core::small_pose_difference(base_T_target, frames.base_T_tool);
  for (int step = 0; step <= options.refinement_steps; ++step) {
    if (step > 0) {
      core::joint_trig(calibrated_chain, target, trig);
      core::tool_pose(calibrated_chain, target, trig, base_T_tool);
      error = core::small_pose_difference(base_T_target, base_T_tool);
    }
    const Eigen::VectorXd rhs = j.transpose() * w.asDiagonal() * error;
    target.head(n) += factor.solve(rhs);
  }
  // The identified joint map's inverse: chain variables -> readings.
  coupled = q;  // the first pass from the chain target, as the platform does
  core::undeflect(calibrated_chain, masses, identified_map.compliance, target, core::kUndeflectPasses, deflection,
                  coupled);
  core::JointVector<double> corrected;
  core::readings_from_coupled(identified_map, inverse_coupling, coupled, corrected);
  std::array<double, shared::kJoints> out{};
  for (std::size_t i = 0; i < shared::kJoints; ++i)
    out[i] = static_cast<int>(i) < n ? corrected(static_cast<int>(i)) : shared::joint_angle_rad<double>(joints[i]);
  return out;
}

namespace {

template <class Block>
std::vector<std::uint8_t> image_of(const Block& block, std::size_t size) {
  std::vector<std::uint8_t> image(size);
  shared::encode_block(block, image);
  return image;
}

}  // namespace

ScenarioResult run_platform_scenario(PlatformClient& client, const ScenarioOptions& options, std::ostream& log) {
  ScenarioResult result;
  auto check = [&result, &log](bool ok, const std::string& what) {
    if (!ok) {
      result.failures.push_back(what);
      log << "scenario: FAILED " << what << "\n";
    }
    return ok;
  };

  const shared::Heartbeat first = client.wait_heartbeat(std::chrono::milliseconds(1000));
  log << "scenario: heartbeat state=" << to_string(first.state) << " protocol " << int(first.version_major) << "."
      << int(first.version_minor) << " error_flags=0x" << std::hex << first.error_flags << std::dec << "\n";
  check(first.version_major == shared::kProtocolVersionMajor, "protocol major version differs");
  client.set_mode(false, false, true);

  // Parameters: upload, then read back and compare byte for byte.
  const auto correction = image_of(scenario_correction_parameters(), shared::kCorrectionBytes);
  const std::uint32_t sequence = client.upload(shared::ParameterBlock::kCorrection, correction);
  log << "scenario: uploaded correction parameters (" << correction.size() << " bytes), slot sequence " << sequence
      << "\n";
  check(client.download(shared::ParameterBlock::kCorrection) == correction, "correction parameters read back differ");
  const shared::CameraIntrinsics intrinsics{810.5f, 811.25f, 319.5f, 239.5f, -0.12f, 0.03f,
                                            1e-4f,  -2e-4f,  0.0f,   640,    480};
  const auto intrinsics_image = image_of(intrinsics, shared::kIntrinsicsBytes);
  client.upload(shared::ParameterBlock::kIntrinsics, intrinsics_image);
  check(client.download(shared::ParameterBlock::kIntrinsics) == intrinsics_image, "intrinsics read back differ");
  log << "scenario: parameters read back identical\n";

  client.set_mode(true, true);
  client.clear_error_reports();
  for (int i = 0; i < options.measurements; ++i) {
    const shared::MeasurementReport r = client.measure(shared::section::kRanges);
    if (!check((r.sections & shared::section::kRanges) != 0, "measurement without ranges")) break;
    ++result.measurements_done;
    if (i == 0) {
      log << "scenario: measurement seq=" << int(r.sequence) << " t=" << r.timestamp_us << " us ranges m:";
      for (const std::uint16_t range : r.range_raw) {
        if (range == shared::kNoEcho)
          log << " none";
        else
          log << " " << range * shared::kRangeLsbM;
      }
      log << " status=" << to_string(r.status) << "\n";
    }
  }
  log << "scenario: " << result.measurements_done << " measurements\n";

  const shared::CorrectionParameters params = scenario_correction_parameters();
  std::vector<double> round_trips_us;
  for (int i = 0; i < options.corrections; ++i) {
    // Around a posture clear of the PUMA's singularities (elbow at tan q3 = d4 / a3, i.e. chain
    // q3 = 1.524 or -1.618 rad; wrist at q5 = 0 or pi), +-0.5 rad on every reading. Reading 3 is
    // the elbow relative to the shoulder (the block's coupling): chain q3 = -0.3 +- 0.88 rad.
    const double home_rad[shared::kJoints] = {0.0, -0.6, 0.3, 0.3, 1.0, 0.2};
    std::array<std::int32_t, shared::kJoints> joints{};
    for (std::size_t j = 0; j < shared::kJoints; ++j)
      joints[j] = shared::quantize_joint_angle(home_rad[j] + 0.5 * std::sin(0.01 * i + static_cast<double>(j)));
    const auto t0 = std::chrono::steady_clock::now();
    const auto out = client.correct(joints, options.fd, options.correction_timeout);
    round_trips_us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
    const std::array<double, shared::kJoints> expected = reference_correction(params, joints);
    bool exact = true;
    for (std::size_t j = 0; j < shared::kJoints; ++j)
      exact &= std::abs(out[j] - shared::quantize_joint_angle(expected[j])) <= 1;  // float vs double: 1 LSB
    if (!check(exact, "corrected joint state differs from the double-precision kinematic correction")) break;
    ++result.corrections_done;
  }
  if (!round_trips_us.empty()) {
    std::sort(round_trips_us.begin(), round_trips_us.end());
    result.correction_round_trip_us_median = round_trips_us[round_trips_us.size() / 2];
  }
  log << "scenario: " << result.corrections_done << " corrections (" << (options.fd ? "CAN FD" : "classic")
      << "), median round trip " << result.correction_round_trip_us_median << " us\n";

  client.set_mode(false, false);
  const shared::Heartbeat last = client.wait_heartbeat(std::chrono::milliseconds(1000));
  log << "scenario: heartbeat state=" << to_string(last.state) << " measurements=" << int(last.measurements)
      << " corrections=" << int(last.corrections) << " rejected=" << int(last.rejected_frames) << "\n";
  check(static_cast<std::uint8_t>(last.measurements - first.measurements) ==
            static_cast<std::uint8_t>(result.measurements_done),
        "heartbeat measurement count");
  check(static_cast<std::uint8_t>(last.corrections - first.corrections) ==
            static_cast<std::uint8_t>(result.corrections_done),
        "heartbeat correction count");
  check((last.error_flags & shared::error_flag::kNoCorrection) == 0, "platform still reports no correction block");
  log << "scenario: " << (result.ok() ? "PASS" : "FAIL") << "\n";
  return result;
}

}  // namespace kincal::can

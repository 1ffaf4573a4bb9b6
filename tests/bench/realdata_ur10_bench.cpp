// Issue #12: identification on real measurements, the shared UR10 laser-tracker set read through
// kincal import's reader. Training sets of 30, 100 and 300 rows, a fixed held-out set of 500:
//   realdata_ur10_heldout_rms_mm[_nN]      held-out position RMS of `full` with the tracker's
//                                          covariance columns (the defaults; plain name: N = 300)
//   realdata_ur10_cov_over_nocov[_nN]      the same over the same without the covariance
//                                          columns (plain name: the worst of the three sizes)
//   realdata_ur10_norejection_heldout_rms_mm_nN, realdata_ur10_rejection_over_norejection[_nN]
//                                          outlier rejection off, and the ratio (plain: worst)
//   realdata_ur10_coverage_95[_nN]         fraction of held-out errors inside the predicted 95 %
//                                          ellipsoid: parameter covariance propagated + model
//                                          error + the row's instrument covariance (plain: N = 300)
//   realdata_ur10_model_error_mm_nN, realdata_ur10_rejected_nN
//   realdata_ur10_nominal_registered_rms_mm   nominal geometry, only base and probe identified
//                                             (300 rows), for orientation
//   realdata_ur10_positions_only_heldout_rms_mm_n300   without the orientation columns
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "host/identify/identify.hpp"
#include "host/identify/statistics.hpp"
#include "host/model/model_file.hpp"
#include "tests/host/model/ur10_realdata.hpp"

namespace {

using namespace kincal;

struct Outcome {
  double rms_m = 0.0;
  double coverage = 0.0;
  identify::IdentifyResult result;
};

Outcome run(const model::RobotModel& nominal, const model::Dataset& train, const model::Dataset& held_out,
            const identify::IdentifyOptions& o) {
  Outcome out;
  out.result = identify::identify(nominal, train, o);
  out.rms_m = identify::accuracy(out.result.model, held_out).rms_m;
  const double limit = identify::chi_square_quantile(0.95, 3);
  int inside = 0;
  for (const model::Measurement& m : held_out.rows) {
    const Eigen::Vector3d e = m.position - model::forward_kinematics(out.result.model, m.q).translation;
    Eigen::Matrix3d s = identify::prediction_covariance(out.result, m.q);
    if (m.covariance) s += *m.covariance;
    inside += e.dot(s.ldlt().solve(e)) <= limit ? 1 : 0;
  }
  out.coverage = static_cast<double>(inside) / static_cast<double>(held_out.rows.size());
  return out;
}

model::Dataset without_covariance(model::Dataset d) {
  for (model::Measurement& m : d.rows) m.covariance.reset();
  d.noise = model::NoiseColumns::none;
  return d;
}

void figure(const std::string& name, double value, const char* unit) {
  std::printf("FIGURE %s %.4f %s\n", name.c_str(), value, unit);
}

}  // namespace

int main() {
  const model::RobotModel nominal = model::load_model(KINCAL_ROBOTS_DIR "/ur10.yaml");
  const model::Dataset all = realdata::import_ur10(KINCAL_REALDATA_DIR).data;
  const realdata::Split split = realdata::split_rows(static_cast<int>(all.rows.size()), 500);
  const model::Dataset held_out = realdata::subset(all, split.held_out);
  double worst_ratio = 0.0, worst_rejection_ratio = 0.0;
  for (int n : {30, 100, 300}) {
    const std::vector<int> rows(split.train_order.begin(), split.train_order.begin() + n);
    const model::Dataset train = realdata::subset(all, rows);
    const std::string suffix = "_n" + std::to_string(n);
    identify::IdentifyOptions o;
    const Outcome cov = run(nominal, train, held_out, o);
    const Outcome nocov = run(nominal, without_covariance(train), held_out, o);
    o.robust = false;
    const Outcome norej = run(nominal, train, held_out, o);
    const double ratio = cov.rms_m / nocov.rms_m, rejection_ratio = cov.rms_m / norej.rms_m;
    worst_ratio = std::max(worst_ratio, ratio);
    worst_rejection_ratio = std::max(worst_rejection_ratio, rejection_ratio);
    figure("realdata_ur10_heldout_rms_mm" + suffix, cov.rms_m * 1e3, "mm");
    figure("realdata_ur10_nocov_heldout_rms_mm" + suffix, nocov.rms_m * 1e3, "mm");
    figure("realdata_ur10_cov_over_nocov" + suffix, ratio, "ratio");
    figure("realdata_ur10_norejection_heldout_rms_mm" + suffix, norej.rms_m * 1e3, "mm");
    figure("realdata_ur10_rejection_over_norejection" + suffix, rejection_ratio, "ratio");
    figure("realdata_ur10_coverage_95" + suffix, cov.coverage, "fraction");
    figure("realdata_ur10_norejection_coverage_95" + suffix, norej.coverage, "fraction");
    figure("realdata_ur10_model_error_mm" + suffix, cov.result.model_error_position_m * 1e3, "mm");
    figure("realdata_ur10_model_error_deg" + suffix, cov.result.model_error_orientation_rad * 180.0 / std::numbers::pi,
           "deg");
    figure("realdata_ur10_rejected" + suffix, static_cast<double>(cov.result.rejections.size()), "rows");
    if (n == 300) {
      figure("realdata_ur10_heldout_rms_mm", cov.rms_m * 1e3, "mm");
      figure("realdata_ur10_coverage_95", cov.coverage, "fraction");
      model::Dataset points = train;
      points.has_orientation = false;
      for (model::Measurement& m : points.rows) m.orientation.reset();
      identify::IdentifyOptions p;
      figure("realdata_ur10_positions_only_heldout_rms_mm_n300", run(nominal, points, held_out, p).rms_m * 1e3, "mm");
      identify::IdentifyOptions r;
      r.requested = {"base", "tool"};
      figure("realdata_ur10_nominal_registered_rms_mm", run(nominal, train, held_out, r).rms_m * 1e3, "mm");
    }
  }
  figure("realdata_ur10_cov_over_nocov", worst_ratio, "ratio");
  figure("realdata_ur10_rejection_over_norejection", worst_rejection_ratio, "ratio");
  return 0;
}

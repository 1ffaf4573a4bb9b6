#include "host/cli/fiducials.hpp"

#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "firmware/core/fiducial_id.hpp"
#include "host/cli/threshold_option.hpp"
#include "host/vision/blob_json.hpp"
#include "host/vision/image_labeling.hpp"

namespace kincal::cli {

namespace {

struct FiducialsOptions {
  std::string image;
  std::optional<std::uint8_t> threshold;  // none: automatic
};

const char* status_name(core::FidStatus s) {
  switch (s) {
    case core::FidStatus::kOk:
      return "ok";
    case core::FidStatus::kNoCentre:
      return "no_centre";
    case core::FidStatus::kTooFewFiducials:
      return "too_few_fiducials";
    case core::FidStatus::kCollinear:
      return "collinear";
    case core::FidStatus::kTooManyBlobs:
      return "too_many_blobs";
    case core::FidStatus::kVerdictsTooShort:
      return "verdicts_too_short";
  }
  return "unknown";
}

const char* verdict_name(core::FidVerdict v) {
  switch (v) {
    case core::FidVerdict::kUnused:
      return "unused";
    case core::FidVerdict::kCentre:
      return "centre";
    case core::FidVerdict::kPerimeter:
      return "perimeter";
    case core::FidVerdict::kCorner:
      return "corner";
    case core::FidVerdict::kRejectedIncomplete:
      return "rejected_incomplete";
    case core::FidVerdict::kRejectedBorder:
      return "rejected_border";
    case core::FidVerdict::kRejectedArea:
      return "rejected_area";
    case core::FidVerdict::kRejectedShape:
      return "rejected_shape";
    case core::FidVerdict::kRejectedPosition:
      return "rejected_position";
    case core::FidVerdict::kRejectedAmbiguous:
      return "rejected_ambiguous";
    case core::FidVerdict::kRejectedWeakerCentre:
      return "rejected_weaker_centre";
  }
  return "unknown";
}

int run_fiducials(const FiducialsOptions& o) {
  const cv::Mat grey = vision::read_image(o.image, true);
  vision::LabelOptions options;
  options.polarity = core::Polarity::kDark;
  options.threshold = o.threshold;
  options.min_area_px = 4;
  const vision::LabelResult labels = vision::label_grey(grey, options);
  if (labels.blobs.size() > core::kFidMaxBlobs) {
    throw std::runtime_error(o.image + ": " + std::to_string(labels.blobs.size()) +
                             " blobs, more than the FID examines (" + std::to_string(core::kFidMaxBlobs) + ")");
  }
  std::vector<core::FidVerdict> verdicts(labels.blobs.size());
  core::FidResult result;
  const core::FidStatus status = core::identify_fiducials(core::FidModel{}, labels.blobs, verdicts, result);

  nlohmann::ordered_json fiducials = nlohmann::ordered_json::array();
  for (int i = 0; i < result.count; ++i) {
    const core::IdentifiedFiducial& f = result.fiducials[static_cast<std::size_t>(i)];
    fiducials.push_back({{"id", f.id}, {"x", f.x_px.to_double()}, {"y", f.y_px.to_double()}, {"blob", f.blob_index}});
  }
  nlohmann::ordered_json blobs = nlohmann::ordered_json::array();
  for (std::size_t i = 0; i < labels.blobs.size(); ++i) {
    nlohmann::ordered_json b = vision::blob_to_json(labels.blobs[i]);
    b["verdict"] = verdict_name(verdicts[i]);
    blobs.push_back(std::move(b));
  }
  nlohmann::ordered_json out = {{"image", o.image},
                                {"status", status_name(status)},
                                {"threshold", labels.threshold},
                                {"fiducials", std::move(fiducials)}};
  if (result.count > 0) {
    out["axes"] = {{"x", {result.x_axis_x.to_double(), result.x_axis_y.to_double()}},
                   {"y", {result.y_axis_x.to_double(), result.y_axis_y.to_double()}}};
    out["fiducial_side_px"] = result.fiducial_side_px.to_double();
    out["orientation_from_marker"] = result.orientation_from_marker;
  }
  out["blobs"] = std::move(blobs);
  std::cout << out.dump(2) << "\n";
  return status == core::FidStatus::kOk ? 0 : 2;
}

}  // namespace

void add_fiducials_command(CLI::App& app, int& status) {
  auto options = std::make_shared<FiducialsOptions>();
  auto* cmd =
      app.add_subcommand("fiducials", "Identify a calibration square's fiducials in an image (Doty's FID, JSON)");
  cmd->add_option("image", options->image, "Image file (any format OpenCV reads)")->required();
  add_threshold_option(*cmd, options->threshold);
  cmd->callback([options, &status] {
    try {
      status = run_fiducials(*options);
    } catch (const std::exception& e) {
      std::cerr << "kincal fiducials: " << e.what() << "\n";
      status = 1;
    }
  });
}

}  // namespace kincal::cli

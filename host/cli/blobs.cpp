#include "host/cli/blobs.hpp"

#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "host/cli/colour_table.hpp"
#include "host/cli/number_options.hpp"
#include "host/cli/threshold_option.hpp"
#include "host/files/input_limits.hpp"
#include "host/vision/blob_json.hpp"
#include "host/vision/image_labeling.hpp"

namespace kincal::cli {

namespace {

struct BlobsOptions {
  std::vector<std::string> images;
  std::string polarity = "bright";
  std::optional<std::uint8_t> threshold;  // none: automatic
  std::string colour_table;
  int connectivity = 8;
  std::uint32_t min_area_px = 1;
  std::uint32_t max_blobs = 100000;
  bool no_refine = false;
};

int run_blobs(const BlobsOptions& o) {
  vision::LabelOptions options;
  options.polarity = o.polarity == "dark" ? core::Polarity::kDark : core::Polarity::kBright;
  options.threshold = o.threshold;
  options.connectivity = o.connectivity == 4 ? core::Connectivity::kFour : core::Connectivity::kEight;
  options.min_area_px = o.min_area_px;
  options.refine = !o.no_refine;
  if (!o.colour_table.empty()) options.colour = read_colour_table(o.colour_table);

  // Read every image first: a bad file stops the command before anything is printed.
  std::vector<cv::Mat> images;
  for (const std::string& path : o.images) images.push_back(vision::read_image(path, !options.colour));

  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  for (std::size_t i = 0; i < images.size(); ++i) {
    const vision::LabelResult r =
        options.colour ? vision::label_colour(images[i], options) : vision::label_grey(images[i], options);
    const std::uint64_t found = std::uint64_t{r.summary.blobs} + r.summary.blobs_dropped_output_full;
    if (found > o.max_blobs || r.summary.blobs_dropped_output_full > 0)
      throw std::runtime_error(o.images[i] + ": " + std::to_string(found) + " blobs, more than " +
                               (r.summary.blobs_dropped_output_full > 0
                                    ? std::string("the labeler's output holds")
                                    : "--max-blobs " + std::to_string(o.max_blobs)) +
                               " (about 300 bytes of JSON each): raise the threshold or --min-area, or --max-blobs");
    nlohmann::ordered_json blobs = nlohmann::ordered_json::array();
    for (const core::Blob& b : r.blobs) blobs.push_back(vision::blob_to_json(b));
    nlohmann::ordered_json image = {{"image", o.images[i]}, {"summary", vision::summary_to_json(r.summary)}};
    if (options.colour) {
      image["colour_table"] = o.colour_table;
      image["threshold"] = r.threshold;
    } else {
      image["polarity"] = o.polarity;
      image["threshold"] = r.threshold;
      image["threshold_automatic"] = r.threshold_automatic;
    }
    image["blobs"] = std::move(blobs);
    out.push_back(std::move(image));
  }
  std::cout << out.dump(2) << "\n";
  return 0;
}

}  // namespace

void add_blobs_command(CLI::App& app, int& status) {
  auto options = std::make_shared<BlobsOptions>();
  auto* cmd = app.add_subcommand("blobs", "Label blobs in images with the firmware core's streaming labeler (JSON)");
  cmd->add_option("images", options->images,
                  std::string("Image files (any format OpenCV reads; ") + files::kImageLimitText + ")")
      ->required();
  auto* polarity = cmd->add_option("--polarity", options->polarity, "Blobs brighter or darker than the threshold")
                       ->check(CLI::IsMember({"bright", "dark"}))
                       ->capture_default_str();
  auto* threshold = add_threshold_option(*cmd, options->threshold);
  cmd->add_option("--colour-table", options->colour_table,
                  "Colour-class table (kincal colour-table): label that colour class instead of a threshold")
      ->excludes(polarity)
      ->excludes(threshold);
  cmd->add_option("--connectivity", options->connectivity, "Pixel connectivity")
      ->check(CLI::IsMember({4, 8}))
      ->capture_default_str();
  cmd->add_option("--min-area", options->min_area_px, "Drop blobs with fewer pixels")->capture_default_str();
  cmd->add_option("--max-blobs", options->max_blobs, "Fail (exit 1) rather than print more blobs than this per image")
      ->check(whole_in(1, 1 << 20))
      ->capture_default_str();
  cmd->add_flag("--no-refine", options->no_refine, "Skip the Gaussian-window refinement of spot-like blobs");
  cmd->callback([options, &status] {
    try {
      status = run_blobs(*options);
    } catch (const std::exception& e) {
      std::cerr << "kincal blobs: " << e.what() << "\n";
      status = 1;
    }
  });
}

}  // namespace kincal::cli

#include "host/cli/colour_table.hpp"

#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "host/cli/number_options.hpp"
#include "host/files/input_file.hpp"
#include "host/files/output_file.hpp"
#include "host/vision/colour_table_builder.hpp"
#include "host/vision/image_labeling.hpp"

namespace kincal::cli {

namespace {

struct ColourTableOptions {
  std::vector<std::string> positive, negative;
  std::string space = "rgb565";
  std::string output;
  double max_distance = 3.0;
};

void add_pixels(const std::string& path, std::vector<cv::Vec3b>& out) {
  const cv::Mat img = vision::read_image(path, false);
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x) out.push_back(img.at<cv::Vec3b>(y, x));
}

int run_colour_table(const ColourTableOptions& o) {
  std::vector<files::NamedPath> inputs;
  for (const std::string& p : o.positive) inputs.push_back({"--positive", p});
  for (const std::string& p : o.negative) inputs.push_back({"--negative", p});
  files::refuse_overwriting({{"-o", o.output}}, inputs);
  vision::ColourTableSamples samples;
  for (const std::string& p : o.positive) add_pixels(p, samples.positive_bgr);
  for (const std::string& p : o.negative) add_pixels(p, samples.negative_bgr);
  const core::ColourSpace space = o.space == "yuv422" ? core::ColourSpace::kYuv422 : core::ColourSpace::kRgb565;
  const core::ColourClassTable table = vision::build_colour_table(samples, space, o.max_distance);
  std::array<std::uint8_t, core::kColourTableBlockBytes> block{};
  core::serialize_colour_table(table, block);
  files::write_file_atomically(o.output, std::string_view(reinterpret_cast<const char*>(block.data()), block.size()));
  std::size_t cells = 0;
  for (const std::uint8_t s : table.score) cells += s > table.threshold ? 1 : 0;
  std::cout << "colour table " << o.output << ": " << o.space << ", " << cells << " of " << core::kColourCells
            << " cells in the class, threshold " << int{table.threshold} << ", from " << samples.positive_bgr.size()
            << " positive and " << samples.negative_bgr.size() << " negative samples\n";
  return 0;
}

}  // namespace

core::ColourClassTable read_colour_table(const std::string& path) {
  const std::string file = files::read_text(path, files::kColourTableFile);
  const std::vector<std::uint8_t> bytes(file.begin(), file.end());
  core::ColourClassTable table;
  switch (core::parse_colour_table(bytes, table)) {
    case core::ColourTableStatus::kOk:
      return table;
    case core::ColourTableStatus::kWrongSize:
      throw std::runtime_error(path + ": not a colour table (" + std::to_string(bytes.size()) + " bytes, expected " +
                               std::to_string(core::kColourTableBlockBytes) + ")");
    case core::ColourTableStatus::kBadMagic:
      throw std::runtime_error(path + ": not a colour table (bad magic)");
    case core::ColourTableStatus::kBadCrc:
      throw std::runtime_error(path + ": colour table corrupted (CRC mismatch)");
    case core::ColourTableStatus::kUnsupportedVersion:
      throw std::runtime_error(path + ": colour table of an unsupported version");
    case core::ColourTableStatus::kUnknownColourSpace:
      throw std::runtime_error(path + ": colour table with an unknown colour space");
    case core::ColourTableStatus::kReservedNotZero:
      throw std::runtime_error(path + ": colour table with its reserved byte 7 not zero (of a newer version?)");
  }
  throw std::runtime_error(path + ": colour table not readable");
}

void add_colour_table_command(CLI::App& app, int& status) {
  auto options = std::make_shared<ColourTableOptions>();
  auto* cmd = app.add_subcommand("colour-table", "Build the beacon's colour-class table from sample pixels");
  cmd->add_option("--positive", options->positive, "Images whose every pixel is the class (crops of the beacon)")
      ->required();
  cmd->add_option("--negative", options->negative, "Images whose pixels must not be the class");
  cmd->add_option("--space", options->space, "The camera's colour format")
      ->check(CLI::IsMember({"rgb565", "yuv422"}))
      ->capture_default_str();
  cmd->add_option("--max-distance", options->max_distance, "Class boundary, in standard deviations of the samples")
      ->check(finite_in(0.5, 10.0))
      ->capture_default_str();
  cmd->add_option("-o,--output", options->output, "Parameter block to write")->required();
  cmd->callback([options, &status] {
    try {
      status = run_colour_table(*options);
    } catch (const std::exception& e) {
      std::cerr << "kincal colour-table: " << e.what() << "\n";
      status = 1;
    }
  });
}

}  // namespace kincal::cli

// Writes the small images the `cli.*` vision tests run `kincal` on (host/cli/CMakeLists.txt):
//   spots.png             a Gaussian spot (sigma 1.5 px, peak 180 DN) at (40.2, 30.7) on 20 DN
//   square.png            a calibration square (fiducial side 10 px), dark on light vellum
//   beacon_crop.png       crimson pixels under varying light: the colour-table samples
//   scene_background.png  the scene without the beacon: grey, white, green, orange
//   beacon_scene.png      that scene with a crimson disc centred on (60, 40)
//   not_an_image.png      text with an image's name
// Usage: make_test_images OUTPUT_DIR
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include "tests/firmware/core/calibration_square_image.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: make_test_images OUTPUT_DIR\n";
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  std::filesystem::create_directories(dir);

  cv::Mat spots(64, 80, CV_8UC1);
  for (int y = 0; y < spots.rows; ++y)
    for (int x = 0; x < spots.cols; ++x) {
      const double dx = x - 40.2, dy = y - 30.7;
      spots.at<std::uint8_t>(y, x) = cv::saturate_cast<std::uint8_t>(20 + 180 * std::exp(-(dx * dx + dy * dy) / 4.5));
    }
  cv::imwrite((dir / "spots.png").string(), spots);

  static kincal::test::Image<240, 240> square;
  kincal::test::SquareView view{120.0, 121.0, 0.6, -0.8, 10.0};
  kincal::test::render_square(square, view);
  cv::imwrite((dir / "square.png").string(), cv::Mat(240, 240, CV_8UC1, square.px));

  cv::Mat crop(20, 20, CV_8UC3);
  for (int y = 0; y < crop.rows; ++y)
    for (int x = 0; x < crop.cols; ++x) {
      const double light = 0.7 + 0.3 * (x + y) / 38.0;  // shading across the beacon
      crop.at<cv::Vec3b>(y, x) =
          cv::Vec3b(cv::saturate_cast<std::uint8_t>(40 * light), cv::saturate_cast<std::uint8_t>(20 * light),
                    cv::saturate_cast<std::uint8_t>(200 * light));  // BGR crimson
    }
  cv::imwrite((dir / "beacon_crop.png").string(), crop);

  cv::Mat scene(80, 120, CV_8UC3, cv::Scalar(90, 90, 90));
  cv::rectangle(scene, cv::Rect(5, 5, 20, 20), cv::Scalar(250, 250, 250), cv::FILLED);
  cv::rectangle(scene, cv::Rect(90, 50, 20, 20), cv::Scalar(40, 180, 40), cv::FILLED);
  cv::rectangle(scene, cv::Rect(10, 55, 25, 15), cv::Scalar(30, 140, 240), cv::FILLED);  // orange
  cv::imwrite((dir / "scene_background.png").string(), scene);
  cv::circle(scene, cv::Point(60, 40), 8, cv::Scalar(36, 18, 180), cv::FILLED);
  cv::imwrite((dir / "beacon_scene.png").string(), scene);

  std::ofstream(dir / "not_an_image.png") << "this is text, not a PNG\n";
  return 0;
}

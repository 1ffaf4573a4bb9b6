// host/session/platform_setup: platform.yaml and camera files into the platform's blocks, and
// every refusal naming the file, line and key.
#include <doctest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "host/camera/calibration_file.hpp"
#include "host/session/platform_setup.hpp"

using namespace kincal;

namespace {

// A file of the test's own in a fresh temporary directory; the path.
std::string write_file(const std::string& name, const std::string& text) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "kincal-platform-setup-test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / name).string();
  std::ofstream(path) << text;
  return path;
}

// Doty's + pattern, 10 cm across, beams along +z (lines 2..9 of the file).
const std::string kRangers =
    "rangers:\n"
    "  - origin_m: [0.05, 0.0, 0.01]\n"
    "    direction: [0, 0, 1]\n"
    "  - origin_m: [0.0, 0.05, 0.01]\n"
    "    direction: [0, 0, 2]\n"
    "  - origin_m: [-0.05, 0.0, 0.01]\n"
    "    direction: [0.0005, 0, 1]\n"
    "  - origin_m: [0.0, -0.05, 0.01]\n"
    "    direction: [0, 0, 1]\n";

// The refusal's message for `text` as platform.yaml.
std::string refusal(const std::string& text) {
  const std::string path = write_file("refused.yaml", "# platform\n" + text);
  try {
    (void)session::read_geometry_block(path);
  } catch (const session::PlatformSetupError& e) {
    return e.what();
  }
  return "accepted";
}

// `text` with its first `from` replaced by `to` (which must be there).
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

}  // namespace

TEST_CASE("platform.yaml: the rangers, Doty's fiducials for the side, the pitch") {
  const std::string path =
      write_file("platform.yaml", kRangers + "fiducial_side_m: 0.005\nsquare_pitch_m: 0.2  # a wider strip\n");
  const shared::PlatformGeometry g = session::read_geometry_block(path);
  CHECK(g.rangers[0].origin_m == std::array<float, 3>{0.05f, 0.0f, 0.01f});
  CHECK(g.rangers[3].origin_m == std::array<float, 3>{0.0f, -0.05f, 0.01f});
  CHECK(g.rangers[0].direction == std::array<float, 3>{0.0f, 0.0f, 1.0f});
  // Normalized on load.
  CHECK(g.rangers[1].direction == std::array<float, 3>{0.0f, 0.0f, 1.0f});
  CHECK(g.rangers[2].direction[0] == doctest::Approx(0.0005 / std::sqrt(1 + 0.0005 * 0.0005)).epsilon(1e-6));
  CHECK(g.rangers[2].direction[2] == doctest::Approx(1 / std::sqrt(1 + 0.0005 * 0.0005)).epsilon(1e-7));
  // Doty's layout, s = 5 mm: p1 (-7s, 7s), p2 (0, 7s), p3 (-7s, 0), p4 (0, 0), p5 (7s, 0), p6 (0, -7s).
  REQUIRE(g.fiducial_count == 6);
  const std::array<std::array<float, 2>, 6> expected{
      {{-0.035f, 0.035f}, {0.0f, 0.035f}, {-0.035f, 0.0f}, {0.0f, 0.0f}, {0.035f, 0.0f}, {0.0f, -0.035f}}};
  for (std::size_t k = 0; k < 6; ++k) {
    CAPTURE(k);
    CHECK(g.fiducial_square_m[k][0] == doctest::Approx(expected[k][0]).epsilon(1e-6));
    CHECK(g.fiducial_square_m[k][1] == doctest::Approx(expected[k][1]).epsilon(1e-6));
    CHECK(g.fiducial_square_m[k][2] == 0.0f);
  }
  CHECK(g.square_pitch_m == 0.2f);
}

TEST_CASE("platform.yaml: Doty's 1/4-inch fiducials and 4-inch pitch by default; pitch 0 is one square per frame") {
  const shared::PlatformGeometry doty = session::read_geometry_block(write_file("doty.yaml", kRangers));
  CHECK(doty.square_pitch_m == 0.1016f);
  CHECK(doty.fiducial_square_m[4][0] == doctest::Approx(7 * 0.00635).epsilon(1e-6));
  CHECK(doty.fiducial_square_m[0][1] == doctest::Approx(7 * 0.00635).epsilon(1e-6));
  const shared::PlatformGeometry one =
      session::read_geometry_block(write_file("one.yaml", kRangers + "square_pitch_m: 0\n"));
  CHECK(one.square_pitch_m == 0.0f);
  // The description names what was loaded.
  const std::string text = session::describe(doty);
  CHECK(contains(text, "ranger 2: origin (-0.05, 0, 0.01)"));
  CHECK(contains(text, "fiducial side: 0.00635 m"));
  CHECK(contains(text, "square pitch: 0.1016 m"));
}

TEST_CASE("platform.yaml refusals name the file, the line and the key") {
  CHECK(contains(refusal("rangers: [\n"), "refused.yaml:"));
  CHECK(contains(refusal("rangers: [\n"), "not valid YAML"));
  CHECK(contains(refusal("- 1\n- 2\n"), "not a map of rangers"));
  CHECK(contains(refusal(kRangers + "square_pich_m: 0.1\n"),
                 "refused.yaml:11: square_pich_m: unknown key (expected rangers, fiducial_side_m, square_pitch_m)"));
  CHECK(contains(refusal("fiducial_side_m: 0.006\n"), "refused.yaml:2: rangers: key 'rangers' missing"));
  // Three rangers.
  const std::string three = kRangers.substr(0, kRangers.find("  - origin_m: [0.0, -0.05"));
  CHECK(contains(refusal(three), "refused.yaml:3: rangers: must list exactly 4 rangers, found 3"));
  // Edits of the good file: {what, instead, the message's part}.
  const std::array<std::array<const char*, 3>, 10> edits{{
      // A ranger's own keys.
      {"    direction: [0, 0, 2]", "    directoin: [0, 0, 2]",
       "refused.yaml:6: rangers[1].directoin: unknown key (expected origin_m, direction)"},
      {"    direction: [0, 0, 2]\n", "", "rangers[1]: key 'direction' missing"},
      // NaN, not a number, a wrong length.
      {"0.05, 0.01]", "0.05, .nan]", "refused.yaml:5: rangers[1].origin_m[2]: '.nan' is not finite"},
      {"[0, 0, 2]", "[0, zero, 2]", "refused.yaml:6: rangers[1].direction[1]: 'zero' is not a number"},
      {"[0, 0, 2]", "[0, 2]", "refused.yaml:6: rangers[1].direction: not a list of three numbers"},
      // A zero direction.
      {"[0, 0, 2]", "[0, 0, 0]", "refused.yaml:6: rangers[1].direction: zero or unusable length"},
      // A beam tilted off the optical axis (0.002 > 1e-3), and one pointing backwards.
      {"[0, 0, 2]", "[0, 0.004, 2]",
       "refused.yaml:6: rangers[1].direction: (0, 0.002, 0.999998) normalized is not along the optical axis +z "
       "within 1e-3 in x and y: the platform's plane fit needs beams parallel to it and would answer kNoParameters"},
      {"[0, 0, 2]", "[0, 0, -1]", "refused.yaml:6: rangers[1].direction: (0, 0, -1) normalized is not along"},
      // Uneven origin z: 0.3 mm.
      {"[-0.05, 0.0, 0.01]", "[-0.05, 0.0, 0.0103]",
       "refused.yaml:7: rangers[2].origin_m: z 0.0103 m differs from rangers[0]'s 0.01 m by more than 0.1 mm"},
      // Three origins on one line.
      {"[0.0, 0.05, 0.01]", "[0.0, 0.0, 0.01]", "refused.yaml:3: rangers: three of the origins lie on one line"},
  }};
  for (const auto& [from, to, expected] : edits) {
    CAPTURE(to);
    const std::string message = refusal(replaced(kRangers, from, to));
    CAPTURE(message);
    CHECK(contains(message, expected));
  }
  // Bad pitch: below the floor, above the ceiling, too small for the fiducials, not a number.
  CHECK(contains(refusal(kRangers + "square_pitch_m: 0.005\n"),
                 "refused.yaml:11: square_pitch_m: 0.005 m: must be 0 (one square per frame) or within [0.01, 2] m"));
  CHECK(contains(refusal(kRangers + "square_pitch_m: 2.5\n"), "within [0.01, 2] m"));
  CHECK(contains(refusal(kRangers + "square_pitch_m: -0.1\n"), "within [0.01, 2] m"));
  CHECK(contains(refusal(kRangers + "square_pitch_m: 0.09\n"),
                 "square_pitch_m: 0.09 m: neighbouring squares' fiducials"));
  CHECK(contains(refusal(kRangers + "square_pitch_m: .inf\n"), "square_pitch_m: '.inf' is not finite"));
  // The fiducial side.
  CHECK(contains(refusal(kRangers + "fiducial_side_m: 0\n"), "refused.yaml:11: fiducial_side_m: must be positive"));
  CHECK(contains(refusal(kRangers + "fiducial_side_m: 0.01\n"), "neighbouring squares' fiducials would overlap"));
}

TEST_CASE("a missing file is named") {
  const std::string missing = "/nonexistent/kincal/platform.yaml";
  CHECK_THROWS_WITH_AS(session::read_geometry_block(missing), (missing + ": no such file").c_str(),
                       session::PlatformSetupError);
  CHECK_THROWS_WITH_AS(session::read_camera_block(missing), (missing + ": no such file").c_str(),
                       session::PlatformSetupError);
}

TEST_CASE("camera.yaml: kincal camera calibrate's files (ROS camera_info) into the camera block") {
  camera::CameraModel model;
  model.image_size = cv::Size(1280, 720);
  model.camera_matrix = cv::Matx33d(910.5, 0, 641.25, 0, 912.0, 359.75, 0, 0, 1);
  model.distortion = {-0.11, 0.07, 0.001, -0.0007, -0.01};
  const std::string path = write_file("camera_ros.yaml", "");
  camera::save_camera_ros(path, model, "platform_camera");
  const shared::CameraIntrinsics c = session::read_camera_block(path);
  CHECK(c.fx_px == 910.5f);
  CHECK(c.fy_px == 912.0f);
  CHECK(c.cx_px == 641.25f);
  CHECK(c.cy_px == 359.75f);
  CHECK(c.k1 == -0.11f);
  CHECK(c.p2 == -0.0007f);
  CHECK(c.k3 == -0.01f);
  CHECK(c.width_px == 1280);
  CHECK(c.height_px == 720);
  CHECK(contains(session::describe(c), "camera: 1280 x 720 px, fx 910.5 fy 912 cx 641.25 cy 359.75 px"));
  // A camera file without its matrix: the loader's message, behind the file's name.
  const std::string broken = write_file("camera_broken.yaml", "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n");
  try {
    (void)session::read_camera_block(broken);
    FAIL("accepted a camera file without a camera matrix");
  } catch (const session::PlatformSetupError& e) {
    CHECK(std::string(e.what()).rfind(broken + ":", 0) == 0);
    CHECK(contains(e.what(), "camera_matrix"));
  }
}

#include "host/session/platform_files.hpp"

#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <initializer_list>
#include <sstream>
#include <utility>

#include "firmware/app/platform_measurement.hpp"
#include "firmware/core/range_plane.hpp"
#include "host/camera/calibration_file.hpp"
#include "host/files/input_file.hpp"
#include "host/files/yaml_limits.hpp"
#include "host/target/doty_square.hpp"

namespace kincal::session {

namespace {

// Where a node came from, for messages: "PATH:LINE: KEY".
class Place {
 public:
  Place(const std::string& path, const YAML::Node& node, std::string key)
      : path_(path), line_(node.Mark().line + 1), key_(std::move(key)) {}
  [[noreturn]] void fail(const std::string& what) const {
    throw PlatformSetupError(path_ + ":" + std::to_string(line_) + ": " + key_ + ": " + what);
  }

 private:
  const std::string& path_;
  int line_;
  std::string key_;
};

std::string list(std::initializer_list<const char*> names) {
  std::string out;
  for (const char* n : names) out += (out.empty() ? "" : ", ") + std::string(n);
  return out;
}

// The map's keys, each one of `allowed` (else an error naming it and its line).
void check_keys(const std::string& path, const YAML::Node& map, const std::string& prefix,
                std::initializer_list<const char*> allowed) {
  for (auto it = map.begin(); it != map.end(); ++it) {
    const std::string key = it->first.Scalar();
    bool known = false;
    for (const char* a : allowed) known = known || key == a;
    if (!known) Place(path, it->first, prefix + key).fail("unknown key (expected " + list(allowed) + ")");
  }
}

double number(const std::string& path, const YAML::Node& node, const std::string& key) {
  const Place place(path, node, key);
  if (!node.IsScalar()) place.fail("not a number");
  double value = 0;
  try {
    value = node.as<double>();
  } catch (const YAML::Exception&) {
    place.fail("'" + node.Scalar() + "' is not a number");
  }
  if (!std::isfinite(value)) place.fail("'" + node.Scalar() + "' is not finite");
  return value;
}

std::array<double, 3> vector3(const std::string& path, const YAML::Node& node, const std::string& key) {
  if (!node.IsSequence() || node.size() != 3) Place(path, node, key).fail("not a list of three numbers [x, y, z]");
  std::array<double, 3> v{};
  for (std::size_t k = 0; k < 3; ++k) {
    v[k] = number(path, node[k], key + "[" + std::to_string(k) + "]");
    if (!std::isfinite(static_cast<float>(v[k]))) Place(path, node[k], key).fail("beyond float's range");
  }
  return v;
}

const YAML::Node required(const std::string& path, const YAML::Node& map, const char* key, const std::string& where) {
  const YAML::Node node = map[key];
  if (!node) Place(path, map, where).fail(std::string("key '") + key + "' missing");
  return node;
}

shared::RangerBeam read_beam(const std::string& path, const YAML::Node& node, const std::string& name) {
  if (!node.IsMap()) Place(path, node, name).fail("not a map with origin_m and direction");
  check_keys(path, node, name + ".", {"origin_m", "direction"});
  const std::array<double, 3> origin = vector3(path, required(path, node, "origin_m", name), name + ".origin_m");
  const YAML::Node direction_node = required(path, node, "direction", name);
  const std::array<double, 3> d = vector3(path, direction_node, name + ".direction");
  const double norm = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (!(norm > 0) || !std::isfinite(norm))
    Place(path, direction_node, name + ".direction").fail("zero or unusable length: a beam needs a direction");
  shared::RangerBeam beam;
  for (std::size_t k = 0; k < 3; ++k) {
    beam.origin_m[k] = static_cast<float>(origin[k]);
    beam.direction[k] = static_cast<float>(d[k] / norm);
  }
  return beam;
}

// The platform's own judgement of the rangers (app::prepare_ranger_plane, on the block's floats),
// as an error at the offending key: the platform would take the block and answer kNoParameters.
void check_rangers(const std::string& path, const YAML::Node& rangers, const shared::PlatformGeometry& block) {
  core::RangePlaneModel model;
  const app::RangerLayoutCheck check = app::prepare_ranger_plane(block, model);
  const std::size_t i = check.ranger;
  const std::string name = "rangers[" + std::to_string(i) + "]";
  std::ostringstream s;
  switch (check.status) {
    case app::RangerLayoutStatus::kOk:
      return;
    case app::RangerLayoutStatus::kBeamOffAxis: {
      const auto& d = block.rangers[i].direction;
      s << "(" << d[0] << ", " << d[1] << ", " << d[2]
        << ") normalized is not along the optical axis +z within 1e-3 in x and y: the "
           "platform's plane fit needs beams parallel to it and would answer kNoParameters";
      Place(path, rangers[i]["direction"], name + ".direction").fail(s.str());
    }
    case app::RangerLayoutStatus::kOriginZ:
      s << "z " << block.rangers[i].origin_m[2] << " m differs from rangers[0]'s " << block.rangers[0].origin_m[2]
        << " m by more than 0.1 mm: the platform's plane fit needs a common origin z "
           "and would answer kNoParameters";
      Place(path, rangers[i]["origin_m"], name + ".origin_m").fail(s.str());
    case app::RangerLayoutStatus::kNoPlane:
      Place(path, rangers, "rangers")
          .fail(
              "three of the origins lie on one line in (x, y): the platform cannot fit a plane to the ranges and "
              "would answer kNoParameters");
  }
}

}  // namespace

shared::CameraIntrinsics read_camera_block(const std::string& camera_yaml) {
  try {
    return camera::to_platform(camera::load_camera(camera_yaml));
  } catch (const PlatformSetupError&) {
    throw;
  } catch (const std::exception& e) {
    const std::string what = e.what();
    // The loader's messages start with the path; to_platform's name only the parameter.
    throw PlatformSetupError(what.rfind(camera_yaml, 0) == 0 ? what : camera_yaml + ": " + what);
  }
}

shared::PlatformGeometry read_geometry_block(const std::string& path) {
  const std::string text = files::read_text_or_throw<PlatformSetupError>(path, files::kSettingsFile);
  YAML::Node root;
  try {
    files::check_yaml_text<PlatformSetupError>(text, path);
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw PlatformSetupError(path + ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1) +
                             ": not valid YAML: " + e.msg);
  } catch (const YAML::Exception& e) {
    throw PlatformSetupError(path + ": cannot read: " + e.what());
  }
  if (!root.IsMap()) throw PlatformSetupError(path + ": not a map of rangers, fiducial_side_m, square_pitch_m");
  check_keys(path, root, "", {"rangers", "fiducial_side_m", "square_pitch_m"});

  shared::PlatformGeometry block;
  const YAML::Node rangers = required(path, root, "rangers", "rangers");
  if (!rangers.IsSequence() || rangers.size() != shared::kRangers) {
    Place(path, rangers, "rangers")
        .fail("must list exactly " + std::to_string(shared::kRangers) + " rangers, found " +
              (rangers.IsSequence() ? std::to_string(rangers.size()) : std::string("no list")));
  }
  for (std::size_t i = 0; i < shared::kRangers; ++i)
    block.rangers[i] = read_beam(path, rangers[i], "rangers[" + std::to_string(i) + "]");
  check_rangers(path, rangers, block);

  double side_m = target::kDotyFiducialSideM;
  if (const YAML::Node n = root["fiducial_side_m"]) {
    side_m = number(path, n, "fiducial_side_m");
    if (!(side_m > 0) || static_cast<float>(side_m) <= 0.0f) Place(path, n, "fiducial_side_m").fail("must be positive");
  }
  double pitch_m = target::kDotySquareM;
  const YAML::Node pitch_node = root["square_pitch_m"];
  if (pitch_node) pitch_m = number(path, pitch_node, "square_pitch_m");
  block.square_pitch_m = static_cast<float>(pitch_m);
  if (block.square_pitch_m != 0.0f) {
    const auto fail = [&](const std::string& what) {
      if (pitch_node) Place(path, pitch_node, "square_pitch_m").fail(what);
      std::ostringstream s;
      s << path << ": square_pitch_m (default " << pitch_m << "): " << what;
      throw PlatformSetupError(s.str());
    };
    if (!(block.square_pitch_m >= shared::kMinSquarePitchM && block.square_pitch_m <= shared::kMaxSquarePitchM)) {
      std::ostringstream s;
      s << pitch_m << " m: must be 0 (one square per frame) or within [" << shared::kMinSquarePitchM << ", "
        << shared::kMaxSquarePitchM << "] m";
      fail(s.str());
    }
    if (!(pitch_m > 2 * 7.5 * side_m)) {
      std::ostringstream s;
      s << pitch_m << " m: neighbouring squares' fiducials would overlap (the pitch must exceed 15 x fiducial_side_m = "
        << 15 * side_m << " m)";
      fail(s.str());
    }
  }

  const std::array<target::FiducialRect, 6> fiducials = target::doty_square_fiducials(side_m);
  static_assert(6 <= shared::kMaxFiducials);
  block.fiducial_count = static_cast<std::uint8_t>(fiducials.size());
  for (std::size_t k = 0; k < fiducials.size(); ++k) {
    block.fiducial_square_m[k] = {static_cast<float>(fiducials[k].centre_m.x()),
                                  static_cast<float>(fiducials[k].centre_m.y()), 0.0f};
  }

  // The block's own decoder must take it (the platform runs the same).
  std::array<std::uint8_t, shared::kGeometryBytes> image{};
  shared::PlatformGeometry decoded;
  if (shared::encode_block(block, image) != image.size() ||
      shared::decode_block(image, decoded) != shared::DecodeStatus::kOk)
    throw PlatformSetupError(path + ": the geometry block does not encode (a value beyond the block's range)");
  return block;
}

}  // namespace kincal::session

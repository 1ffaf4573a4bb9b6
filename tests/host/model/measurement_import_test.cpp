// kincal import's reader (host/model/measurement_import.hpp): separators, decimal commas, units,
// Euler conventions, standard deviations, errors naming file:line:column, and the shared real
// UR10 laser-tracker export read as it is.
#include "host/model/measurement_import.hpp"
#include "tests/host/model/ur10_realdata.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <sstream>

namespace model = kincal::model;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

std::string error_of(const std::string& text, const model::ImportOptions& o) {
  std::istringstream in(text);
  try {
    (void)model::import_measurements(in, "x.csv", o);
  } catch (const model::InputError& e) {
    return e.what();
  }
  return "";
}

model::ImportOptions two_joint_options() {
  model::ImportOptions o;
  o.joints = {"J 1", "J 2"};
  o.joint_units = {model::JointUnit::deg};
  o.position = {"X", "Y", "Z"};
  o.position_unit = model::LengthUnit::mm;
  return o;
}

}  // namespace

TEST_CASE("Euler conventions: intrinsic xyz is extrinsic zyx with the angles reversed") {
  const Eigen::Vector3d a(0.3, -0.7, 1.1);
  const Eigen::Matrix3d intrinsic = model::rotation_from_euler(model::parse_euler_convention("intrinsic-xyz"), a);
  const Eigen::Matrix3d expected =
      (Eigen::AngleAxisd(a(0), Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(a(1), Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(a(2), Eigen::Vector3d::UnitZ()))
          .toRotationMatrix();
  CHECK((intrinsic - expected).norm() < 1e-14);
  const Eigen::Matrix3d extrinsic =
      model::rotation_from_euler(model::parse_euler_convention("extrinsic-zyx"), Eigen::Vector3d(a(2), a(1), a(0)));
  CHECK((intrinsic - extrinsic).norm() < 1e-14);
  // ZYZ (proper Euler) is accepted; xx and other names are not.
  CHECK_NOTHROW(model::parse_euler_convention("intrinsic-zyz"));
  CHECK_THROWS_AS(model::parse_euler_convention("intrinsic-xxz"), model::InputError);
  CHECK_THROWS_AS(model::parse_euler_convention("xyz"), model::InputError);
  CHECK_THROWS_AS(model::parse_length_unit("cm"), model::InputError);
}

TEST_CASE("semicolons, decimal commas, units and standard deviations") {
  model::ImportOptions o = two_joint_options();
  o.position_std = {"sx", "sy", "sz"};
  o.angles = {"a", "b", "c"};
  o.convention = model::parse_euler_convention("intrinsic-xyz");
  o.angle_unit = model::AngleUnit::deg;
  std::istringstream in(
      "Time; J 1; J 2; X; sx; Y; sy; Z; sz; a; b; c\n"
      "1,5; 90; -45,5; 1000; 0,01; -2,5; 0,02; 3; 0,03; 90; 0; 0\n"
      "\n"
      "2; 0; 1e1; 1; 0,01; 2; 0,01; 3; 0,01; 0; 0; 0\n");
  const model::ImportResult r = model::import_measurements(in, "x.csv", o);
  CHECK(r.separator == ';');
  CHECK(r.decimal_comma);
  REQUIRE(r.data.rows.size() == 2);
  const model::Measurement& m = r.data.rows[0];
  CHECK(m.line == 2);
  CHECK(m.q[0] == doctest::Approx(std::numbers::pi / 2));
  CHECK(m.q[1] == doctest::Approx(-45.5 * kDeg));
  CHECK(m.position.x() == doctest::Approx(1.0));
  CHECK(m.position.y() == doctest::Approx(-0.0025));
  REQUIRE(m.covariance);
  CHECK((*m.covariance)(1, 1) == doctest::Approx(4e-10));
  CHECK((*m.covariance)(0, 1) == 0.0);
  REQUIRE(m.orientation);
  CHECK(m.orientation->angularDistance(
            Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()))) < 1e-12);
  CHECK(r.data.rows[1].line == 4);
  CHECK(r.data.rows[1].q[1] == doctest::Approx(10 * kDeg));
  CHECK(r.data.noise == model::NoiseColumns::covariance);
}

TEST_CASE("tabs and points; errors name file, line and column") {
  model::ImportOptions o = two_joint_options();
  std::istringstream in("J 1\tJ 2\tX\tY\tZ\n1.5\t2\t3\t4\t5\n");
  const model::ImportResult r = model::import_measurements(in, "x.csv", o);
  CHECK(r.separator == '\t');
  CHECK(!r.decimal_comma);
  CHECK(r.data.rows[0].position.z() == doctest::Approx(0.005));

  CHECK(error_of("J 1,J 2,X,Y,Z\n1,2,3,oops,5\n", o) == "x.csv:2:4: column 'Y': 'oops' is not a number");
  CHECK(error_of("J 1,J 2,X,Y,Z\n1,2,3,4\n", o).starts_with("x.csv:2:5: expected 5 fields as in the header, found 4"));
  CHECK(error_of("J 1,J 2,X,Y\n1,2,3,4\n", o).starts_with("x.csv:1:5: no column named 'Z' in the header"));
  CHECK(error_of("J 1,J 2,X,Y,Z,X\n", o) == "x.csv:1:6: header: column 'X' appears twice");
  CHECK(error_of("J 1,J 2,X,Y,Z\n1,2,3,4,inf\n", o) == "x.csv:2:5: column 'Z' is not finite");
  o.position_std = {"X", "Y", "J 1"};  // one column for two values: a typing slip, refused (issue #25)
  CHECK(error_of("J 1,J 2,X,Y,Z\n0,2,3,4,5\n", o) ==
        "x.csv:1:3: column 'X' is named twice: as value 1 of --position and as value 1 of --position-std (every "
        "column feeds one value)");
  o.position_std = {"SX", "SY", "SZ"};
  CHECK(error_of("J 1,J 2,X,Y,Z,SX,SY,SZ\n0,2,3,4,5,0,1,1\n", o) ==
        "x.csv:2:6: column 'SX': a standard deviation must be > 0");
  CHECK(error_of("J 1,J 2,X,Y,Z,SX,SY,SZ\n", o) == "x.csv: no data rows after the header");
}

TEST_CASE("the real UR10 laser-tracker export, read as it is") {
  const model::ImportResult r = kincal::realdata::import_ur10(KINCAL_REALDATA_DIR);
  CHECK(r.separator == ';');
  CHECK(r.decimal_comma);
  REQUIRE(r.data.rows.size() == 1495);
  const model::Measurement& first = r.data.rows.front();
  CHECK(first.line == 2);
  CHECK(first.q[0] == doctest::Approx(-3.14159));
  CHECK(first.q[1] == doctest::Approx(-1.5708));
  CHECK(first.position.x() == doctest::Approx(0.38376294));
  CHECK(first.position.y() == doctest::Approx(-3.2408734));
  CHECK((*first.covariance)(0, 0) == doctest::Approx(0.031674e-3 * 0.031674e-3));
  const Eigen::Matrix3d expected =
      model::rotation_from_euler({true, {0, 1, 2}}, Eigen::Vector3d(-90.179302, -20.118749, -90.169308) * kDeg);
  CHECK(first.orientation->angularDistance(Eigen::Quaterniond(expected)) < 1e-12);
  // The tracker's own precision: about 0.01 mm and a few thousandths of a degree.
  CHECK(r.median_position_std_m > 3e-6);
  CHECK(r.median_position_std_m < 3e-5);
  CHECK(r.median_angle_std_rad < 0.01 * kDeg);
}

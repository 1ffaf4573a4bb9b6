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
  CHECK(error_of("J 1,J 2,X,Y,Z,X\n", o) ==
        "x.csv:1:6: header: column 'X' appears 2 times (columns 3 and 6): name the one meant by its number, #3 or #6");
  CHECK(error_of("J 1,J 2,X,Y,Z\n1,2,3,4,inf\n", o) == "x.csv:2:5: column 'Z' is not finite");
  o.position_std = {"X", "Y", "J 1"};  // one column for two values: a typing slip, refused (issue #25)
  CHECK(error_of("J 1,J 2,X,Y,Z\n0,2,3,4,5\n", o) ==
        "x.csv:1:3: column 'X' is named twice: as value 1 of --position and as value 1 of --position-std (every "
        "column feeds one value)");
  o.position_std = {"SX", "SY", "SZ"};
  CHECK(error_of("J 1,J 2,X,Y,Z,SX,SY,SZ\n0,2,3,4,5,0,1,1\n", o) ==
        "x.csv:2:6: column 'SX': a standard deviation must be > 0");
  CHECK(error_of("J 1,J 2,X,Y,Z,SX,SY,SZ\n", o) == "x.csv: no data rows after the header");
  o.position_std.reset();  // at most kMaxRows data rows (dataset.hpp): the dataset written must be one to read
  std::string rows = "J 1,J 2,X,Y,Z\n";
  for (std::size_t i = 0; i <= model::kMaxRows; ++i) rows += "1,2,3,4,5\n";
  CHECK(error_of(rows, o) == "x.csv:" + std::to_string(model::kMaxRows + 2) + ":1: " + model::too_many_rows());
}

TEST_CASE("a whitespace-aligned export (numpy.savetxt, a fixed-width report): runs of blanks, detected or given") {
  model::ImportOptions o = two_joint_options();
  o.joints = {"J1", "J2"};
  // Padded to the column's width, a leading blank and tabs among the spaces, a blank line.
  const std::string aligned =
      "# fixed-width report of a tracker session\n"
      "     J1        J2          X           Y         Z\n"
      "   1.500    -2.000     3.000       4.000  \t 5.000\n"
      "\n"
      "  10.250     0.000   -300.125    400.000   500.500   \n";
  std::istringstream in(aligned);
  const model::ImportResult r = model::import_measurements(in, "x.txt", o);
  CHECK(r.separator == ' ');
  CHECK(r.header_line == 2);
  REQUIRE(r.data.rows.size() == 2);
  CHECK(r.data.rows[0].q[1] == doctest::Approx(-2.0 * kDeg));
  CHECK(r.data.rows[1].position.x() == doctest::Approx(-0.300125));
  CHECK(r.data.rows[1].line == 5);
  o.separator = ' ';  // given: the same
  std::istringstream again(aligned);
  CHECK(model::import_measurements(again, "x.txt", o).data.rows.size() == 2);
  o.separator = 0;
  // Names with a blank stand in quotes; a cell left empty cannot be told from alignment: the row
  // has fewer fields than the header, named.
  o.joints = {"J 1", "J 2"};
  std::istringstream quoted("\"J 1\"  \"J 2\"   X   Y   Z\n 1  2  3  4  5\n");
  CHECK(model::import_measurements(quoted, "x.txt", o).data.rows[0].position.z() == doctest::Approx(0.005));
  CHECK(error_of("\"J 1\" \"J 2\" X Y Z\n1 2  4 5\n", o)
            .starts_with("x.csv:2:5: expected 5 fields as in the header, found 4"));
  CHECK(error_of("\"J 1\" \"J 2\" X Y Z\n1 2 \"3 4 5\n", o).starts_with("x.csv:2:1: a double quote is not closed"));
  // A comma in a number of such a file is a decimal comma, as in a ';' separated one.
  o.joints = {"J1", "J2"};
  std::istringstream commas("J1 J2 X Y Z\n1,5 2 3 4 5\n");
  const model::ImportResult c = model::import_measurements(commas, "x.txt", o);
  CHECK(c.decimal_comma);
  CHECK(c.data.rows[0].q[0] == doctest::Approx(1.5 * kDeg));
  // numpy.savetxt's header is a comment, "# J1 J2 ...": the mark is no column; a column named "#"
  // (a row number) is one.
  std::istringstream numpy("# J1  J2  X  Y  Z\n 1.0  2.0  3.0  4.0  5.0\n");
  CHECK(model::import_measurements(numpy, "x.txt", o).data.rows[0].position.z() == doctest::Approx(0.005));
  std::istringstream numbered("#;J1;J2;X;Y;Z\n7;1;2;3;4;5\n");
  CHECK(model::import_measurements(numbered, "x.csv", o).data.rows[0].position.z() == doctest::Approx(0.005));
  // A header a ';', tab or ',' splits is never split at its blanks.
  std::istringstream semicolons("J1 ;J2; X ;Y;Z\n1;2;3;4;5\n");
  CHECK(model::import_measurements(semicolons, "x.csv", o).separator == ';');
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

TEST_CASE("import --id: the row id is kept, written to the dataset, read back and named in messages") {
  model::ImportOptions o = two_joint_options();
  o.id = "Stamp";
  // A spreadsheet's time stamp with a decimal comma, a quoted one, one plain.
  std::istringstream in("Stamp;J 1;J 2;X;Y;Z\n2,02011E+13;1;2;3;4;5\n\" r 2 \";1;2;3;4;6\nr-7;1;2;3;4;7\n");
  model::ImportResult r = model::import_measurements(in, "x.csv", o);
  REQUIRE(r.data.rows.size() == 3);
  CHECK(r.data.rows[0].id == "2,02011E+13");
  CHECK(r.data.rows[1].id == "r 2");
  CHECK(r.data.rows[2].id == "r-7");
  CHECK(r.distinct_ids == 3);
  r.data.rows[2].id = "say \"a\", \"b\"";  // what the dataset writes in quotes and reads back
  std::ostringstream written;
  model::write_dataset(written, r.data);
  CHECK(written.str().starts_with("q1,q2,x,y,z,id\n"));
  CHECK(written.str().find(",\"2,02011E+13\"\n") != std::string::npos);
  CHECK(written.str().find(",\"say \"\"a\"\", \"\"b\"\"\"\n") != std::string::npos);
  std::istringstream back(written.str());
  const model::Dataset d = model::parse_dataset(back, "d.csv");
  REQUIRE(d.rows.size() == 3);
  for (std::size_t k = 0; k < 3; ++k) {
    CHECK(d.rows[k].id == r.data.rows[k].id);
    CHECK(d.rows[k].position == r.data.rows[k].position);
  }
  // A dataset without the column reads as before; rows have no id and write no column.
  std::istringstream old("q1,x,y,z\n0.5,1,2,3\n");
  const model::Dataset plain = model::parse_dataset(old, "old.csv");
  CHECK(plain.rows[0].id.empty());
  std::ostringstream plain_written;
  model::write_dataset(plain_written, plain);
  CHECK(plain_written.str() == "q1,x,y,z\n0.5,1,2,3\n");
  // A comma export whose quoted fields hold commas (a spreadsheet's time stamp, a comment) and a
  // quote: the fields as RFC 4180 reads them.
  {
    model::ImportOptions c = two_joint_options();
    c.id = "Stamp";
    std::istringstream commas(
        "\"Stamp\",J 1,J 2,X,Y,Z,\"Note, free\"\n\"Nov 27, 2026 10:00\",1,2,3,4,5,\"moved \"\"a\"\", then b\"\n");
    const model::ImportResult q = model::import_measurements(commas, "c.csv", c);
    REQUIRE(q.data.rows.size() == 1);
    CHECK(q.data.rows[0].id == "Nov 27, 2026 10:00");
    CHECK(q.data.rows[0].position.z() == doctest::Approx(0.005));
    // A field spanning lines, and text after a closing quote.
    CHECK(error_of("Stamp,J 1,J 2,X,Y,Z\n\"a\nb\",1,2,3,4,5\n", c) ==
          "x.csv:2:1: a double quote is not closed on this line, or text follows a closing quote (a quoted field may "
          "hold the separator, not a line break)");
    CHECK(
        error_of("Stamp,J 1,J 2,X,Y,Z\n\"a\"b,1,2,3,4,5\n", c).starts_with("x.csv:2:1: a double quote is not closed"));
  }
  // Messages about a row name its id; an empty id and an open quote are refused.
  CHECK(error_of("Stamp;J 1;J 2;X;Y;Z\nt1;1;2;3;oops;5\n", o) ==
        "x.csv:2:5: column 'Y': 'oops' is not a number (id t1)");
  CHECK(error_of("Stamp;J 1;J 2;X;Y;Z\n;1;2;3;4;5\n", o) == "x.csv:2:1: column 'Stamp' (--id) is empty");
  o.position = {"X", "Y", "Stamp"};
  CHECK(error_of("Stamp;J 1;J 2;X;Y;Z\nt1;1;2;3;4;5\n", o) ==
        "x.csv:1:1: column 'Stamp' is named twice: as value 3 of --position and as the row id (--id) (every column "
        "feeds one value)");
  const auto dataset_error = [](const std::string& text) {
    std::istringstream is(text);
    try {
      (void)model::parse_dataset(is, "d.csv");
    } catch (const model::InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(dataset_error("q1,x,y,z,id\n1,2,x,4,\"t,9\"\n") == "d.csv:2: column y: 'x' is not a number (id t,9)");
  CHECK(dataset_error("q1,x,y,z,id\n1,2,3,4,\"\"\n") == "d.csv:2: column id is empty");
  CHECK(dataset_error("q1,x,y,z,id\n1,2,3,4,\"t,9\n") ==
        "d.csv:2: a double quote is not closed, or text follows a closing quote");
  CHECK(dataset_error("q1,x,y,z,id\n1,2,3,4,\"t\"9\n") ==
        "d.csv:2: a double quote is not closed, or text follows a closing quote");
}

TEST_CASE("the real UR10 export's Timestamp column as the id: one value for every row") {
  model::ImportOptions o = kincal::realdata::ur10_import_options();
  o.id = "Timestamp";
  const model::ImportResult r = model::import_measurements_file(
      KINCAL_REALDATA_DIR "/ur10-laser-tracker/measurements_joint_configurations.csv", o);
  REQUIRE(r.data.rows.size() == 1495);
  CHECK(r.data.rows[0].id == "2,02011E+13");  // a spreadsheet rounded the stamps: they tell no row apart
  CHECK(r.distinct_ids == 1);
}

// Issue #44: exports as spreadsheets write them -- quoted fields, either separator, either
// decimal mark, detected together; what is ambiguous is refused saying why.
TEST_CASE("quoted decimal commas in a ',' separated export read; ambiguous marks are refused") {
  model::ImportOptions o = two_joint_options();
  const auto read = [&](const std::string& text) {
    std::istringstream in(text);
    return model::import_measurements(in, "x.csv", o);
  };
  // A tracker export: ',' separators, every number quoted with a decimal comma.
  const model::ImportResult quoted =
      read("\"J 1\",\"J 2\",\"X\",\"Y\",\"Z\"\n\"1,5\",\"2\",\"-21,140068\",\"4,25\",\"5\"\n");
  CHECK(quoted.separator == ',');
  CHECK(quoted.decimal_comma);
  CHECK(quoted.data.rows[0].q[0] == doctest::Approx(1.5 * kDeg));
  CHECK(quoted.data.rows[0].position.x() == doctest::Approx(-0.021140068));
  CHECK(quoted.data.rows[0].position.y() == doctest::Approx(0.00425));
  // The same rows as with decimal points, and as with ';' and tabs (quoted or not).
  const model::ImportResult points = read("J 1,J 2,X,Y,Z\n1.5,2,-21.140068,4.25,5\n");
  CHECK(!points.decimal_comma);
  for (const std::string& text : {std::string("J 1;J 2;X;Y;Z\n1,5;2;-21,140068;4,25;5\n"),
                                  std::string("J 1\tJ 2\tX\tY\tZ\n\"1,5\"\t2\t\"-21,140068\"\t4,25\t5\n"),
                                  std::string("J 1,J 2,X,Y,Z\n\"1,5\",2,\"-21,140068\",\"4,25\",5\n")}) {
    INFO(text);
    const model::ImportResult r = read(text);
    CHECK(r.decimal_comma);
    CHECK(r.data.rows[0].q == points.data.rows[0].q);
    CHECK(r.data.rows[0].position == points.data.rows[0].position);
  }
  // A header name holding a ',' in quotes does not make ',' the separator of a ';' file.
  o.position = {"X, mm", "Y", "Z"};
  CHECK(read("J 1;J 2;\"X, mm\";Y;Z\n1;2;3,5;4;5\n").separator == ';');
  o.position = {"X", "Y", "Z"};
  // Unquoted decimal commas in a ',' separated file split the numbers: the message says so.
  CHECK(error_of("J 1,J 2,X,Y,Z\n1,5,2,-21,140068,4,25,5\n", o)
            .starts_with("x.csv:2:6: expected 5 fields as in the header, found 8 (decimal commas in a ',' separated "
                         "file must be quoted"));
  // Both marks in one ',' separated file: the comma may be a thousands separator.
  CHECK(error_of("J 1,J 2,X,Y,Z\n1.5,2,3,4,5\n\"1,5\",2,3,4,5\n", o) ==
        "x.csv:3:1: column 'J 1': '1,5': this ',' separated file writes numbers with a decimal comma (line 3) and "
        "with a decimal point (line 2), so a comma may be a thousands separator: export with one decimal mark");
  // Both marks in one number: a thousands separator, either way round.
  CHECK(error_of("J 1;J 2;X;Y;Z\n1.234,5;2;3;4;5\n", o) ==
        "x.csv:2:1: column 'J 1': '1.234,5' has both '.' and ',' (a thousands separator?): export the numbers "
        "without one");
  CHECK(error_of("J 1,J 2,X,Y,Z\n\"1,234.5\",2,3,4,5\n", o).find("has both '.' and ','") != std::string::npos);
}

TEST_CASE("a row that holds no measurement (a lost beam, an occluded marker) is left out and listed") {
  model::ImportOptions o = two_joint_options();
  o.id = "T";
  // Empty and NaN measured fields, as tracker and motion-capture exports write them.
  std::istringstream in("T;J 1;J 2;X;Y;Z\n1;1;2;3;4;5\n2;1;2;;;\n3;oops;2;NaN;nan;-NaN\n4;1;2;6;7;8\n");
  const model::ImportResult r = model::import_measurements(in, "x.csv", o);
  REQUIRE(r.data.rows.size() == 2);
  CHECK(r.data.rows[1].position.x() == doctest::Approx(0.006));
  CHECK(r.distinct_ids == 2);
  REQUIRE(r.skipped.size() == 2);
  CHECK(r.skipped[0].line == 3);
  CHECK(r.skipped[0].id == "2");
  CHECK(r.skipped[1].line == 4);  // its joint readings are not read
  // A partial measurement is refused; so is a file with none.
  CHECK(error_of("T;J 1;J 2;X;Y;Z\n1;1;2;3;;5\n", o) == "x.csv:2:5: column 'Y' is empty (id 1)");
  CHECK(error_of("T;J 1;J 2;X;Y;Z\n1;1;2;3;4;NaN\n", o) == "x.csv:2:6: column 'Z' is not finite (id 1)");
  CHECK(error_of("T;J 1;J 2;X;Y;Z\n1;1;2;;;\n2;1;2;nan;nan;nan\n", o) ==
        "x.csv: none of the 2 data rows holds a measurement (every measured column empty or NaN)");
  // With orientation columns named, they are measured columns too: a position alone is partial.
  o.angles = std::array<std::string, 3>{"A", "B", "C"};
  CHECK(error_of("T;J 1;J 2;X;Y;Z;A;B;C\n1;1;2;3;4;5;;;\n", o) == "x.csv:2:7: column 'A' is empty (id 1)");
  std::istringstream posed("T;J 1;J 2;X;Y;Z;A;B;C\n1;1;2;3;4;5;0;0;0\n2;1;2;;;;;;\n");
  CHECK(model::import_measurements(posed, "x.csv", o).skipped.size() == 1);
}

TEST_CASE("lines before the header (a title, settings, a spreadsheet's sep=;) are skipped") {
  const model::ImportOptions o = two_joint_options();
  std::istringstream in("sep=;\n# Tracker export, 2026-12-03\nunits;mm;deg\n\nJ 1;J 2;X;Y;Z\n1;2;3;4;5\n6;7;8;9;10\n");
  const model::ImportResult r = model::import_measurements(in, "x.csv", o);
  CHECK(r.header_line == 5);
  CHECK(r.separator == ';');
  REQUIRE(r.data.rows.size() == 2);
  CHECK(r.data.rows[1].line == 7);
  CHECK(r.data.rows[1].position.x() == doctest::Approx(0.008));
  // No line holds every named column: the first line is the header the message names.
  CHECK(error_of("# title\nJ 1;J 2;X;Y\n1;2;3;4\n", o).starts_with("x.csv:1:2: no column named 'J 1' in the header"));
  CHECK(error_of("J 1;J 2;X;Y\n", o).starts_with("x.csv:1:5: no column named 'Z' in the header"));
  // A title line and the header alone: no data rows.
  CHECK(error_of("title\nJ 1,J 2,X,Y,Z\n", o) == "x.csv: no data rows after the header");
}

TEST_CASE("import --quaternion: w, x, y, z from the columns named, whatever their order; a norm off 1 refused") {
  model::ImportOptions o = two_joint_options();
  o.quaternion = std::array<std::string, 4>{"W", "QX", "QY", "QZ"};
  // A motion-capture export writes x, y, z, w; 90 deg about z, written to 4 digits.
  std::istringstream in("J 1,J 2,X,Y,Z,QX,QY,QZ,W\n1,2,3,4,5,0,0,0.7071,0.7071\n1,2,,,,,,,\n");
  const model::ImportResult r = model::import_measurements(in, "x.csv", o);
  CHECK(r.data.has_orientation);
  REQUIRE(r.data.rows.size() == 1);
  CHECK(r.skipped.size() == 1);  // the row whose position and quaternion are empty (a rigid body lost)
  const Eigen::Matrix3d R = r.data.rows[0].orientation->toRotationMatrix();
  CHECK(R(0, 1) == doctest::Approx(-1.0));
  CHECK(R(1, 0) == doctest::Approx(1.0));
  CHECK(r.data.rows[0].orientation->norm() == doctest::Approx(1.0).epsilon(1e-15));
  CHECK(error_of("J 1,J 2,X,Y,Z,QX,QY,QZ,W\n1,2,3,4,5,3,4,5,1\n", o) ==
        "x.csv:2:9: the quaternion (--quaternion) has norm 7.141428, not 1: are its columns the ones named, in the "
        "order w, x, y, z?");
  CHECK(error_of("J 1,J 2,X,Y,Z,QX,QY,QZ,W\n1,2,3,4,5,0,0,0.7071,\n", o) == "x.csv:2:9: column 'W' is empty");
  o.quaternion = std::array<std::string, 4>{"W", "QX", "QY", "X"};
  CHECK(error_of("J 1,J 2,X,Y,Z,QX,QY,QZ,W\n", o) ==
        "x.csv:1:3: column 'X' is named twice: as value 1 of --position and as value z of --quaternion (every "
        "column feeds one value)");
}

TEST_CASE("a units row under the header (motion-capture exports) is checked against the units given and skipped") {
  const model::ImportOptions o = two_joint_options();  // deg, mm
  std::istringstream in("Trajectories\nJ 1,J 2,X,Y,Z\n[deg],\xc2\xb0,Millimeters,mm,(mm)\n1,2,3,4,5\n");
  const model::ImportResult r = model::import_measurements(in, "x.csv", o);
  CHECK(r.header_line == 2);
  CHECK(r.units_line == 3);
  REQUIRE(r.data.rows.size() == 1);
  CHECK(r.data.rows[0].position.x() == doctest::Approx(0.003));
  // An empty cell is taken as the options say; the id column's cell is not read.
  CHECK(error_of("J 1,J 2,X,Y,Z\n,,mm,mm,mm\n1,2,3,4,5\n", o).empty());
  // A unit other than the one given: refused naming both (a file in m imported as mm).
  CHECK(error_of("J 1,J 2,X,Y,Z\ndeg,deg,m,m,m\n1,2,3,4,5\n", o) ==
        "x.csv:2:3: the units row under the header gives 'm' for column 'X', --position-unit says mm: give "
        "--position-unit m if the file is in m");
  CHECK(error_of("J 1,J 2,X,Y,Z\nrad,rad,mm,mm,mm\n1,2,3,4,5\n", o)
            .starts_with(
                "x.csv:2:1: the units row under the header gives 'rad' for column 'J 1', --joint-unit says deg"));
  CHECK(error_of("J 1,J 2,X,Y,Z\ndeg,deg,in,in,in\n1,2,3,4,5\n", o) ==
        "x.csv:2:3: the units row under the header gives 'in' for column 'X', --position-unit says mm (and 'in' is "
        "no unit kincal reads: m, mm, rad, deg)");
  // A row holding a number is data, however its other cells read: its text is refused as before.
  CHECK(error_of("J 1,J 2,X,Y,Z\n1,deg,mm,mm,mm\n", o) == "x.csv:2:2: column 'J 2': 'deg' is not a number");
  // Only the row under the header is read as units.
  CHECK(error_of("J 1,J 2,X,Y,Z\n1,2,3,4,5\ndeg,deg,mm,mm,mm\n", o) ==
        "x.csv:3:1: column 'J 1': 'deg' is not a number");
}

TEST_CASE("columns by number (#7) where the header holds a name twice, as motion-capture exports write X, Y, Z") {
  model::ImportOptions o = two_joint_options();
  o.position = {"#6", "#7", "#8"};
  o.quaternion = std::array<std::string, 4>{"#5", "#2", "#3", "#4"};
  o.joints = {"J 1", "#10"};
  // A name twice that no option names is no fault; the header is the first line with every name.
  std::istringstream in("Take,1\nFrame,X,Y,Z,W,X,Y,Z,J 1,J 2\n0,0,0,0.7071,0.7071,1,2,3,4,5\n");
  const model::ImportResult r = model::import_measurements(in, "x.csv", o);
  CHECK(r.header_line == 2);
  REQUIRE(r.data.rows.size() == 1);
  CHECK(r.data.rows[0].position.x() == doctest::Approx(0.001));
  CHECK(r.data.rows[0].q[1] == doctest::Approx(5 * kDeg));
  CHECK(r.data.rows[0].orientation->z() == doctest::Approx(std::sqrt(0.5)));
  o.position = {"X", "#7", "#8"};
  CHECK(error_of("Frame,X,Y,Z,W,X,Y,Z,J 1,J 2\n", o) ==
        "x.csv:1:6: header: column 'X' appears 2 times (columns 2 and 6): name the one meant by its number, #2 or #6");
  o.position = {"#6", "#7", "#11"};
  CHECK(error_of("Frame,X,Y,Z,W,X,Y,Z,J 1,J 2\n0,0,0,0.7071,0.7071,1,2,3,4,5\n", o) ==
        "x.csv:1:11: column #11: the header has 10 columns");
  o.position = {"#6", "#7", "#2"};  // one column for two values, by name or number alike
  CHECK(error_of("Frame,X,Y,Z,W,X,Y,Z,J 1,J 2\n0,0,0,0.7071,0.7071,1,2,3,4,5\n", o)
            .starts_with(
                "x.csv:1:2: column 'X' is named twice: as value 3 of --position and as value x of --quaternion"));
}

// candump -L lines: what can-utils writes, we read; what we write, canplayer reads. Bad lines
// fail with a message that says what is wrong.
#include "host/can/candump_log.hpp"

#include <doctest.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

using namespace kincal;

TEST_CASE("candump -L lines parse: classic, extended, CAN FD, remote") {
  auto f = can::parse_candump_line("(1436509052.249713) vcan0 123#DEADBEEF");
  CHECK(f.time_us == 1436509052249713ull);
  CHECK(f.interface == "vcan0");
  CHECK(f.frame.id == 0x123);
  CHECK_FALSE(f.frame.extended);
  CHECK_FALSE(f.frame.fd);
  CHECK(f.frame.length == 4);
  CHECK(f.frame.data[0] == 0xDE);
  CHECK(f.frame.data[3] == 0xEF);
  f = can::parse_candump_line("(0000000001.000001) can0 1F334455#");
  CHECK(f.frame.extended);
  CHECK(f.frame.id == 0x1F334455);
  CHECK(f.frame.length == 0);
  f = can::parse_candump_line("(1.000000) vcan0 112##1000102030405060708090A0B0C0D0E0F");
  CHECK(f.frame.fd);
  CHECK(f.frame.brs);
  CHECK(f.frame.length == 16);
  CHECK(f.frame.data[15] == 0x0F);
  f = can::parse_candump_line("(1.000000) vcan0 170#R");
  CHECK(f.remote);
}

TEST_CASE("format and parse are inverse") {
  can::LoggedFrame in;
  in.time_us = 1700000000123456ull;
  in.interface = "vcan0";
  in.frame.id = 0x11A;
  in.frame.fd = true;
  in.frame.brs = true;
  in.frame.length = 16;
  for (std::uint8_t i = 0; i < 16; ++i) in.frame.data[i] = static_cast<std::uint8_t>(i * 17);
  const std::string line = can::format_candump_line(in);
  CHECK(line == "(1700000000.123456) vcan0 11A##100112233445566778899AABBCCDDEEFF");
  const auto out = can::parse_candump_line(line);
  CHECK(out.time_us == in.time_us);
  CHECK(out.frame.data == in.frame.data);
  in.frame = {};
  in.frame.id = 0x7;
  in.frame.length = 1;
  in.frame.data[0] = 0xAB;
  CHECK(can::format_candump_line(in) == "(1700000000.123456) vcan0 007#AB");
}

TEST_CASE("malformed lines say what is wrong") {
  CHECK_THROWS_WITH_AS(can::parse_candump_line("vcan0 123#00"), doctest::Contains("timestamp"), can::CanError);
  CHECK_THROWS_WITH_AS(can::parse_candump_line("(1.5) vcan0 123#00"), doctest::Contains("6 digits"), can::CanError);
  CHECK_THROWS_WITH_AS(can::parse_candump_line("(1.000000) vcan0 1234#00"), doctest::Contains("3 (standard) or 8"),
                       can::CanError);
  CHECK_THROWS_WITH_AS(can::parse_candump_line("(1.000000) vcan0 123#0"), doctest::Contains("odd"), can::CanError);
  CHECK_THROWS_WITH_AS(can::parse_candump_line("(1.000000) vcan0 123#000102030405060708"),
                       doctest::Contains("9 data bytes"), can::CanError);
  CHECK_THROWS_WITH_AS(can::parse_candump_line("(1.000000) vcan0 123##1000102030405060708"),
                       doctest::Contains("9 data bytes is not a valid CAN FD length"), can::CanError);
  CHECK_THROWS_WITH_AS(can::parse_candump_line("(1.000000) vcan0 800#00"), doctest::Contains("above 7FF"),
                       can::CanError);
  CHECK_THROWS_WITH_AS(can::parse_candump_line("(1.000000) vcan0 12G#00"), doctest::Contains("CAN ID"), can::CanError);
  CHECK_THROWS_WITH_AS(can::parse_candump_line("(1.000000) vcan0 123#ZZ"), doctest::Contains("not hex"), can::CanError);
}

TEST_CASE("the reader names file and line of a bad line") {
  const auto path = (std::filesystem::temp_directory_path() / "kincal-bad.log").string();
  {
    std::ofstream out(path);
    out << "(1.000000) vcan0 123#00\n\n(2.000000) vcan0 123#0\n";
  }
  can::CandumpReader reader(path);
  CHECK(reader.next().has_value());
  CHECK_THROWS_WITH_AS(reader.next(), doctest::Contains(doctest::String((path + ":3: ").c_str())), can::CanError);
  std::filesystem::remove(path);
  CHECK_THROWS_WITH_AS(can::CandumpReader("/nonexistent/x.log"), doctest::Contains("no such file"), can::CanError);
}

// Issue #44: a time stamp's seconds fit the 64-bit microsecond clock or are refused, never wrapped.
TEST_CASE("time stamps beyond the 64-bit microsecond clock are refused naming the line") {
  const std::uint64_t last_s = std::numeric_limits<std::uint64_t>::max() / 1000000 - 1;
  CHECK(can::parse_candump_line("(" + std::to_string(last_s) + ".999999) vcan0 123#00").time_us ==
        last_s * 1000000 + 999999);
  for (const std::string& stamp : {std::to_string(last_s + 1) + ".000000", std::string("18446744073709551616.000000"),
                                   std::string(40, '9') + ".000000"})
    CHECK_THROWS_WITH_AS(can::parse_candump_line("(" + stamp + ") vcan0 123#00"),
                         doctest::Contains("s is beyond the 64-bit microsecond clock (at most 18446744073708 s)"),
                         can::CanError);
  const auto path = (std::filesystem::temp_directory_path() / "kincal-stamp.log").string();
  {
    std::ofstream out(path);
    out << "(1.000000) vcan0 123#00\n(99999999999999999999.000000) vcan0 123#00\n";
  }
  can::CandumpReader reader(path);
  CHECK(reader.next().has_value());
  CHECK_THROWS_WITH_AS(reader.next(), doctest::Contains(doctest::String((path + ":2: timestamp").c_str())),
                       can::CanError);
  std::filesystem::remove(path);
}

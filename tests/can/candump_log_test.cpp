#include "axon/can/candump_log.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

using namespace std::chrono_literals;
using axon::can::CandumpReader;
using axon::can::CandumpReadOptions;
using axon::can::CandumpWriter;
using axon::can::CanErrc;
using axon::can::format_candump_line;
using axon::can::Frame;
using axon::can::IdFormat;
using axon::can::LogDirection;
using axon::can::LogEntry;
using axon::can::parse_candump_line;
using axon::core::WallTime;

namespace {

Frame stamped(Frame f, std::int64_t ns) {
  f.set_timestamp(WallTime(ns));
  return f;
}

std::filesystem::path temp_file(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() / ("axon-candump-test-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir / name;
}

}  // namespace

TEST(CandumpLine, ParsesTheCanUtilsExample) {
  const auto e = parse_candump_line("(1436509052.249713) vcan0 12345678#01020304").value();
  EXPECT_EQ(e.frame.timestamp(), WallTime(1'436'509'052'249'713'000LL));
  EXPECT_EQ(e.iface, "vcan0");
  EXPECT_FALSE(e.error_frame);
  EXPECT_EQ(e.direction, LogDirection::unknown);
  EXPECT_EQ(e.frame, Frame::extended(0x12345678, std::array<std::uint8_t, 4>{1, 2, 3, 4}).value());
  EXPECT_EQ(format_candump_line(e.frame, e.iface), "(1436509052.249713) vcan0 12345678#01020304");
}

TEST(CandumpLine, RemoteFramesWithAndWithoutLength) {
  auto e = parse_candump_line("(1436509052.249713) vcan0 123#R").value();
  EXPECT_EQ(e.frame, Frame::remote(0x123, IdFormat::standard, 0).value());
  EXPECT_EQ(format_candump_line(e), "(1436509052.249713) vcan0 123#R");

  e = parse_candump_line("(1436509052.249713) vcan0 123#R4").value();
  EXPECT_EQ(e.frame, Frame::remote(0x123, IdFormat::standard, 4).value());
  EXPECT_EQ(format_candump_line(e), "(1436509052.249713) vcan0 123#R4");

  e = parse_candump_line("(1436509052.249713) can1 1FFFFFFF#r8").value();
  EXPECT_EQ(e.frame, Frame::remote(0x1FFFFFFF, IdFormat::extended, 8).value());
  EXPECT_EQ(parse_candump_line("(1.000000) can0 123#R0").value().frame.dlc(), 0);
}

TEST(CandumpLine, StandardExtendedAndEmptyFrames) {
  auto e = parse_candump_line("(0000000001.000001) can0 7FF#").value();
  EXPECT_EQ(e.frame, Frame::standard(0x7FF, {}).value());
  EXPECT_EQ(e.frame.timestamp(), WallTime(1'000'001'000LL));
  // Eight digits make an extended id even when the value is small.
  e = parse_candump_line("(1.000000) can0 00000123#DEADBEEF").value();
  EXPECT_TRUE(e.frame.is_extended());
  EXPECT_EQ(e.frame.id(), 0x123u);
  EXPECT_EQ(format_candump_line(e), "(0000000001.000000) can0 00000123#DEADBEEF");
  // Lower-case hex and cansend's dot separators are read too.
  e = parse_candump_line("(1.000000) can0 0ab#de.ad.be.ef").value();
  EXPECT_EQ(e.frame, Frame::standard(0xAB, std::array<std::uint8_t, 4>{0xDE, 0xAD, 0xBE, 0xEF}).value());
}

TEST(CandumpLine, ErrorReports) {
  const auto e = parse_candump_line("(1436509052.249713) can0 20000080#0000000000000000").value();
  EXPECT_TRUE(e.error_frame);
  EXPECT_EQ(e.frame.id(), 0x80u);  // the error classes, without the flag
  EXPECT_EQ(e.frame.dlc(), 8);
  EXPECT_EQ(format_candump_line(e), "(1436509052.249713) can0 20000080#0000000000000000");

  const auto busoff = parse_candump_line("(1.000000) can0 20000044#0004000000000000").value();
  EXPECT_TRUE(busoff.error_frame);
  EXPECT_EQ(busoff.frame.id(), 0x44u);
  EXPECT_EQ(busoff.frame.payload()[1], 0x04);

  // Written as a plain frame, the same entry would be an ordinary extended frame: the flag is what
  // tells readers it is an error report.
  EXPECT_EQ(format_candump_line(busoff.frame, "can0"), "(0000000001.000000) can0 00000044#0004000000000000");
}

TEST(CandumpLine, PythonCanDirectionField) {
  auto e = parse_candump_line("(1436509052.249713) vcan0 123#11 R").value();
  EXPECT_EQ(e.direction, LogDirection::rx);
  e = parse_candump_line("(1436509052.249713) vcan0 123#R T").value();
  EXPECT_EQ(e.direction, LogDirection::tx);
  EXPECT_TRUE(e.frame.is_remote());
  // The direction is not part of the candump format and is not written.
  EXPECT_EQ(format_candump_line(e), "(1436509052.249713) vcan0 123#R");
}

TEST(CandumpLine, TimestampsKeepMicrosecondsAndReadOtherPrecisions) {
  EXPECT_EQ(parse_candump_line("(1.5) can0 123#").value().frame.timestamp(), WallTime(1'500'000'000));
  EXPECT_EQ(parse_candump_line("(1.123456789) can0 123#").value().frame.timestamp(), WallTime(1'123'456'789));
  EXPECT_EQ(parse_candump_line("(0.000000) can0 123#").value().frame.timestamp(), WallTime(0));
  // Writing truncates to the microsecond, as candump does.
  EXPECT_EQ(format_candump_line(stamped(Frame(), 1'123'456'789), "can0"), "(0000000001.123456) can0 000#");
  EXPECT_EQ(format_candump_line(stamped(Frame(), -5), "can0"), "(0000000000.000000) can0 000#");
  EXPECT_EQ(format_candump_line(stamped(Frame(), 8'999'999'999'999'999'999LL), "can0"),
            "(8999999999.999999) can0 000#");
}

TEST(CandumpLine, InterfaceNamesAreOneField) {
  EXPECT_EQ(format_candump_line(stamped(Frame(), 0), "my bus"), "(0000000000.000000) my_bus 000#");
  EXPECT_EQ(format_candump_line(stamped(Frame(), 0), ""), "(0000000000.000000) any 000#");
  EXPECT_EQ(parse_candump_line("(1.0)\tcan0 \t 123#  ").value().iface, "can0");
}

TEST(CandumpLine, CrLfAndSurroundingSpace) {
  const auto e = parse_candump_line("  (1436509052.249713) vcan0 123#0102\r\n").value();
  EXPECT_EQ(e.frame, Frame::standard(0x123, std::array<std::uint8_t, 2>{1, 2}).value());
  EXPECT_EQ(parse_candump_line("(1436509052.249713) vcan0 123#R\r").value().frame.dlc(), 0);
}

TEST(CandumpLine, RoundTrips) {
  const std::array<std::uint8_t, 8> d{0x00, 0xFF, 0x10, 0x01, 0xA5, 0x5A, 0x7E, 0x81};
  std::vector<LogEntry> entries;
  std::int64_t ts = 1'700'000'000'000'000'000LL;
  for (std::size_t n = 0; n <= 8; ++n) {
    for (auto f : {Frame::standard(0x7FF - n, std::span(d).first(n)).value(),
                   Frame::extended(0x1FFFFFFF - n, std::span(d).first(n)).value(),
                   Frame::remote(static_cast<std::uint32_t>(n), IdFormat::standard, static_cast<std::uint8_t>(n)).value(),
                   Frame::remote(0x1000 + n, IdFormat::extended, static_cast<std::uint8_t>(n)).value()}) {
      ts += 1'234'567'000;  // whole microseconds survive exactly
      entries.push_back(LogEntry{stamped(f, ts), n % 2 ? "vcan0" : "can12", false, LogDirection::unknown});
    }
  }
  entries.push_back(LogEntry{stamped(Frame::extended(0x204, d).value(), 7'000'001'000), "can0", true, {}});
  for (const auto& e : entries) {
    const std::string line = format_candump_line(e);
    auto back = parse_candump_line(line);
    ASSERT_TRUE(back) << line << ": " << back.error().message();
    EXPECT_EQ(back.value().frame, e.frame) << line;
    EXPECT_EQ(back.value().frame.to_string(), e.frame.to_string()) << line;
    EXPECT_EQ(back.value().frame.timestamp(), e.frame.timestamp()) << line;
    EXPECT_EQ(back.value().iface, e.iface) << line;
    EXPECT_EQ(back.value().error_frame, e.error_frame) << line;
    EXPECT_EQ(format_candump_line(back.value()), line);
  }
}

TEST(CandumpLine, MalformedLinesAreTypedErrors) {
  const char* bad[] = {
      "",                                              // blank
      "1436509052.249713 vcan0 123#00",                // no parentheses
      "(1436509052.249713 vcan0 123#00",               // unclosed
      "1436509052.249713) vcan0 123#00",               // unopened
      "(abc.def) vcan0 123#00",                        // not a number
      "(1.2.3) vcan0 123#00",                          // two points
      "(-1.000000) vcan0 123#00",                      // negative
      "(1436509052) vcan0 123#00",                     // no fraction
      "(.249713) vcan0 123#00",                        // no seconds
      "(1. ) vcan0 123#00",                            // no fraction digits
      "(1.1234567890) vcan0 123#00",                   // more than ns
      "(99999999999.000000) vcan0 123#00",             // beyond 64-bit nanoseconds
      "(1436509052.249713) vcan0",                     // no frame
      "(1436509052.249713)",                           // only a timestamp
      "(1436509052.249713) vcan0 12300",               // no '#'
      "(1436509052.249713) vcan0 12#00",               // 2-digit id
      "(1436509052.249713) vcan0 1234#00",             // 4-digit id
      "(1436509052.249713) vcan0 XYZ#00",              // id not hex
      "(1436509052.249713) vcan0 800#00",              // over 11 bits
      "(1436509052.249713) vcan0 G2345678#00",         // id not hex
      "(1436509052.249713) vcan0 80000123#00",         // extended flag in the text id
      "(1436509052.249713) vcan0 40000123#00",         // remote flag in the text id
      "(1436509052.249713) vcan0 123#0",               // odd hex
      "(1436509052.249713) vcan0 123#ABC",             // odd hex
      "(1436509052.249713) vcan0 123#GG",              // not hex
      "(1436509052.249713) vcan0 123#001122334455667788",  // 9 bytes
      "(1436509052.249713) vcan0 123#R9",              // remote DLC over 8
      "(1436509052.249713) vcan0 123#RX",              // remote DLC not a digit
      "(1436509052.249713) vcan0 123#R12",             // trailing characters
      "(1436509052.249713) vcan0 20000080#R",          // error report marked remote
      "(1436509052.249713) vcan0 123#0011_9",          // raw DLC on a short frame
      "(1436509052.249713) vcan0 123#00 X",            // unknown fourth field
      "(1436509052.249713) vcan0 123#00 R extra",      // five fields
      "(1436509052.249713) vc\x01n0 123#00",           // control character
  };
  for (const char* line : bad) {
    auto r = parse_candump_line(line);
    ASSERT_FALSE(r) << "accepted: " << line;
    EXPECT_EQ(r.error(), CanErrc::parse_error) << line << ": " << r.error().message();
    EXPECT_FALSE(r.error().detail.empty());
  }
}

TEST(CandumpLine, CanFdAndRawDlcAreNotSupported) {
  for (const char* line : {"(1436509052.249713) vcan0 123##1001122", "(1436509052.249713) vcan0 12345678##0",
                           "(1436509052.249713) vcan0 123#1122334455667788_C", "(1.0) vcan0 123#R8_9"}) {
    auto r = parse_candump_line(line);
    ASSERT_FALSE(r) << line;
    EXPECT_EQ(r.error(), CanErrc::not_supported) << line << ": " << r.error().message();
  }
  EXPECT_NE(parse_candump_line("(1.0) vcan0 123##100").error().detail.find("CAN FD"), std::string::npos);
}

TEST(CandumpReader, ReadsLinesSkippingBlanksAndCrLf) {
  std::istringstream in(
      "(1436509052.249713) vcan0 12345678#01020304\r\n"
      "\r\n"
      "   \n"
      "(1436509052.249714) vcan0 123#R\r\n"
      "(1436509052.249715) vcan1 123#11");  // no final newline
  CandumpReader reader(in, "mem.log");
  std::vector<LogEntry> got;
  for (;;) {
    auto e = reader.next();
    ASSERT_TRUE(e) << e.error().message();
    if (!e.value()) break;
    got.push_back(*e.value());
  }
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].frame.id(), 0x12345678u);
  EXPECT_TRUE(got[1].frame.is_remote());
  EXPECT_EQ(got[2].iface, "vcan1");
  EXPECT_EQ(got[2].frame.timestamp(), WallTime(1'436'509'052'249'715'000LL));
  EXPECT_EQ(reader.lines_read(), 5u);
  EXPECT_EQ(reader.entries_read(), 3u);
  EXPECT_EQ(reader.lines_skipped(), 0u);
  // At the end it stays at the end.
  EXPECT_FALSE(reader.next().value());
}

TEST(CandumpReader, BadLineNamesFileAndLine) {
  std::istringstream in("(1.000000) can0 123#00\n\n(1.000001) can0 123#0\n(1.000002) can0 124#00\n");
  CandumpReader reader(in, "bus.log");
  ASSERT_TRUE(reader.next().value());
  auto bad = reader.next();
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error(), CanErrc::parse_error);
  EXPECT_EQ(bad.error().detail.rfind("bus.log:3: ", 0), 0u) << bad.error().detail;
  // The reader goes on after the bad line.
  auto next = reader.next();
  ASSERT_TRUE(next && next.value());
  EXPECT_EQ(next.value()->frame.id(), 0x124u);
}

TEST(CandumpReader, SkipBadCountsAndContinues) {
  std::istringstream in(
      "(1.000000) can0 123#00\n"
      "garbage\n"
      "(1.000001) can0 123##100\n"
      "(1.000002) can0 124#00\n");
  CandumpReader reader(in, "bus.log", CandumpReadOptions{.skip_bad = true});
  std::vector<std::uint32_t> ids;
  while (auto e = reader.next().value()) ids.push_back(e->frame.id());
  EXPECT_EQ(ids, (std::vector<std::uint32_t>{0x123, 0x124}));
  EXPECT_EQ(reader.lines_skipped(), 2u);
  EXPECT_EQ(reader.lines_read(), 4u);
  ASSERT_TRUE(reader.first_skipped());
  EXPECT_EQ(reader.first_skipped()->detail.rfind("bus.log:2: ", 0), 0u);
}

TEST(CandumpFiles, WriteThenReadAFile) {
  const auto path = temp_file("roundtrip.log");
  std::vector<Frame> frames{
      stamped(Frame::standard(0x123, std::array<std::uint8_t, 2>{0xAB, 0xCD}).value(), 1'436'509'052'249'713'000LL),
      stamped(Frame::extended(0x1ABCDEF, {}).value(), 1'436'509'052'250'000'000LL),
      stamped(Frame::remote(0x7FF, IdFormat::standard, 3).value(), 1'436'509'053'000'001'000LL),
  };
  {
    auto writer = CandumpWriter::create(path).value();
    for (const auto& f : frames) ASSERT_TRUE(writer.write(f, "vcan0"));
    EXPECT_EQ(writer.lines_written(), 3u);
    // Every line is flushed as it is written: another reader sees them now.
    std::ifstream peek(path);
    std::string first;
    std::getline(peek, first);
    EXPECT_EQ(first, "(1436509052.249713) vcan0 123#ABCD");
  }
  auto reader = CandumpReader::open(path).value();
  for (const auto& f : frames) {
    auto e = reader.next().value();
    ASSERT_TRUE(e);
    EXPECT_EQ(e->frame, f);
    EXPECT_EQ(e->frame.timestamp(), f.timestamp());
  }
  EXPECT_FALSE(reader.next().value());

  // Appending keeps what is there.
  {
    auto writer = CandumpWriter::create(path, CandumpWriter::Flush::on_request, true).value();
    ASSERT_TRUE(writer.write(frames[0], "vcan1"));
    ASSERT_TRUE(writer.flush());
  }
  auto again = CandumpReader::open(path).value();
  int n = 0;
  while (again.next().value()) ++n;
  EXPECT_EQ(n, 4);
  std::filesystem::remove_all(path.parent_path());
}

TEST(CandumpFiles, WriterOnAStream) {
  std::ostringstream out;
  CandumpWriter writer(out);
  ASSERT_TRUE(writer.write(stamped(Frame::standard(0x1, {}).value(), 2'000'000), "can0"));
  LogEntry err{stamped(Frame::extended(0x40, std::array<std::uint8_t, 8>{}).value(), 3'000'000), "can0", true, {}};
  ASSERT_TRUE(writer.write(err));
  EXPECT_EQ(out.str(), "(0000000000.002000) can0 001#\n(0000000000.003000) can0 20000040#0000000000000000\n");
}

TEST(CandumpFiles, MissingFilesAreIoErrors) {
  auto r = CandumpReader::open("/nonexistent/axon/bus.log");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), CanErrc::io);
  EXPECT_NE(r.error().detail.find("/nonexistent/axon/bus.log"), std::string::npos);
  auto w = CandumpWriter::create("/nonexistent/axon/bus.log");
  ASSERT_FALSE(w);
  EXPECT_EQ(w.error(), CanErrc::io);
}

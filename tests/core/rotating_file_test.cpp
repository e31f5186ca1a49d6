// Recording files with limits: what lands in NAME, NAME.1, ... after size and age rotations.
#include "axon/core/rotating_file.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <unistd.h>

namespace axon::core {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

struct TempDir {
  fs::path dir = fs::temp_directory_path() / fs::path("axon_rotating_" + std::to_string(::getpid()) + "_" +
                                                      ::testing::UnitTest::GetInstance()->current_test_info()->name());
  TempDir() {
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~TempDir() { fs::remove_all(dir); }
};

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

const TimePoint t0{};

TEST(RotatingFile, WithoutLimitsEverythingStaysInOneFile) {
  TempDir d;
  auto f = RotatingFile::open(d.dir / "log", {}, t0).value();
  for (int i = 0; i < 100; ++i) ASSERT_TRUE(f.write("0123456789\n", t0 + 1h * i));
  ASSERT_TRUE(f.flush());
  EXPECT_EQ(fs::file_size(d.dir / "log"), 1100u);
  EXPECT_EQ(f.rotations(), 0u);
  EXPECT_FALSE(fs::exists(d.dir / "log.1"));
}

TEST(RotatingFile, SizeLimitRotatesBeforeARecordWouldPassItNewestDataInName) {
  TempDir d;
  RotationLimits l;
  l.max_bytes = 10;
  auto f = RotatingFile::open(d.dir / "log", l, t0).value();
  for (const char* r : {"aaaa\n", "bbbb\n", "cccc\n", "dddd\n", "eeee\n"}) ASSERT_TRUE(f.write(r, t0));
  ASSERT_TRUE(f.flush());
  EXPECT_EQ(read(d.dir / "log"), "eeee\n");
  EXPECT_EQ(read(d.dir / "log.1"), "cccc\ndddd\n");
  EXPECT_EQ(read(d.dir / "log.2"), "aaaa\nbbbb\n");
  EXPECT_EQ(f.rotations(), 2u);
}

TEST(RotatingFile, ARecordLargerThanTheLimitGoesWholeIntoAFileOfItsOwn) {
  TempDir d;
  RotationLimits l;
  l.max_bytes = 4;
  auto f = RotatingFile::open(d.dir / "log", l, t0).value();
  ASSERT_TRUE(f.write("0123456789", t0));
  ASSERT_TRUE(f.write("x", t0));
  ASSERT_TRUE(f.flush());
  EXPECT_EQ(read(d.dir / "log.1"), "0123456789");
  EXPECT_EQ(read(d.dir / "log"), "x");
}

TEST(RotatingFile, AgeLimitRotatesOnTheFirstRecordAfterIt) {
  TempDir d;
  RotationLimits l;
  l.max_age = 60s;
  auto f = RotatingFile::open(d.dir / "log", l, t0).value();
  ASSERT_TRUE(f.write("first\n", t0 + 10s));
  ASSERT_TRUE(f.write("second\n", t0 + 59s));
  ASSERT_TRUE(f.write("third\n", t0 + 60s));   // the file is 60 s old: a new one
  ASSERT_TRUE(f.write("fourth\n", t0 + 119s));
  ASSERT_TRUE(f.write("fifth\n", t0 + 121s));  // 61 s after the second file was opened
  ASSERT_TRUE(f.flush());
  EXPECT_EQ(read(d.dir / "log.2"), "first\nsecond\n");
  EXPECT_EQ(read(d.dir / "log.1"), "third\nfourth\n");
  EXPECT_EQ(read(d.dir / "log"), "fifth\n");
}

TEST(RotatingFile, KeepsOnlyTheNewestOldFiles) {
  TempDir d;
  RotationLimits l;
  l.max_bytes = 2;
  l.keep = 2;
  auto f = RotatingFile::open(d.dir / "log", l, t0).value();
  for (const char* r : {"1\n", "2\n", "3\n", "4\n", "5\n"}) ASSERT_TRUE(f.write(r, t0));
  ASSERT_TRUE(f.flush());
  EXPECT_EQ(read(d.dir / "log"), "5\n");
  EXPECT_EQ(read(d.dir / "log.1"), "4\n");
  EXPECT_EQ(read(d.dir / "log.2"), "3\n");
  EXPECT_FALSE(fs::exists(d.dir / "log.3"));
}

TEST(RotatingFile, EveryFileStartsWithTheHeader) {
  TempDir d;
  RotationLimits l;
  l.max_bytes = 12;
  auto f = RotatingFile::open(d.dir / "data.csv", l, t0, "t,v\n").value();
  for (const char* r : {"1,10\n", "2,20\n", "3,30\n"}) ASSERT_TRUE(f.write(r, t0));
  ASSERT_TRUE(f.flush());
  EXPECT_EQ(read(d.dir / "data.csv.2"), "t,v\n1,10\n");
  EXPECT_EQ(read(d.dir / "data.csv.1"), "t,v\n2,20\n");
  EXPECT_EQ(read(d.dir / "data.csv"), "t,v\n3,30\n");
}

TEST(RotatingFile, RefusesKeepZeroAndUnwritablePaths) {
  TempDir d;
  RotationLimits l;
  l.keep = 0;
  EXPECT_EQ(RotatingFile::open(d.dir / "log", l, t0).error(), CoreErrc::invalid_argument);
  EXPECT_EQ(RotatingFile::open(d.dir / "missing" / "log", {}, t0).error(), CoreErrc::io);
}


// A writer with its own file handle (a libpcap dumper) renames with shift(): NAME -> NAME.1 ->
// NAME.2, the oldest beyond `keep` deleted.
TEST(RotatingFile, ShiftRenamesTheChainAndDropsTheOldest) {
  TempDir t;
  const auto name = t.dir / "cap.pcap";
  for (const char* text : {"first", "second", "third"}) {
    std::ofstream(name) << text;
    ASSERT_TRUE(RotatingFile::shift(name, 2));
  }
  EXPECT_FALSE(fs::exists(name));
  EXPECT_EQ(read(RotatingFile::rotated_name(name, 1)), "third");
  EXPECT_EQ(read(RotatingFile::rotated_name(name, 2)), "second");
  EXPECT_FALSE(fs::exists(RotatingFile::rotated_name(name, 3)));
}

// A CSV's title line is known only with the first row: set_header() writes it into the empty file
// and starts every later file with it.
TEST(RotatingFile, HeaderSetLaterStartsTheEmptyFileAndEveryRotatedOne) {
  TempDir t;
  const auto name = t.dir / "run.csv";
  RotationLimits lim;
  lim.max_bytes = 12;
  auto f = RotatingFile::open(name, lim, t0).value();
  ASSERT_TRUE(f.set_header("h\n"));
  ASSERT_TRUE(f.write("row1\n", t0));
  ASSERT_TRUE(f.write("row2\n", t0));  // 2 + 5 + 5 = 12: fits
  ASSERT_TRUE(f.write("row3\n", t0));  // would pass 12: rotates
  ASSERT_TRUE(f.flush());
  EXPECT_EQ(read(RotatingFile::rotated_name(name, 1)), "h\nrow1\nrow2\n");
  EXPECT_EQ(read(name), "h\nrow3\n");
}

}  // namespace
}  // namespace axon::core

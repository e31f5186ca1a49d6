#include "axon/c4g/apps/moni.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

using namespace axon::c4g;
using namespace axon::c4g::apps;

namespace {
protocol::Packet packet(float base, std::int32_t mode) {
  protocol::Packet p;
  p.count = 2;
  for (std::size_t i = 0; i < 2; ++i) {
    auto& a = p.axes[i];
    a.mode = mode;
    const float b = base + 10.0f * static_cast<float>(i);
    a.d1 = b + 1, a.d2 = b + 2, a.d3 = b + 3, a.d4 = b + 4, a.d5 = b + 5, a.ext1 = b + 6, a.ext2 = b + 7, a.ext3 = b + 8;
  }
  return p;
}
}  // namespace

TEST(Moni, ViewsTakeTheManualsFieldsFromTheRightPacket) {
  EXPECT_TRUE(is_moni_type(19));
  EXPECT_TRUE(is_moni_type(24));
  EXPECT_TRUE(is_moni_type(0));
  EXPECT_FALSE(is_moni_type(25));
  EXPECT_FALSE(is_moni_type(18));
  const auto c4g = packet(100, 5), pc = packet(200, 5);
  auto row = [&](int type) {
    std::string s;
    append_moni_row(s, type, 7, 0.5, c4g, pc);
    return s;
  };
  // 19: the whole reply; 20: the whole controller packet.
  EXPECT_EQ(row(19), "7,0.500000,201,202,203,204,205,5,211,212,213,214,215,5\n");
  EXPECT_EQ(row(20), "7,0.500000,101,102,103,104,105,5,111,112,113,114,115,5\n");
  // 21 (mode 5): PC d1 d2, controller d1 d3 d5.
  EXPECT_EQ(row(21), "7,0.500000,201,202,101,103,105,5,211,212,111,113,115,5\n");
  // 22 (mode 2): PC d4 d5, controller d1 d3 d5.
  EXPECT_EQ(row(22), "7,0.500000,204,205,101,103,105,5,214,215,111,113,115,5\n");
  // 23 (mode 9): controller d1 d5 ext1 ext2, PC d5; 24 (mode 8): the same with PC d4.
  EXPECT_EQ(row(23), "7,0.500000,101,105,106,107,205,5,111,115,116,117,215,5\n");
  EXPECT_EQ(row(24), "7,0.500000,101,105,106,107,204,5,111,115,116,117,214,5\n");
}

TEST(Moni, HeaderNamesEveryAxisColumn) {
  EXPECT_EQ(moni_header(22, 2),
            "cycle,time_s,a1_pc_d4,a1_pc_d5,a1_c4g_d1,a1_c4g_d3,a1_c4g_d5,a1_mode,a2_pc_d4,a2_pc_d5,a2_c4g_d1,a2_c4g_d3,"
            "a2_c4g_d5,a2_mode\n");
  EXPECT_EQ(moni_columns(0).size(), 18u);
}

TEST(Moni, WriterWritesHeaderAndRowsWithTimeFromTheFirstRow) {
  const auto path = std::filesystem::temp_directory_path() / ("axon_moni_" + std::to_string(::getpid()) + ".csv");
  {
    auto w = MoniCsvWriter::open(path.string(), 20).value();
    w->write(3, 1'000'000'000, packet(0, 0), packet(0, 0));
    w->write(4, 1'002'000'000, packet(0, 0), packet(0, 0));
    EXPECT_EQ(w->rows(), 2u);
  }
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  std::filesystem::remove(path);
  EXPECT_EQ(text.substr(0, text.find('\n')), moni_header(20, 2).substr(0, moni_header(20, 2).size() - 1));
  EXPECT_NE(text.find("\n3,0.000000,1,2,3,4,5,0,"), std::string::npos);
  EXPECT_NE(text.find("\n4,0.002000,1,2,3,4,5,0,"), std::string::npos);
  EXPECT_FALSE(MoniCsvWriter::open("/nonexistent/dir/x.csv", 20));
  EXPECT_FALSE(MoniCsvWriter::open(path.string(), 18));
}

// With a size limit every CSV file starts with the title line, so each opens alone in a
// spreadsheet or pandas; rows are never split and none is lost.
TEST(Moni, RotatedFilesEachStartWithTheHeader) {
  const auto path = std::filesystem::temp_directory_path() / ("axon_moni_rot_" + std::to_string(::getpid()) + ".csv");
  axon::core::RotationLimits lim;
  lim.max_bytes = 2048;
  lim.keep = 100;
  std::uint64_t rotations = 0;
  {
    auto w = MoniCsvWriter::open(path.string(), 20, lim).value();
    for (int i = 0; i < 100; ++i) w->write(static_cast<std::uint64_t>(i), 1'000'000'000 + i * 2'000'000, packet(0, 0), packet(0, 0));
    rotations = w->rotations();
    EXPECT_EQ(w->write_errors(), 0u);
  }
  EXPECT_GE(rotations, 2u);
  const std::string header = moni_header(20, 2);
  std::size_t rows = 0;
  for (std::uint64_t k = 0; k <= rotations; ++k) {
    const auto name = k == 0 ? path : std::filesystem::path(path.string() + "." + std::to_string(k));
    std::ifstream in(name);
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string text = ss.str();
    EXPECT_EQ(text.substr(0, header.size()), header) << name;
    EXPECT_EQ(text.back(), '\n') << name;
    rows += static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')) - 1;
    std::filesystem::remove(name);
  }
  EXPECT_EQ(rows, 100u);
}

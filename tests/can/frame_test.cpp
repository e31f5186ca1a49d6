#include "axon/can/frame.hpp"

#include <gtest/gtest.h>

#include <array>

using axon::can::CanErrc;
using axon::can::Frame;
using axon::can::IdFormat;

TEST(Frame, ValidatesIdRange) {
  const std::array<std::uint8_t, 1> d{1};
  EXPECT_TRUE(Frame::standard(0x7FF, d));
  auto bad = Frame::standard(0x800, d);
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error(), CanErrc::invalid_id);
  EXPECT_TRUE(Frame::extended(0x1FFFFFFF, d));
  EXPECT_EQ(Frame::extended(0x20000000, d).error(), CanErrc::invalid_id);
}

TEST(Frame, ValidatesLength) {
  std::array<std::uint8_t, 9> nine{};
  EXPECT_EQ(Frame::standard(1, nine).error(), CanErrc::invalid_length);
  EXPECT_TRUE(Frame::standard(1, std::span(nine).first(8)));
  EXPECT_EQ(Frame::remote(1, IdFormat::standard, 9).error(), CanErrc::invalid_length);
  auto r = Frame::remote(1, IdFormat::extended, 8).value();
  EXPECT_TRUE(r.is_remote());
  EXPECT_EQ(r.dlc(), 8);
  EXPECT_TRUE(r.payload().empty());
}

TEST(Frame, ParsesCansendNotation) {
  auto f = Frame::parse("123#DEADBEEF").value();
  EXPECT_EQ(f.id(), 0x123u);
  EXPECT_FALSE(f.is_extended());
  ASSERT_EQ(f.dlc(), 4);
  EXPECT_EQ(f.payload()[0], 0xDE);
  auto e = Frame::parse("0001ABCD#11.22.33").value();
  EXPECT_TRUE(e.is_extended());
  EXPECT_EQ(e.id(), 0x1ABCDu);
  EXPECT_EQ(e.dlc(), 3);
  auto r = Frame::parse("7FF#R3").value();
  EXPECT_TRUE(r.is_remote());
  EXPECT_EQ(r.dlc(), 3);
  EXPECT_EQ(Frame::parse("123#").value().dlc(), 0);
}

TEST(Frame, RejectsMalformedText) {
  for (const char* bad : {"123", "12#00", "XYZ#00", "123#0", "123#GG", "123#001122334455667788", "800#00",
                          "123##0011", "123#R9", "3FFFFFFFF#00"}) {
    auto r = Frame::parse(bad);
    EXPECT_FALSE(r) << bad;
    if (!r) {
      EXPECT_TRUE(r.error() == CanErrc::parse_error || r.error() == CanErrc::invalid_id) << bad;
    }
  }
}

TEST(Frame, PrintsWhatItParses) {
  for (const char* text : {"123#DEADBEEF", "00000001#", "1FFFFFFF#0102030405060708", "000#R", "7FF#R8"}) {
    EXPECT_EQ(Frame::parse(text).value().to_string(), text);
  }
}

TEST(Frame, EqualityIgnoresTimestamp) {
  auto a = Frame::parse("123#01").value();
  auto b = a;
  b.set_timestamp(axon::core::WallTime{42});
  EXPECT_EQ(a, b);
  EXPECT_NE(a, Frame::parse("123#02").value());
  EXPECT_NE(a, Frame::parse("00000123#01").value());
}

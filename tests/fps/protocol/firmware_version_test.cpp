#include "axon/fps/protocol/firmware_version.hpp"

#include "axon/fps/protocol/error.hpp"

#include <gtest/gtest.h>

#include <array>

using namespace axon::fps::protocol;

TEST(FpsFirmwareVersion, FieldByteOrderIsLittleEndian00XXYYZZ) {
  // 04.01.13 arrives as the bytes 13 01 04 00 (ZZ YY XX 00).
  const std::array<std::uint8_t, 4> wire{13, 1, 4, 0};
  const auto v = FirmwareVersion::decode(wire).value();
  EXPECT_EQ(v, (FirmwareVersion{4, 1, 13}));
  EXPECT_EQ(v.to_string(), "04.01.13");
  EXPECT_EQ(v.to_u32(), 0x0004010Du);
  EXPECT_FALSE(v.is_bootloader());
  EXPECT_EQ(v.encode().to_hex(), "0D 01 04 00");
}

TEST(FpsFirmwareVersion, BootloaderHasMinor80) {
  const std::array<std::uint8_t, 4> wire{1, 80, 3, 0};
  const auto v = FirmwareVersion::decode(wire).value();
  EXPECT_EQ(v.to_string(), "03.80.01");
  EXPECT_TRUE(v.is_bootloader());
  EXPECT_FALSE(v.has_64bit_status());
}

TEST(FpsFirmwareVersion, DocumentByteOrderOption) {
  const std::array<std::uint8_t, 4> wire{0, 4, 1, 13};
  const auto v = FirmwareVersion::decode(wire, VersionByteOrder::document).value();
  EXPECT_EQ(v.to_string(), "04.01.13");
  EXPECT_EQ(v.encode(VersionByteOrder::document).to_hex(), "00 04 01 0D");
  // Read in the field order, the same bytes have a non-zero top byte: rejected, not misread.
  EXPECT_EQ(FirmwareVersion::decode(wire).error(), ProtocolErrc::value_out_of_range);
}

TEST(FpsFirmwareVersion, RejectsBadInput) {
  const std::array<std::uint8_t, 3> three{1, 2, 3};
  EXPECT_EQ(FirmwareVersion::decode(three).error(), ProtocolErrc::wrong_length);
  EXPECT_EQ(FirmwareVersion::from_u32(0x01000000).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(FirmwareVersion::parse("4.1").error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(FirmwareVersion::parse("4.1.13.2").error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(FirmwareVersion::parse("4.256.1").error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(FirmwareVersion::parse("a.b.c").error(), ProtocolErrc::value_out_of_range);
}

TEST(FpsFirmwareVersion, ParseCompareAndFeatures) {
  EXPECT_EQ(FirmwareVersion::parse("04.01.13").value(), (FirmwareVersion{4, 1, 13}));
  EXPECT_EQ(FirmwareVersion::parse("4.1.13").value(), (FirmwareVersion{4, 1, 13}));
  EXPECT_LT((FirmwareVersion{4, 0, 99}), (FirmwareVersion{4, 1, 0}));
  EXPECT_FALSE((FirmwareVersion{4, 0, 99}).has_64bit_status());
  EXPECT_TRUE((FirmwareVersion{4, 1, 0}).has_64bit_status());
  EXPECT_FALSE((FirmwareVersion{4, 1, 16}).has_precise_move_switches());
  EXPECT_TRUE((FirmwareVersion{4, 1, 17}).has_precise_move_switches());
}

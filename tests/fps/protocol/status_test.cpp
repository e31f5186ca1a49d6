#include "axon/fps/protocol/bootloader_status.hpp"
#include "axon/fps/protocol/status.hpp"

#include "axon/fps/protocol/error.hpp"

#include <gtest/gtest.h>

#include <array>
#include <utility>

using namespace axon::fps::protocol;

TEST(FpsStatus, BitsMatchTheSpecMasks) {
  // (name, mask) as the interface document's status table gives them (bits 17..19 read as numbers).
  const std::array<std::pair<std::string_view, std::uint64_t>, 34> spec{{
      {"SYSTEM_INITIALIZATION", 0x0000000000000001},
      {"RECEIVING_TRAJECTORY", 0x0000000000000010},
      {"TRAJECTORY_ALPHA_RECEIVED", 0x0000000000000020},
      {"TRAJECTORY_BETA_RECEIVED", 0x0000000000000040},
      {"LOW_POWER_AFTER_MOVE", 0x0000000000000080},
      {"DISPLACEMENT_COMPLETED", 0x0000000000000100},
      {"DISPLACEMENT_COMPLETED_ALPHA", 0x0000000000000200},
      {"DISPLACEMENT_COMPLETED_BETA", 0x0000000000000400},
      {"COLLISION_ALPHA", 0x0000000000000800},
      {"COLLISION_BETA", 0x0000000000001000},
      {"CLOSED_LOOP_ALPHA", 0x0000000000002000},
      {"CLOSED_LOOP_BETA", 0x0000000000004000},
      {"COLLISION_DETECT_ALPHA_DISABLE", 0x00000000000020000},
      {"COLLISION_DETECT_BETA_DISABLE", 0x00000000000040000},
      {"MOTOR_CALIBRATION", 0x00000000000080000},
      {"MOTOR_ALPHA_CALIBRATED", 0x0000000000100000},
      {"MOTOR_BETA_CALIBRATED", 0x0000000000200000},
      {"DATUM_CALIBRATION", 0x0000000000400000},
      {"DATUM_ALPHA_CALIBRATED", 0x0000000000800000},
      {"DATUM_BETA_CALIBRATED", 0x0000000001000000},
      {"DATUM_INITIALIZATION", 0x0000000002000000},
      {"DATUM_ALPHA_INITIALIZED", 0x0000000004000000},
      {"DATUM_BETA_INITIALIZED", 0x0000000008000000},
      {"HALL_ALPHA_DISABLE", 0x0000000010000000},
      {"HALL_BETA_DISABLE", 0x0000000020000000},
      {"COGGING_CALIBRATION", 0x0000000040000000},
      {"COGGING_ALPHA_CALIBRATED", 0x0000000080000000},
      {"COGGING_BETA_CALIBRATED", 0x0000000100000000},
      {"ESTIMATED_POSITION", 0x0000000200000000},
      {"POSITION_RESTORED", 0x0000000400000000},
      {"SWITCH_OFF_AFTER_MOVE", 0x0000000800000000},
      {"PRECISE_MOVE_ALPHA", 0x0000002000000000},
      {"PRECISE_MOVE_BETA", 0x0000004000000000},
      {"SWITCH_OFF_HALL_AFTER_MOVE", 0x0000008000000000},
  }};
  std::uint64_t all = 0;
  for (const auto& [name, m] : spec) {
    const auto bit = status_bit_from_name(name);
    ASSERT_TRUE(bit.has_value()) << name;
    EXPECT_EQ(mask(*bit), m) << name;
    EXPECT_EQ(status_bit_name(*bit), name);
    all |= m;
  }
  EXPECT_EQ(PositionerStatus::kKnownMask, all);
  EXPECT_EQ(status_bit_from_name("system_initialized"), StatusBit::system_initialized);
  EXPECT_FALSE(status_bit_from_name("NOT_A_BIT").has_value());
}

TEST(FpsStatus, NamesListSetBitsAndUnknownOnes) {
  PositionerStatus s;
  s.set(StatusBit::system_initialized).set(StatusBit::displacement_completed).set(StatusBit::cogging_beta_calibrated);
  EXPECT_EQ(s.to_string(), "SYSTEM_INITIALIZATION|DISPLACEMENT_COMPLETED|COGGING_BETA_CALIBRATED");
  s = PositionerStatus((std::uint64_t{1} << 15) | (std::uint64_t{1} << 63) | 1);
  EXPECT_EQ(s.names(), (std::vector<std::string>{"SYSTEM_INITIALIZATION", "BIT_15", "BIT_63"}));
  EXPECT_EQ(s.unknown_bits(), (std::uint64_t{1} << 15) | (std::uint64_t{1} << 63));
  EXPECT_EQ(PositionerStatus().to_string(), "");
}

TEST(FpsStatus, Predicates) {
  PositionerStatus s;
  EXPECT_FALSE(s.ready_to_move());
  s.set(StatusBit::datum_alpha_initialized).set(StatusBit::datum_beta_initialized);
  EXPECT_FALSE(s.ready_to_move());
  s.set(StatusBit::displacement_completed);
  EXPECT_TRUE(s.ready_to_move());
  EXPECT_FALSE(s.initialized());
  s.set(StatusBit::system_initialized);
  EXPECT_TRUE(s.initialized());
  EXPECT_TRUE(s.idle());
  EXPECT_FALSE(s.collided());
  s.set(StatusBit::collision_beta);
  EXPECT_TRUE(s.collided());
  s.clear(StatusBit::displacement_completed);
  EXPECT_FALSE(s.ready_to_move());
  EXPECT_FALSE(s.calibrating());
  s.set(StatusBit::cogging_calibration);
  EXPECT_TRUE(s.calibrating());
  EXPECT_FALSE(s.trajectory_received());
  s.set(StatusBit::trajectory_alpha_received).set(StatusBit::trajectory_beta_received);
  EXPECT_TRUE(s.trajectory_received());
  EXPECT_FALSE(s.hall_disabled());
  s.set(StatusBit::hall_beta_disable);
  EXPECT_TRUE(s.hall_disabled());
}

TEST(FpsStatus, WireIsEightBytesLittleEndianAllBitsKept) {
  const std::array<std::uint8_t, 8> b{0x01, 0x01, 0x00, 0x0C, 0x01, 0x00, 0x00, 0x80};
  const auto s = PositionerStatus::decode(b).value();
  EXPECT_EQ(s.raw(), 0x800000010C000101u);
  EXPECT_TRUE(s.ready_to_move());
  EXPECT_TRUE(s.has(StatusBit::cogging_beta_calibrated));  // bit 32: lost by hosts reading 32 bits
  EXPECT_EQ(s.encode().span().size(), 8u);
  EXPECT_TRUE(std::equal(b.begin(), b.end(), s.encode().data()));
  const std::array<std::uint8_t, 4> four{1, 1, 0, 12};
  EXPECT_EQ(PositionerStatus::decode(four).error(), ProtocolErrc::wrong_length);
}

TEST(FpsBootloaderStatus, BitsMatchTheSpecMasks) {
  const std::array<std::pair<std::string_view, std::uint32_t>, 7> spec{{
      {"BOOTLOADER_INIT", 0x00000001},
      {"BOOTLOADER_TIMEOUT", 0x00000002},
      {"BSETTINGS_CHANGED", 0x00000200},
      {"RECEIVING_NEW_FIRMWARE", 0x00010000},
      {"NEW_FIRMWARE_RECEIVED", 0x01000000},
      {"NEW_FIRMWARE_CHECK_OK", 0x02000000},
      {"NEW_FIRMWARE_CHECK_BAD", 0x04000000},
  }};
  for (const auto& [name, m] : spec) {
    const auto bit = bootloader_bit_from_name(name);
    ASSERT_TRUE(bit.has_value()) << name;
    EXPECT_EQ(mask(*bit), m) << name;
  }
}

TEST(FpsBootloaderStatus, DecodeNamesAndPredicates) {
  const std::array<std::uint8_t, 4> b{0x01, 0x00, 0x00, 0x03};
  const auto s = BootloaderStatus::decode(b).value();
  EXPECT_EQ(s.to_string(), "BOOTLOADER_INIT|NEW_FIRMWARE_RECEIVED|NEW_FIRMWARE_CHECK_OK");
  EXPECT_TRUE(s.upgrade_succeeded());
  EXPECT_FALSE(s.upgrade_failed());
  EXPECT_FALSE(s.receiving());
  EXPECT_EQ(BootloaderStatus(1u << 5).names(), std::vector<std::string>{"BIT_5"});
  const std::array<std::uint8_t, 8> eight{};
  EXPECT_EQ(BootloaderStatus::decode(eight).error(), ProtocolErrc::wrong_length);
  EXPECT_TRUE(std::equal(b.begin(), b.end(), s.encode().data()));
}

#include "axon/fps/protocol/payloads.hpp"

#include "axon/fps/protocol/error.hpp"

#include <gtest/gtest.h>

#include <array>
#include <vector>

using namespace axon::fps::protocol;

namespace {
std::vector<std::uint8_t> bytes(std::initializer_list<int> v) {
  std::vector<std::uint8_t> out;
  for (int b : v) out.push_back(static_cast<std::uint8_t>(b));
  return out;
}
}  // namespace

TEST(FpsPayloads, GoToAbsoluteRequestAndEtaReply) {
  const ArmPositions req{Angle::from_degrees(90).value(), Angle::from_degrees(45).value()};
  // 268435456 = 0x10000000, 134217728 = 0x08000000, little-endian.
  EXPECT_EQ(req.encode().to_hex(), "00 00 00 10 00 00 00 08");
  EXPECT_EQ(ArmPositions::decode(req.encode()).value(), req);
  const auto eta = ArmTimes::decode(bytes({0x20, 0x4E, 0, 0, 0x10, 0x27, 0, 0})).value();
  EXPECT_DOUBLE_EQ(eta.alpha.seconds(), 10.0);  // 20000
  EXPECT_DOUBLE_EQ(eta.beta.seconds(), 5.0);    // 10000
}

TEST(FpsPayloads, NegativePositionsAreSigned) {
  const auto p = ArmPositions::decode(bytes({0, 0, 0, 0xF0, 0xFF, 0xFF, 0xFF, 0xFF})).value();
  EXPECT_DOUBLE_EQ(p.alpha.degrees(), -90.0);
  EXPECT_EQ(p.beta.steps(), -1);
}

TEST(FpsPayloads, TrajectorySizeAndPoint) {
  EXPECT_EQ((TrajectorySize{3, 4}).encode().to_hex(), "03 00 00 00 04 00 00 00");
  EXPECT_EQ(TrajectorySize::decode(bytes({0xFF, 3, 0, 0, 0, 0, 0, 0})).value().alpha_points, 1023u);
  EXPECT_EQ(TrajectorySize::decode(bytes({0, 4, 0, 0, 0, 0, 0, 0})).error(), ProtocolErrc::value_out_of_range);
  const TrajectoryPoint p{Angle::from_degrees(45).value(), Time::from_seconds(5).value()};
  EXPECT_EQ(p.encode().to_hex(), "00 00 00 08 10 27 00 00");
}

TEST(FpsPayloads, RangeCheckedSetters) {
  EXPECT_EQ((ArmMargins{CollisionMargin::from_value(-5).value(), CollisionMargin::from_value(20).value()})
                .encode()
                .to_hex(),
            "FB FF FF FF 14 00 00 00");
  EXPECT_EQ(ArmMargins::decode(bytes({31, 0, 0, 0, 0, 0, 0, 0})).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(ArmMargins::decode(bytes({0xE2, 0xFF, 0xFF, 0xFF, 30, 0, 0, 0})).value().alpha.value(), -30);
  EXPECT_EQ(ArmCurrents::decode(bytes({45, 0, 0, 0, 30, 0, 0, 0})).value().alpha.percent(), 45u);
  EXPECT_EQ(ArmCurrents::decode(bytes({101, 0, 0, 0, 30, 0, 0, 0})).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(ArmSpeeds::decode(bytes({0xB8, 0x0B, 0, 0, 0xD0, 0x07, 0, 0})).value().alpha.rpm(), 3000u);
}

TEST(FpsPayloads, SmallReplies) {
  EXPECT_EQ(PositionerIdReply::decode(bytes({17, 0, 0, 0})).value().id, 17);
  EXPECT_EQ(PositionerIdReply::decode(bytes({0, 8, 0, 0})).error(), ProtocolErrc::positioner_out_of_range);
  EXPECT_EQ(U32Value::decode(bytes({1, 2, 3, 4})).value().value, 0x04030201u);
  EXPECT_EQ(PositionAndValue::decode(bytes({0, 0, 0, 0x10, 0xF6, 0xFF, 0xFF, 0xFF})).value().value, -10);
  EXPECT_EQ(FirmwareUpgradeHeader::decode(bytes({0, 1, 0, 0, 0x26, 0x39, 0xF4, 0xCB})).value().crc32, 0xCBF43926u);
  EXPECT_EQ(FirmwareChunk::decode(bytes({1, 2, 3})).value().data.size(), 3u);
  EXPECT_EQ(FirmwareChunk::decode({}).error(), ProtocolErrc::wrong_length);
  EXPECT_EQ(FirmwareChunk::decode(std::array<std::uint8_t, 9>{}).error(), ProtocolErrc::wrong_length);
}

TEST(FpsPayloads, CommandTypesMatchTheirCommands) {
  static_assert(std::is_same_v<RequestOf<CommandId::go_to_absolute_position>, ArmPositions>);
  static_assert(std::is_same_v<ReplyOf<CommandId::go_to_absolute_position>, ArmTimes>);
  static_assert(std::is_same_v<ReplyOf<CommandId::get_status>, StatusReply>);
  static_assert(std::is_same_v<CommandTypes<CommandId::get_status>::bootloader_reply, BootloaderStatusReply>);
  static_assert(std::is_same_v<RequestOf<CommandId::set_holding_current>, ArmCurrents>);
  static_assert(std::is_same_v<ReplyOf<CommandId::get_holding_current>, ArmCurrents>);
  static_assert(std::is_same_v<RequestOf<CommandId::stop_trajectory>, Empty>);
  SUCCEED();
}

// Every command and direction rejects every size its layout does not accept, and accepts an
// all-zero payload of the right size (zero is in range for every field).
TEST(FpsPayloads, EveryDecoderChecksTheSize) {
  const std::array<std::uint8_t, 9> zeros{};
  for (const auto& c : kCommands) {
    for (auto dir : {Direction::request, Direction::reply}) {
      for (auto mode : {Mode::application, Mode::bootloader}) {
        const auto& l = c.layout(dir, mode);
        for (std::size_t n = 0; n <= 9; ++n) {
          const auto r = check_payload(c.id, dir, mode, std::span(zeros).first(n));
          if (l.accepts(n)) {
            EXPECT_TRUE(r) << c.name << " size " << n << ": " << r.error().message();
          } else {
            ASSERT_FALSE(r) << c.name << " size " << n;
            EXPECT_EQ(r.error(), ProtocolErrc::wrong_length) << c.name << " size " << n;
            EXPECT_EQ(response_code_for(r.error().code), ResponseCode::incorrect_data_length);
          }
        }
      }
    }
  }
}

TEST(FpsPayloads, CheckPayloadReportsValueErrors) {
  const auto r = check_payload(CommandId::set_collision_margin, Direction::request, Mode::application,
                               bytes({40, 0, 0, 0, 0, 0, 0, 0}));
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(response_code_for(r.error().code), ResponseCode::value_out_of_range);
  EXPECT_NE(r.error().detail.find("SET_COLLISION_MARGIN"), std::string::npos);
}

TEST(FpsPayloads, Describe) {
  EXPECT_EQ(describe_payload(CommandId::go_to_absolute_position, Direction::request, Mode::application,
                             bytes({0, 0, 0, 0x10, 0, 0, 0, 8}))
                .value(),
            "alpha=90.0000 deg beta=45.0000 deg");
  EXPECT_EQ(describe_payload(CommandId::get_status, Direction::reply, Mode::bootloader, bytes({1, 0, 0, 0})).value(),
            "BOOTLOADER_INIT");
  EXPECT_EQ(describe_payload(CommandId::get_firmware_version, Direction::reply, Mode::application,
                             bytes({13, 1, 4, 0}))
                .value(),
            "04.01.13");
  EXPECT_EQ(describe_payload(CommandId::stop_trajectory, Direction::request, Mode::application, {}).value(), "");
  EXPECT_EQ(describe_payload(CommandId::get_status, Direction::reply, Mode::application, bytes({1, 0, 0, 0})).error(),
            ProtocolErrc::wrong_length);
}

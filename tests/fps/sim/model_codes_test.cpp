// PositionerModel: the response codes that do not depend on motion: size, broadcast, mode,
// unknown numbers, and the table-wide rules.
#include "harness.hpp"

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::sim;
using namespace axon::fps::sim::testing;

TEST(FpsSimCodes, WrongPayloadLengthIsCode5) {
  Harness h;
  EXPECT_EQ(h.ask(CommandId::get_id, Payload().put_u8(1)).id.response, ResponseCode::incorrect_data_length);
  EXPECT_EQ(h.code(CommandId::go_to_absolute_position, Payload().put_u32(1)), ResponseCode::incorrect_data_length);
  EXPECT_EQ(h.code(CommandId::set_speed, Payload().put_u64(0) /* right size, bad value */),
            ResponseCode::value_out_of_range);
  EXPECT_EQ(h.code(CommandId::send_trajectory_data, Payload().put_u32(1).put_u8(1)), ResponseCode::incorrect_data_length);
  EXPECT_FALSE(h.model.moving());
}

TEST(FpsSimCodes, ErrorRepliesCarryNoData) {
  Harness h;
  const auto m = h.ask(CommandId::get_current_position, Payload().put_u8(0));
  EXPECT_EQ(m.id.response, ResponseCode::incorrect_data_length);
  EXPECT_TRUE(m.payload.empty());
}

TEST(FpsSimCodes, UnicastOnlyCommandsRefuseBroadcastWithCode10) {
  Harness h;
  for (auto c : {CommandId::go_to_absolute_position, CommandId::get_current_position, CommandId::go_to_datums,
                 CommandId::send_new_trajectory, CommandId::switch_on_led}) {
    auto out = h.send(c, c == CommandId::go_to_absolute_position || c == CommandId::send_new_trajectory
                             ? two_u32(1, 1)
                             : Payload{},
                      0);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_EQ(out[0].id.response, ResponseCode::invalid_broadcast) << protocol::command_name(c);
    EXPECT_EQ(out[0].id.uid, 0);
  }
  EXPECT_FALSE(h.model.moving());
}

TEST(FpsSimCodes, BroadcastCommandsAreTakenAsBroadcast) {
  Harness h;
  for (auto c : {CommandId::get_id, CommandId::get_firmware_version, CommandId::get_status,
                 CommandId::trajectory_abort, CommandId::stop_trajectory, CommandId::switch_on_hall,
                 CommandId::switch_off_hall, CommandId::switch_off_led}) {
    auto out = h.send(c, {}, 0);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_EQ(out[0].id.response, ResponseCode::accepted) << protocol::command_name(c);
  }
  Harness fresh;
  auto out = fresh.send(CommandId::start_trajectory, {}, 0);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].id.response, ResponseCode::accepted);  // broadcast is fine; nothing loaded, nothing moves
  EXPECT_FALSE(fresh.model.moving());
}

TEST(FpsSimCodes, BootloaderCommandsInTheApplicationAreCode12) {
  Harness h;
  EXPECT_EQ(h.code(CommandId::start_firmware_upgrade, two_u32(8, 0)), ResponseCode::invalid_command);
  EXPECT_EQ(h.code(CommandId::firmware_data, Payload().put_u8(1)), ResponseCode::invalid_command);
}

TEST(FpsSimCodes, CollisionReportSentToTheRobotIsCode12) {
  Harness h;
  EXPECT_EQ(h.code(CommandId::collision_detected), ResponseCode::invalid_command);
}

TEST(FpsSimCodes, UnknownNumbersAreCode13) {
  Harness h;
  for (std::uint8_t n : {0, 4, 16, 50, 133, 199, 202, 255}) {
    auto out = h.raw(n);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_EQ(out[0].id.response, ResponseCode::unknown_command) << int(n);
    EXPECT_EQ(out[0].id.command, n);
  }
}

TEST(FpsSimCodes, HoldingCurrentNumbersFollowTheSummaryTableByDefault) {
  Harness h;
  EXPECT_EQ(h.code(CommandId::set_holding_current, two_u32(10, 40)), ResponseCode::accepted);
  EXPECT_EQ(h.ask(CommandId::get_holding_current).payload, two_u32(10, 40));
  EXPECT_EQ(h.raw(112).at(0).id.response, ResponseCode::incorrect_data_length);  // empty 112 is a bad set
}

TEST(FpsSimCodes, HoldingCurrentGetOn112WhenConfigured) {
  auto c = test_config();
  c.device_options.get_holding_current_on_112 = true;
  Harness h(c);
  auto out = h.raw(112);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].id.response, ResponseCode::accepted);
  EXPECT_EQ(out[0].id.command, 112);
  EXPECT_EQ(out[0].payload, two_u32(0, 30));
  EXPECT_EQ(h.raw(112, two_u32(5, 6)).at(0).id.response, ResponseCode::accepted);  // 8 bytes: still a set
  EXPECT_EQ(h.raw(112).at(0).payload, two_u32(5, 6));
}

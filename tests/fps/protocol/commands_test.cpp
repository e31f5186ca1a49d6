#include "axon/fps/protocol/commands.hpp"

#include "axon/fps/protocol/error.hpp"

#include <gtest/gtest.h>

#include <set>

using namespace axon::fps::protocol;

TEST(FpsCommands, TableHoldsBothFirmwaresCommands) {
  // Bootloader table (5.2).
  for (int n : {1, 2, 3, 200, 201}) {
    const auto* c = find_command(static_cast<std::uint8_t>(n));
    ASSERT_NE(c, nullptr) << n;
    EXPECT_TRUE(c->bootloader) << n;
  }
  // Main application table (5.3): 64 numbers.
  const std::set<int> app{1,  2,  3,  10, 11, 12, 13, 14, 15, 18,  20,  21,  22,  23,  24,  25,  26,  27,  28,  29,  30,  31,
                          32, 33, 34, 35, 40, 41, 44, 45, 47, 48,  49,  53,  54,  55,  56,  57,  58,  59,  106, 107, 108, 110,
                          111, 112, 113, 116, 117, 118, 119, 120, 121, 122, 123, 124, 125, 126, 127, 128, 129, 130, 131, 132};
  EXPECT_EQ(app.size(), 64u);
  for (int n = 0; n < 256; ++n) {
    const auto* c = find_command(static_cast<std::uint8_t>(n));
    const bool in_app = app.count(n) != 0;
    const bool in_boot = n == 1 || n == 2 || n == 3 || n == 200 || n == 201;
    EXPECT_EQ(c != nullptr, in_app || in_boot) << n;
    if (c != nullptr) {
      EXPECT_EQ(c->application, in_app) << n;
      EXPECT_EQ(c->bootloader, in_boot) << n;
    }
  }
}

TEST(FpsCommands, BroadcastFlagsFollowTheSpec) {
  const std::set<int> broadcast{1, 2, 3, 13, 14, 15, 116, 117, 127};
  for (const auto& c : kCommands) EXPECT_EQ(c.broadcast, broadcast.count(c.number()) != 0) << c.name;
}

TEST(FpsCommands, NamesAndLookups) {
  EXPECT_EQ(command_name(CommandId::go_to_absolute_position), "GO_TO_ABSOLUTE_POSITION");
  EXPECT_EQ(command_name(std::uint8_t{18}), "COLLISION_DETECTED");
  EXPECT_EQ(command_name(std::uint8_t{19}), "UNKNOWN_COMMAND_19");
  ASSERT_NE(find_command("send_trajectory_data"), nullptr);
  EXPECT_EQ(find_command("send_trajectory_data")->id, CommandId::send_trajectory_data);
  EXPECT_EQ(find_command("NO_SUCH_COMMAND"), nullptr);
  EXPECT_EQ(lookup_command(19).error(), ProtocolErrc::unknown_command);
  EXPECT_EQ(lookup_command(201).value()->id, CommandId::firmware_data);
  std::set<std::string_view> names;
  for (const auto& c : kCommands) EXPECT_TRUE(names.insert(c.name).second) << c.name;
}

TEST(FpsCommands, PayloadShapes) {
  const auto& go = command_info(CommandId::go_to_absolute_position);
  EXPECT_EQ(go.request.max_size, 8);
  EXPECT_EQ(go.request.fields[0].type, FieldType::i32);
  EXPECT_EQ(go.request.fields[0].unit, Unit::position);
  EXPECT_EQ(go.reply.fields[1].unit, Unit::time);
  const auto& st = command_info(CommandId::get_status);
  EXPECT_EQ(st.reply_in(Mode::application).max_size, 8);
  EXPECT_EQ(st.reply_in(Mode::bootloader).max_size, 4);
  const auto& fw = command_info(CommandId::firmware_data);
  EXPECT_TRUE(fw.request.accepts(1));
  EXPECT_TRUE(fw.request.accepts(8));
  EXPECT_FALSE(fw.request.accepts(0));
  EXPECT_FALSE(fw.request.accepts(9));
  EXPECT_EQ(command_info(CommandId::get_raw_temperature).reply.max_size, 4);
  EXPECT_EQ(command_info(CommandId::get_cogging_vector_length).reply.max_size, 4);
  EXPECT_TRUE(command_info(CommandId::collision_detected).reply.is_empty());
  EXPECT_FALSE(command_info(CommandId::collision_detected).host_sends);
}

TEST(FpsCommands, HoldingCurrentSetIs112AndGetIs113) {
  const auto& set = command_info(CommandId::set_holding_current);
  const auto& get = command_info(CommandId::get_holding_current);
  EXPECT_EQ(set.number(), 112);
  EXPECT_EQ(get.number(), 113);
  EXPECT_EQ(set.request.max_size, 8);
  EXPECT_TRUE(set.reply.is_empty());
  EXPECT_TRUE(get.request.is_empty());
  EXPECT_EQ(get.reply.max_size, 8);
  // By default an empty 112 is a malformed set.
  EXPECT_EQ(check_device_request(112, Mode::application, false, 0).code, ResponseCode::incorrect_data_length);
  // With the option, an empty 112 reads as a get, an 8-byte one stays a set.
  DeviceOptions heading;
  heading.get_holding_current_on_112 = true;
  auto v = check_device_request(112, Mode::application, false, 0, heading);
  EXPECT_EQ(v.code, ResponseCode::accepted);
  EXPECT_EQ(v.command->id, CommandId::get_holding_current);
  v = check_device_request(112, Mode::application, false, 8, heading);
  EXPECT_EQ(v.code, ResponseCode::accepted);
  EXPECT_EQ(v.command->id, CommandId::set_holding_current);
}

TEST(FpsCommands, DeviceVerdicts) {
  EXPECT_EQ(check_device_request(19, Mode::application, false, 0).code, ResponseCode::unknown_command);
  EXPECT_EQ(check_device_request(19, Mode::application, false, 0).command, nullptr);
  EXPECT_EQ(check_device_request(30, Mode::bootloader, false, 8).code, ResponseCode::invalid_bootloader_command);
  EXPECT_EQ(check_device_request(200, Mode::application, false, 8).code, ResponseCode::invalid_command);
  EXPECT_EQ(check_device_request(18, Mode::application, false, 0).code, ResponseCode::invalid_command);
  EXPECT_EQ(check_device_request(30, Mode::application, true, 8).code, ResponseCode::invalid_broadcast);
  EXPECT_EQ(check_device_request(30, Mode::application, false, 7).code, ResponseCode::incorrect_data_length);
  EXPECT_EQ(check_device_request(30, Mode::application, false, 8).code, ResponseCode::accepted);
  EXPECT_EQ(check_device_request(3, Mode::bootloader, true, 0).code, ResponseCode::accepted);
  EXPECT_EQ(check_device_request(201, Mode::bootloader, false, 3).code, ResponseCode::accepted);
  EXPECT_EQ(check_device_request(201, Mode::bootloader, false, 0).code, ResponseCode::incorrect_data_length);
  EXPECT_EQ(check_device_request(14, Mode::application, false, 1).code, ResponseCode::incorrect_data_length);
}

TEST(FpsCommands, HostChecks) {
  const auto& go = command_info(CommandId::go_to_relative_position);
  EXPECT_TRUE(check_request(go, false, 8));
  EXPECT_EQ(check_request(go, false, 0).error(), ProtocolErrc::wrong_length);
  EXPECT_EQ(check_request(go, true, 8).error(), ProtocolErrc::broadcast_not_allowed);
  EXPECT_EQ(check_request(go, false, 8, Mode::bootloader).error(), ProtocolErrc::wrong_mode);
  EXPECT_TRUE(check_request(go, false, 8, Mode::application));
  EXPECT_EQ(check_request(command_info(CommandId::firmware_data), false, 8, Mode::application).error(),
            ProtocolErrc::wrong_mode);
  EXPECT_TRUE(check_request(command_info(CommandId::get_status), true, 0, Mode::bootloader));
  EXPECT_TRUE(check_reply(go, Mode::application, ResponseCode::accepted, 8));
  EXPECT_EQ(check_reply(go, Mode::application, ResponseCode::accepted, 0).error(), ProtocolErrc::wrong_length);
  EXPECT_TRUE(check_reply(go, Mode::application, ResponseCode::value_out_of_range, 0));
  EXPECT_EQ(check_reply(go, Mode::application, ResponseCode::value_out_of_range, 3).error(), ProtocolErrc::wrong_length);
  const auto& st = command_info(CommandId::get_status);
  EXPECT_TRUE(check_reply(st, Mode::bootloader, ResponseCode::accepted, 4));
  EXPECT_EQ(check_reply(st, Mode::application, ResponseCode::accepted, 4).error(), ProtocolErrc::wrong_length);
}

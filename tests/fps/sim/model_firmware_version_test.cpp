// What the simulated firmware answers depends on its version where the interface document or the
// field notes tie a behaviour to one: one test per command family.
#include "axon/core/config.hpp"
#include "axon/fps/protocol/firmware_image.hpp"
#include "axon/fps/sim/firmware_marker.hpp"
#include "harness.hpp"

namespace axon::fps::sim::testing {
namespace {

PositionerConfig running(protocol::FirmwareVersion v, FirmwareHistory history = FirmwareHistory::document) {
  auto c = test_config();
  c.firmware = v;
  c.firmware_history = history;
  return c;
}

constexpr CommandId kPreciseMoveSwitches[] = {
    CommandId::switch_on_precise_move_alpha, CommandId::switch_off_precise_move_alpha,
    CommandId::switch_on_precise_move_beta, CommandId::switch_off_precise_move_beta};

TEST(FpsSimFirmwareVersion, StatusIsTheSixtyFourBitWordInEveryModelledVersion) {
  for (const auto v : {protocol::FirmwareVersion{4, 1, 0}, protocol::FirmwareVersion{4, 1, 13},
                       protocol::FirmwareVersion{4, 1, 21}}) {
    Harness h(running(v));
    const auto m = h.ask(CommandId::get_status);
    EXPECT_EQ(m.payload.size(), 8u) << v.to_string();
    const auto version = protocol::FirmwareVersion::decode(h.ask(CommandId::get_firmware_version).payload.span());
    EXPECT_EQ(version.value(), v);
  }
}

TEST(FpsSimFirmwareVersion, VersionsBeforeTheSixtyFourBitStatusAreRefusedNotAnsweredWrongly) {
  const auto r = running({4, 0, 99}).validate();
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message().find("not modelled"), std::string::npos) << r.error().message();
  EXPECT_TRUE(running({4, 1, 0}).validate());
}

TEST(FpsSimFirmwareVersion, DocumentHistoryTakesThePreciseMoveSwitchesInEveryVersion) {
  Harness h(running({4, 1, 13}));  // the version whose table 6 lists them
  for (auto c : kPreciseMoveSwitches) EXPECT_EQ(h.code(c), ResponseCode::accepted) << protocol::command_name(c);
}

TEST(FpsSimFirmwareVersion, FieldHistoryAnswersPreciseMoveSwitchesBefore040117AsUnknown) {
  Harness old(running({4, 1, 16}, FirmwareHistory::field));
  for (auto c : kPreciseMoveSwitches) {
    EXPECT_EQ(old.code(c), ResponseCode::unknown_command) << protocol::command_name(c);
  }
  EXPECT_TRUE(old.status().has(StatusBit::precise_move_alpha));  // the refused switch changed nothing
  Harness current(running({4, 1, 17}, FirmwareHistory::field));
  for (auto c : kPreciseMoveSwitches) EXPECT_EQ(current.code(c), ResponseCode::accepted) << protocol::command_name(c);
}

TEST(FpsSimFirmwareVersion, UnknownCommandsAreCode13InEveryVersionAndHistory) {
  for (const auto history : {FirmwareHistory::document, FirmwareHistory::field}) {
    Harness h(running({4, 1, 21}, history));
    for (std::uint8_t n : {4, 16, 60, 133, 199, 250}) {
      const auto out = h.raw(n);
      ASSERT_EQ(out.size(), 1u);
      EXPECT_EQ(out[0].id.response, ResponseCode::unknown_command) << int{n};
    }
  }
}

TEST(FpsSimFirmwareVersion, AnUpgradedImageBringsItsVersionsCommands) {
  // The running version decides, not the one configured at power-up: field history, 04.01.16, then
  // the image of 04.01.17 (the tag the simulated bootloader reads) is running after the upgrade.
  Harness h(running({4, 1, 16}, FirmwareHistory::field));
  EXPECT_EQ(h.code(CommandId::switch_off_precise_move_beta), ResponseCode::unknown_command);
  h.model.power_cycle(h.now, /*sync_line_low=*/true);
  const auto image = make_firmware_image({4, 1, 17}, 64).value();
  ASSERT_EQ(h.code(CommandId::start_firmware_upgrade,
                   two_u32(static_cast<std::uint32_t>(image.size()), protocol::firmware_crc32(image))),
            ResponseCode::accepted);
  for (std::size_t at = 0; at < image.size(); at += 8) {
    Payload chunk;
    for (std::size_t i = at; i < at + 8 && i < image.size(); ++i) chunk.put_u8(image[i]);
    ASSERT_EQ(h.code(CommandId::firmware_data, chunk), ResponseCode::accepted);
  }
  h.model.power_cycle(h.now, /*sync_line_low=*/false);
  h.wait(1s);
  EXPECT_EQ(h.model.running_version(), (protocol::FirmwareVersion{4, 1, 17}));
  EXPECT_EQ(h.code(CommandId::switch_off_precise_move_beta), ResponseCode::accepted);
}

TEST(FpsSimFirmwareVersion, HistoryAndEmptyStartAreConfigurationKeys) {
  const auto node = core::ConfigNode::load_string("{firmware_history: field, start_without_trajectory: refuse}").value();
  const auto c = PositionerConfig::from_config(node).value();
  EXPECT_EQ(c.firmware_history, FirmwareHistory::field);
  EXPECT_EQ(c.start_without_trajectory, EmptyStart::refuse);
  const auto bad = core::ConfigNode::load_string("{firmware_history: newest}").value();
  const auto r = PositionerConfig::from_config(bad);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message().find("document or field"), std::string::npos) << r.error().message();
}

}  // namespace
}  // namespace axon::fps::sim::testing

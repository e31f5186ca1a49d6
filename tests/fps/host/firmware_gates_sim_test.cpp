// Firmware versions between host and simulator: the version gates (protocol/firmware_gates.hpp)
// decide before sending when the robot's version lacks a command, and GET_FIRMWARE_VERSION's byte
// order is an option on both sides.
#include "sim_rig.hpp"

#include "axon/fps/host/error.hpp"

#include <gtest/gtest.h>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::host;
using namespace axon::fps::host::testing;
using protocol::FirmwareHistory;
using protocol::StatusBit;

namespace {

ArrayOptions array_with(FirmwareHistory history, protocol::VersionByteOrder order = protocol::VersionByteOrder::field) {
  ArrayOptions o = fast_array();
  o.positioner.firmware_history = history;
  o.positioner.version_byte_order = order;
  return o;
}

// What robots 7 (04.01.16) and 8 (04.01.17), both with the field's command history, answered to a
// host following `history` that switched their precise moves off, and whether they still have it on.
struct SwitchOff {
  Result<void> old_robot = ok(), new_robot = ok();
  bool old_still_on = false, new_still_on = false;
};

SwitchOff switch_precise_off(FirmwareHistory history) {
  SimRig rig(1, fast_sim(), array_with(history));
  for (const auto& robot : {std::pair<std::uint16_t, protocol::FirmwareVersion>{7, {4, 1, 16}}, {8, {4, 1, 17}}}) {
    const auto version = robot.second;  // (clang 14 cannot capture a structured binding)
    rig.add(robot.first, 0, [version](sim::PositionerConfig& c) {
      c.firmware = version;
      c.firmware_history = FirmwareHistory::field;
    });
  }
  rig.start();
  SwitchOff out;
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    out.old_robot = co_await rig.array->find(7)->set_precise_move(Arm::both, false);
    out.new_robot = co_await rig.array->find(8)->set_precise_move(Arm::both, false);
  });
  out.old_still_on = rig.model(7).status().has(StatusBit::precise_move_alpha);
  out.new_still_on = rig.model(8).status().has(StatusBit::precise_move_alpha);
  return out;
}

TEST(FirmwareGatesSim, AHostThatKnowsTheHistoryRefusesAGatedCommandBeforeSendingIt) {
  const auto r = switch_precise_off(FirmwareHistory::field);
  ASSERT_FALSE(r.old_robot.has_value());
  EXPECT_EQ(r.old_robot.error().code, HostErrc::firmware_lacks) << r.old_robot.error().message();
  EXPECT_NE(r.old_robot.error().detail.find("positioner 7: firmware 04.01.16 lacks SWITCH_OFF_PRECISE_MOVE_ALPHA (129)"),
            std::string::npos)
      << r.old_robot.error().detail;
  EXPECT_TRUE(r.old_still_on);  // untouched
  // The newer robot has the switches.
  EXPECT_TRUE(r.new_robot.has_value()) << r.new_robot.error().message();
  EXPECT_FALSE(r.new_still_on);
}

TEST(FirmwareGatesSim, AHostThatFollowsTheDocumentSendsItAndTheOldRobotAnswersUnknown) {
  const auto r = switch_precise_off(FirmwareHistory::document);
  ASSERT_FALSE(r.old_robot.has_value());
  EXPECT_NE(r.old_robot.error().code, HostErrc::firmware_lacks) << r.old_robot.error().message();
  EXPECT_NE(r.old_robot.error().message().find("UNKNOWN_COMMAND"), std::string::npos) << r.old_robot.error().message();
  EXPECT_TRUE(r.old_still_on);
  EXPECT_TRUE(r.new_robot.has_value()) << r.new_robot.error().message();
}

// Discovery's row of robot 7, which sends its version in the document's byte order, as a host
// reading `host_order` sees it.
StatusRow discovered_document_order_robot(protocol::VersionByteOrder host_order) {
  SimRig rig(1, fast_sim(), array_with(FirmwareHistory::document, host_order));
  rig.add(7, 0, [](sim::PositionerConfig& c) { c.version_byte_order = protocol::VersionByteOrder::document; });
  rig.start();
  StatusRow row;
  rig.run([&]() -> asio::awaitable<void> {
    const auto d = co_await rig.discover();
    if (d.table.rows.size() == 1) row = d.table.rows[0];
  });
  return row;
}

TEST(FirmwareGatesSim, TheDocumentsByteOrderIsReadWhenBothSidesUseIt) {
  const auto row = discovered_document_order_robot(protocol::VersionByteOrder::document);
  EXPECT_EQ(row.firmware, (protocol::FirmwareVersion{4, 1, 13})) << row.error;
  EXPECT_TRUE(row.error.empty()) << row.error;
}

TEST(FirmwareGatesSim, AByteOrderMismatchIsAnErrorNamingTheOption) {
  const auto row = discovered_document_order_robot(protocol::VersionByteOrder::field);
  EXPECT_EQ(row.id, 7);
  EXPECT_FALSE(row.firmware.has_value());
  EXPECT_NE(row.error.find("byte order"), std::string::npos) << row.error;
}

}  // namespace

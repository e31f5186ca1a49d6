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

// Robot 7 runs 04.01.16, robot 8 04.01.17, both with the field's command history.
void add_old_and_new(SimRig& rig) {
  for (const auto& [id, version] : {std::pair<std::uint16_t, protocol::FirmwareVersion>{7, {4, 1, 16}}, {8, {4, 1, 17}}}) {
    rig.add(id, 0, [version](sim::PositionerConfig& c) {
      c.firmware = version;
      c.firmware_history = FirmwareHistory::field;
    });
  }
}

TEST(FirmwareGatesSim, AHostThatKnowsTheHistoryRefusesAGatedCommandBeforeSendingIt) {
  SimRig rig(1, fast_sim(), array_with(FirmwareHistory::field));
  add_old_and_new(rig);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    auto r = co_await rig.array->find(7)->set_precise_move(Arm::both, false);
    EXPECT_FALSE(r.has_value());
    if (r) co_return;
    EXPECT_EQ(r.error().code, HostErrc::firmware_lacks) << r.error().message();
    EXPECT_NE(r.error().detail.find("positioner 7: firmware 04.01.16 lacks SWITCH_OFF_PRECISE_MOVE_ALPHA (129)"),
              std::string::npos)
        << r.error().detail;
    EXPECT_TRUE(rig.model(7).status().has(StatusBit::precise_move_alpha));  // untouched
    // The newer robot has the switches.
    r = co_await rig.array->find(8)->set_precise_move(Arm::both, false);
    EXPECT_TRUE(r.has_value()) << r.error().message();
    EXPECT_FALSE(rig.model(8).status().has(StatusBit::precise_move_alpha));
  });
}

TEST(FirmwareGatesSim, AHostThatFollowsTheDocumentSendsItAndTheOldRobotAnswersUnknown) {
  SimRig rig(1, fast_sim(), array_with(FirmwareHistory::document));
  add_old_and_new(rig);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    auto r = co_await rig.array->find(7)->set_precise_move(Arm::alpha, false);
    EXPECT_FALSE(r.has_value());
    if (r) co_return;
    EXPECT_NE(r.error().code, HostErrc::firmware_lacks) << r.error().message();
    EXPECT_TRUE(rig.model(7).status().has(StatusBit::precise_move_alpha));
  });
}

TEST(FirmwareGatesSim, TheDocumentsByteOrderIsReadWhenBothSidesUseIt) {
  SimRig rig(1, fast_sim(), array_with(FirmwareHistory::document, protocol::VersionByteOrder::document));
  rig.add(7, 0, [](sim::PositionerConfig& c) { c.version_byte_order = protocol::VersionByteOrder::document; });
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    const auto d = co_await rig.discover();
    EXPECT_EQ(d.table.rows.size(), 1u);
    if (d.table.rows.size() != 1) co_return;
    EXPECT_EQ(d.table.rows[0].firmware, (protocol::FirmwareVersion{4, 1, 13})) << d.table.rows[0].error;
    EXPECT_TRUE(d.table.rows[0].error.empty()) << d.table.rows[0].error;
  });
}

TEST(FirmwareGatesSim, AByteOrderMismatchIsAnErrorNamingTheOption) {
  SimRig rig;  // the host reads the field's order
  rig.add(7, 0, [](sim::PositionerConfig& c) { c.version_byte_order = protocol::VersionByteOrder::document; });
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    const auto d = co_await rig.discover();
    EXPECT_EQ(d.table.rows.size(), 1u);
    if (d.table.rows.size() != 1) co_return;
    EXPECT_FALSE(d.table.rows[0].firmware.has_value());
    EXPECT_NE(d.table.rows[0].error.find("byte order"), std::string::npos) << d.table.rows[0].error;
  });
}

}  // namespace

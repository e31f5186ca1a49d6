// Firmware upgrade against the simulator: a good image on robots of two buses, robots not in the
// bootloader, an image corrupted on the way (the robot's CRC check fails), a transfer interrupted
// by a lost frame (half-written, said so), an image too large for the robot.
#include "sim_rig.hpp"

#include "axon/fps/protocol/firmware_image.hpp"
#include "axon/fps/sim/firmware_marker.hpp"

#include <gtest/gtest.h>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::host;
using namespace axon::fps::host::testing;

namespace {

void in_bootloader(sim::PositionerConfig& c) { c.sync_line_low_at_power_on = true; }

// Matches the FIRMWARE_DATA frames of one robot (requests and replies share the identifier).
can::Filter firmware_data_of(std::uint16_t id) {
  return can::Filter{(std::uint32_t{id} << 18) | (201u << 10), 0x1FFFFC00u, can::Filter::Format::extended};
}

}  // namespace

TEST(FirmwareUpgradeSim, AGoodImageReachesEveryRobotInTheBootloaderAndIsVerified) {
  SimRig rig(2);
  rig.add(40, 0, in_bootloader);
  rig.add(41, 0, in_bootloader);
  rig.add(42, 1, in_bootloader);
  rig.add(3, 1);  // runs its application
  rig.start();
  const auto image = sim::make_firmware_image({4, 2, 0}, 3001).value();
  std::map<std::uint16_t, UpgradeProgress> last;
  std::size_t calls = 0;
  UpgradeReport report;
  const std::vector<std::uint16_t> ids0{40, 41, 42, 3, 99};  // outside the coroutine (gcc 12)
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    UpgradeOptions o;
    o.progress_every = 100;
    o.progress = [&](const UpgradeProgress& p) {
      ++calls;
      last[p.positioner] = p;
    };
    auto r = co_await rig.array->upgrade_firmware(ids0, image, o);
    EXPECT_TRUE(r.has_value());
    if (r) report = r.value();
  });
  EXPECT_EQ(report.size, 3001u);
  EXPECT_EQ(report.crc32, protocol::firmware_crc32(image));
  EXPECT_EQ(report.with(UpgradeOutcome::ok), (std::vector<std::uint16_t>{40, 41, 42}));
  EXPECT_EQ(report.with(UpgradeOutcome::not_attempted), (std::vector<std::uint16_t>{3, 99}));
  EXPECT_FALSE(report.ok());
  ASSERT_NE(report.find(3), nullptr);
  EXPECT_NE(report.find(3)->reason.find("not the bootloader"), std::string::npos) << report.find(3)->reason;
  ASSERT_NE(report.find(40), nullptr);
  EXPECT_EQ(report.find(40)->chunks_acked, 376u);  // 3001 bytes in 8-byte chunks
  EXPECT_EQ(report.find(40)->chunks_total, 376u);
  EXPECT_FALSE(report.find(40)->half_written);
  ASSERT_TRUE(report.find(40)->final_status.has_value());
  EXPECT_TRUE(report.find(40)->final_status->upgrade_succeeded());
  EXPECT_EQ(rig.model(40).flash().main.version, (protocol::FirmwareVersion{4, 2, 0}));
  EXPECT_EQ(rig.model(42).flash().main.version, (protocol::FirmwareVersion{4, 2, 0}));
  EXPECT_EQ(rig.model(3).flash().main.version, (protocol::FirmwareVersion{4, 1, 13}));
  // Progress: every 100 chunks and at the end, for each robot.
  EXPECT_EQ(last[41].chunks_acked, 376u);
  EXPECT_EQ(last[41].chunks_total, 376u);
  EXPECT_EQ(calls, 3u * 4u);  // 100, 200, 300, 376
  // The window kept every robot's 16-frame receive buffer from overflowing.
  EXPECT_EQ(rig.simulator.receive_overflows(), 0u);
  EXPECT_NE(report.summary().find("3 ok"), std::string::npos) << report.summary();
}

TEST(FirmwareUpgradeSim, AnImageCorruptedOnTheWayFailsTheRobotsCrcCheck) {
  SimRig rig(1);
  rig.add(40, 0, in_bootloader);
  rig.add(41, 0, in_bootloader);
  rig.start();
  can::FaultPlan plan;
  can::FaultRule corrupt;
  corrupt.action = can::FaultRule::Action::corrupt;  // only frames with data: the host's chunks
  corrupt.match = firmware_data_of(40);
  corrupt.skip = 10;
  corrupt.count = 1;
  corrupt.corrupt_xor = 0x01;
  plan.rules.push_back(corrupt);
  rig.media[0]->set_fault_plan(plan);
  const auto image = sim::make_firmware_image({4, 2, 0}, 800).value();
  UpgradeReport report;
  const std::vector<std::uint16_t> ids0{40, 41};  // outside the coroutine (gcc 12)
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    auto r = co_await rig.array->upgrade_firmware(ids0, image);
    EXPECT_TRUE(r.has_value());
    if (r) report = r.value();
  });
  ASSERT_NE(report.find(40), nullptr);
  EXPECT_EQ(report.find(40)->outcome, UpgradeOutcome::failed);
  EXPECT_NE(report.find(40)->reason.find("CRC"), std::string::npos) << report.find(40)->reason;
  EXPECT_FALSE(report.find(40)->half_written);
  ASSERT_TRUE(report.find(40)->final_status.has_value());
  EXPECT_TRUE(report.find(40)->final_status->upgrade_failed());
  EXPECT_EQ(report.find(41)->outcome, UpgradeOutcome::ok);
  EXPECT_EQ(rig.model(40).counters().firmware_rejected, 1u);
  EXPECT_EQ(rig.model(40).flash().main.version, (protocol::FirmwareVersion{4, 1, 13}));
}

TEST(FirmwareUpgradeSim, AnInterruptedTransferIsReportedHalfWritten) {
  ArrayOptions ao = fast_array();
  ao.client.timeout = 200ms;
  SimRig rig(1, fast_sim(), ao);
  rig.add(40, 0, in_bootloader);
  rig.add(41, 0, in_bootloader);
  rig.start();
  const auto image = sim::make_firmware_image({4, 2, 0}, 2000).value();
  const std::vector<std::uint16_t> ids{40, 41};
  UpgradeReport report;
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    UpgradeOptions o;
    o.progress_every = 1;
    // Robot 40 loses its power a quarter of the way through.
    o.progress = [&](const UpgradeProgress& p) {
      if (p.positioner == 40 && p.chunks_acked == 60) rig.model(40).power_off(rig.simulator.now());
    };
    auto r = co_await rig.array->upgrade_firmware(ids, image, o);
    EXPECT_TRUE(r.has_value());
    if (r) report = r.value();
  });
  ASSERT_NE(report.find(40), nullptr);
  const auto& r40 = *report.find(40);
  EXPECT_EQ(r40.outcome, UpgradeOutcome::failed);
  EXPECT_TRUE(r40.half_written);
  EXPECT_GE(r40.chunks_acked, 60u);
  EXPECT_LT(r40.chunks_acked, r40.chunks_total);
  EXPECT_NE(r40.reason.find("transfer stopped"), std::string::npos) << r40.reason;
  EXPECT_NE(report.summary().find("HALF-WRITTEN"), std::string::npos);
  EXPECT_EQ(report.find(41)->outcome, UpgradeOutcome::ok);
  EXPECT_EQ(rig.model(40).flash().main.version, (protocol::FirmwareVersion{4, 1, 13}));
}

// One of robot 40's FIRMWARE_DATA acknowledgements is lost. The host stops issuing chunks, lets
// the ones in flight finish, then asks the robot what it has.
static UpgradeRobotReport upgrade_losing_reply(std::uint64_t lost) {
  ArrayOptions ao = fast_array();
  ao.client.timeout = 200ms;
  auto so = fast_sim();
  can::FaultRule drop;
  drop.action = can::FaultRule::Action::drop;
  drop.match = firmware_data_of(40);
  drop.skip = lost;
  drop.count = 1;
  so.reply_faults.rules.push_back(drop);
  SimRig rig(1, so, ao);
  rig.add(40, 0, in_bootloader);
  rig.start();
  const auto image = sim::make_firmware_image({4, 2, 0}, 2000).value();  // 250 chunks
  const std::vector<std::uint16_t> ids{40};
  UpgradeReport report;
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    auto r = co_await rig.array->upgrade_firmware(ids, image);
    EXPECT_TRUE(r.has_value());
    if (r) report = r.value();
  });
  const protocol::FirmwareVersion expected = lost >= 245 ? protocol::FirmwareVersion{4, 2, 0}
                                                         : protocol::FirmwareVersion{4, 1, 13};
  EXPECT_EQ(rig.model(40).flash().main.version, expected);
  return report.find(40) ? *report.find(40) : UpgradeRobotReport{};
}

TEST(FirmwareUpgradeSim, AReplyLostEarlyLeavesTheRobotHalfWrittenAndSaysSo) {
  const auto r = upgrade_losing_reply(30);
  EXPECT_EQ(r.outcome, UpgradeOutcome::failed);
  EXPECT_TRUE(r.half_written);
  EXPECT_EQ(r.chunks_acked, 30u);
  ASSERT_TRUE(r.final_status.has_value());
  EXPECT_TRUE(r.final_status->receiving());  // what the robot itself says
}

TEST(FirmwareUpgradeSim, AReplyLostInTheLastWindowIsSettledByTheRobotsOwnCheck) {
  // The chunks in flight behind the lost acknowledgement completed the image.
  const auto r = upgrade_losing_reply(246);
  EXPECT_EQ(r.outcome, UpgradeOutcome::ok) << r.reason;
  EXPECT_FALSE(r.half_written);
  EXPECT_NE(r.reason.find("replies were lost"), std::string::npos) << r.reason;
  ASSERT_TRUE(r.final_status.has_value());
  EXPECT_TRUE(r.final_status->upgrade_succeeded());
}

TEST(FirmwareUpgradeSim, AnImageTooLargeIsRefusedAtTheStart) {
  SimRig rig(1);
  rig.add(40, 0, [](sim::PositionerConfig& c) {
    c.sync_line_low_at_power_on = true;
    c.max_firmware_size = 1000;
  });
  rig.start();
  const auto image = sim::make_firmware_image({4, 2, 0}, 1001).value();
  UpgradeReport report;
  const std::vector<std::uint16_t> ids0{40};  // outside the coroutine (gcc 12)
  const std::vector<std::uint16_t> ids1{40};  // outside the coroutine (gcc 12)
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    auto r = co_await rig.array->upgrade_firmware(ids0, image);
    EXPECT_TRUE(r.has_value());
    if (r) report = r.value();
    auto empty = co_await rig.array->upgrade_firmware(ids1, {});
    EXPECT_FALSE(empty.has_value());
  });
  ASSERT_NE(report.find(40), nullptr);
  EXPECT_EQ(report.find(40)->outcome, UpgradeOutcome::failed);
  EXPECT_FALSE(report.find(40)->half_written);
  EXPECT_EQ(report.find(40)->chunks_acked, 0u);
  EXPECT_NE(report.find(40)->reason.find("VALUE_OUT_OF_RANGE"), std::string::npos) << report.find(40)->reason;
}

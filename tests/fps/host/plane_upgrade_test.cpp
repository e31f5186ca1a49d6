// Firmware upgrade of the whole plane, sextant by sextant through the PLC, against the simulated
// plane over real TCP (2 gateway emulators, PLC emulator): robots power-cycled into the
// bootloader, upgraded, retried, powered back into the application and their version checked.
#include "plane_rig.hpp"

#include "axon/fps/host/plane_upgrade.hpp"
#include "axon/fps/sim/firmware_marker.hpp"

#include <gtest/gtest.h>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::host;
using namespace axon::fps::host::testing;
using protocol::CommandId;
using protocol::FirmwareVersion;

namespace {

PlaneUpgradeOptions quick(std::optional<FirmwareVersion> expected) {
  PlaneUpgradeOptions o;
  o.expected_version = expected;
  o.power_off_time = 50ms;
  o.bootloader_wait = 3s;
  o.boot_wait = 3s;
  o.poll = 20ms;
  return o;
}

}  // namespace

TEST(PlaneUpgrade, EverySextantUpgradedRetriedOnceAndVerified) {
  auto so = plane_sim_options();
  // Robot 3 (sextant 1) does not acknowledge its first START_FIRMWARE_UPGRADE; robot 9 (sextant 2)
  // loses every data reply after the tenth, so both of its attempts stop part-way.
  so.simulator.reply_faults.rules.push_back(drop_rule(replies_of(3, CommandId::start_firmware_upgrade), 0, 1));
  so.simulator.reply_faults.rules.push_back(drop_rule(replies_of(9, CommandId::firmware_data), 10));
  PlaneRig rig(so);
  const FirmwareVersion next{4, 2, 0};
  const auto image = sim::make_firmware_image(next, 3000).value();
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    std::vector<SextantProgress> lines;
    auto o = quick(next);
    o.progress = [&](const SextantProgress& p) {
      if (p.finished) lines.push_back(p);
    };
    auto r = co_await upgrade_plane(*rig.fpa, image, o);
    EXPECT_TRUE(r.has_value());
    if (!r) co_return;
    const auto& rep = r.value();
    const std::string text = rep.summary();
    EXPECT_FALSE(rep.ok()) << text;
    EXPECT_EQ(rep.robots.size(), 12u);
    EXPECT_EQ(rep.with(PlaneRobotOutcome::failed), (std::vector<std::uint16_t>{9})) << text;
    for (const auto& rr : rep.robots) {
      if (rr.id == 9) continue;
      EXPECT_EQ(rr.outcome, PlaneRobotOutcome::ok) << rr.id << " " << rr.reason;
      EXPECT_EQ(rr.attempts, rr.id == 3 ? 2u : 1u) << rr.id;
      EXPECT_EQ(rr.after, std::optional<FirmwareVersion>(next)) << rr.id;
      EXPECT_EQ(rr.before, (FirmwareVersion{4, 1, 13})) << rr.id;
    }
    const auto* r3 = rep.find(3);
    EXPECT_NE(r3->reason.find("attempt 2"), std::string::npos) << r3->reason;
    const auto* r9 = rep.find(9);
    EXPECT_EQ(r9->attempts, 2u);
    EXPECT_TRUE(r9->half_written) << r9->reason;
    EXPECT_NE(r9->reason.find("failed after 2 attempts"), std::string::npos) << r9->reason;
    EXPECT_EQ(r9->after, std::optional<FirmwareVersion>(FirmwareVersion{4, 1, 13}));  // its previous firmware
    EXPECT_NE(text.find("HALF-WRITTEN"), std::string::npos) << text;

    // The simulated robots agree: all in their application, the new image in all but robot 9.
    for (auto* m : rig.sim->simulator().robots()) {
      EXPECT_EQ(m->run_state(), sim::RunState::application) << m->id();
      const FirmwareVersion want = m->id() == 9 ? FirmwareVersion{4, 1, 13} : next;
      EXPECT_EQ(m->running_version(), want) << m->id();
    }
    // Sextant by sextant, each powered back on, the sync line left low.
    EXPECT_EQ(lines.size(), 2u);
    if (lines.size() != 2) co_return;
    EXPECT_EQ(lines[0].sextant, 1);
    EXPECT_EQ(lines[0].done, 6u);
    EXPECT_EQ(lines[1].sextant, 2);
    EXPECT_EQ(lines[1].done, 5u);
    EXPECT_EQ(lines[1].failed, 1u);
    EXPECT_GE(lines[0].bytes, 6u * 3000u);
    auto* plc = rig.sim->plc();
    EXPECT_TRUE(plc->relay({plc::RelayKind::positioner_power, 1}));
    EXPECT_TRUE(plc->relay({plc::RelayKind::positioner_power, 2}));
    EXPECT_FALSE(plc->relay({plc::RelayKind::sync_line, 0}));
    // (the emulator's relay hooks reach the simulator through its executor)
    EXPECT_TRUE(co_await eventually([&] { return !rig.sim->sync_line(); }));
  });
}

TEST(PlaneUpgrade, ARobotThatNeverReachesTheBootloaderIsNotAttempted) {
  auto so = plane_sim_options();
  // Robot 2 never answers GET_FIRMWARE_VERSION: the host cannot see it in the bootloader.
  so.simulator.reply_faults.rules.push_back(drop_rule(replies_of(2, CommandId::get_firmware_version)));
  PlaneRig rig(so);
  const auto image = sim::make_firmware_image({4, 2, 0}, 800).value();
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    auto o = quick(FirmwareVersion{4, 2, 0});
    o.sextants = {1};
    o.bootloader_wait = 500ms;
    auto r = co_await upgrade_plane(*rig.fpa, image, o);
    EXPECT_TRUE(r.has_value());
    if (!r) co_return;
    const auto& rep = r.value();
    EXPECT_EQ(rep.robots.size(), 6u);  // sextant 1 only
    EXPECT_EQ(rep.with(PlaneRobotOutcome::not_attempted), (std::vector<std::uint16_t>{2})) << rep.summary();
    EXPECT_NE(rep.find(2)->reason.find("bootloader"), std::string::npos) << rep.find(2)->reason;
    EXPECT_EQ(rep.find(2)->attempts, 0u);
    EXPECT_EQ(rig.sim->simulator().find(2)->running_version(), (FirmwareVersion{4, 1, 13}));
    EXPECT_EQ(rig.sim->simulator().find(8)->running_version(), (FirmwareVersion{4, 1, 13}));  // sextant 2 untouched
    EXPECT_EQ(rig.sim->simulator().find(1)->running_version(), (FirmwareVersion{4, 2, 0}));
  });
}

TEST(PlaneUpgrade, RefusedWithoutAPlcOrForAnEmptySextant) {
  PlaneRig rig;
  const auto image = sim::make_firmware_image({4, 2, 0}, 100).value();
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    auto o = quick(std::nullopt);
    o.sextants = {4};
    auto r = co_await upgrade_plane(*rig.fpa, image, o);
    EXPECT_FALSE(r.has_value());
    EXPECT_EQ(rig.sim->counters().sextant_power_changes, 0u);
  });
}

// fps::Client::upgrade_firmware against an in-process simulated plane with its PLC emulator, over
// real TCP on loopback: the sextant power-cycled into the bootloader through the PLC, every robot
// sent the image, powered back, its version read; progress reported; no PLC: refused.
#include "axon/fps/host/client.hpp"
#include "axon/fps/host/error.hpp"
#include "axon/fps/sim/firmware_marker.hpp"
#include "axon/fps/sim/simulated_plane.hpp"

#include <gtest/gtest.h>

namespace axon::fps::client_upgrade_test {
namespace {

sim::SimulatedPlaneOptions with_plc(bool plc) {
  sim::SimulatedPlaneOptions so;
  so.time_scale = 20;
  so.plc = plc;
  return so;
}

// A simulated benchtop plane (with or without its PLC) and a client open on it, robots discovered.
struct Rig {
  explicit Rig(bool plc) : plane("benchtop", with_plc(plc)), fps(quick(plc ? plane.plc_address() : "")) {
    fps.open(plane.plane());
    fps.discover();
  }
  static ClientConfig quick(const std::string& plc);
  sim::SimulatedPlane plane;
  Client fps;
};

ClientConfig Rig::quick(const std::string& plc) {
  ClientConfig c;
  c.poll_interval_s = 0.02;
  c.discover_window_s = 0.3;
  c.call_timeout_s = 120;
  c.plc_address = plc;
  return c;
}

TEST(ClientUpgrade, EveryRobotRunsTheNewImageAndProgressIsReported) {
  Rig rig(true);
  auto& fps = rig.fps;
  ASSERT_EQ(fps.robots().size(), 6u);
  const auto image = sim::make_firmware_image({4, 2, 0}, 3000).value();
  std::vector<SextantUpgrade> seen;
  UpgradeSettings s;
  s.expected_version = "04.02.00";
  s.power_off_s = 0.05;
  const auto out = fps.upgrade_firmware(image, s, [&seen](const SextantUpgrade& p) { seen.push_back(p); });
  EXPECT_TRUE(out.ok) << out.summary;
  ASSERT_EQ(out.robots.size(), 6u) << out.summary;
  for (const auto& r : out.robots) {
    EXPECT_EQ(r.outcome, "ok") << r.id << ": " << r.reason;
    EXPECT_EQ(r.before, "04.01.13") << r.id;
    EXPECT_EQ(r.after, "04.02.00") << r.id;
    EXPECT_EQ(r.attempts, 1u) << r.id;
  }
  ASSERT_FALSE(seen.empty());
  EXPECT_TRUE(seen.back().finished);
  EXPECT_EQ(seen.back().done, 6u);
  EXPECT_EQ(seen.back().bytes, 6u * 3000u);
  EXPECT_NE(seen.back().text.find("6/6 robots"), std::string::npos) << seen.back().text;
  // The robots answer from the new application afterwards.
  for (const auto& r : fps.status()) EXPECT_EQ(r.firmware, "04.02.00") << r.id;
}

TEST(ClientUpgrade, WithoutAPlcNothingIsSwitchedAndTheCallSaysWhy) {
  Rig rig(false);
  auto& fps = rig.fps;
  const auto image = sim::make_firmware_image({4, 2, 0}, 3000).value();
  try {
    fps.upgrade_firmware(image);
    FAIL() << "an upgrade ran without a PLC";
  } catch (const Exception& e) {
    EXPECT_EQ(e.code(), host::HostErrc::invalid_argument) << e.what();
  }
  UpgradeSettings bad;
  bad.expected_version = "four";
  EXPECT_THROW(fps.upgrade_firmware(image, bad), Exception);
  for (const auto& r : fps.status()) EXPECT_EQ(r.firmware, "04.01.13") << r.id;
}

// The layout check and the cold policy of a plane with its PLC, from blocking calls.
TEST(ClientPlc, TheLayoutCheckFindsEveryRobotAndTheColdPolicyReachesEveryRobot) {
  Rig rig(true);
  auto& fps = rig.fps;
  const auto check = fps.check_layout();
  EXPECT_TRUE(check.ok()) << check.to_text();
  EXPECT_EQ(check.matched.size(), 6u) << check.to_text();
  const auto cold = fps.apply_cold_policy();
  EXPECT_EQ(cold.applied.size(), 6u) << cold.text;
  EXPECT_TRUE(cold.failed.empty()) << cold.text;
  EXPECT_TRUE(cold.coldest_c.has_value()) << cold.text;
  EXPECT_GT(cold.motor_rpm, 0u);
  EXPECT_FALSE(cold.text.empty());
}

TEST(ClientPlc, TheColdPolicyWithoutAPlcIsRefused) {
  Rig rig(false);
  try {
    rig.fps.apply_cold_policy();
    FAIL() << "a cold policy ran without a PLC";
  } catch (const Exception& e) {
    EXPECT_EQ(e.code(), host::HostErrc::invalid_argument) << e.what();
  }
}

// A start by the sync line (a PLC pulse instead of the START_TRAJECTORY broadcast), from the
// blocking calls: trajectories and a plan-and-move, each one rising edge, every robot at its end.
TEST(ClientPlc, TrajectoriesAndPlanAndMoveStartByTheSyncLine) {
  Rig rig(true);
  auto& fps = rig.fps;
  std::map<std::uint16_t, ArmPath> paths;
  for (const auto id : fps.robots()) paths[id] = {{{20.0, 1.0}}, {{170.0, 1.0}}};
  const auto moved = fps.run_trajectories(paths, true);
  EXPECT_TRUE(moved.completed) << moved.summary;
  EXPECT_EQ(rig.plane.sync_edges(), 1u);
  for (const auto id : fps.robots()) {
    const auto a = rig.plane.arms(id);
    ASSERT_TRUE(a.has_value());
    EXPECT_NEAR(a->alpha, 20.0, 0.1) << id;
  }
  std::map<std::uint16_t, Angles> targets;
  for (const auto id : fps.robots()) targets[id] = {40.0, 150.0};
  PlanSettings s;
  s.start_by_sync_line = true;
  const auto done = fps.plan_and_move(targets, s);
  EXPECT_TRUE(done.move.completed) << done.move.summary;
  EXPECT_EQ(rig.plane.sync_edges(), 2u);
}

TEST(ClientPlc, AStartByTheSyncLineWithoutAPlcIsRefusedBeforeAnythingMoves) {
  Rig rig(false);
  std::map<std::uint16_t, ArmPath> paths;
  for (const auto id : rig.fps.robots()) paths[id] = {{{20.0, 1.0}}, {}};
  try {
    rig.fps.run_trajectories(paths, true);
    FAIL() << "a sync-line start ran without a PLC";
  } catch (const Exception& e) {
    EXPECT_EQ(e.code(), host::HostErrc::invalid_argument) << e.what();
  }
  for (const auto id : rig.fps.robots()) EXPECT_NEAR(rig.plane.arms(id)->alpha, 0.0, 0.01) << id;
}

}  // namespace
}  // namespace axon::fps::client_upgrade_test

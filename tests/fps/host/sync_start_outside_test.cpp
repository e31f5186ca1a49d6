// The sync line reaches every powered robot on every bus of the array, not only the buses of the
// run: a robot outside the run that still holds a trajectory must be aborted before a start by the
// sync line, or that start refused (it would move with nobody watching it).
#include "plane_rig.hpp"

#include <gtest/gtest.h>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::host;
using namespace axon::fps::host::testing;

namespace {

// From the fold to `to` in 4 s, well within the arms' speed limit.
protocol::Trajectory fold_to(ArmAngles to) {
  std::vector<protocol::ArmPoint> a{{to.alpha, 4.0}}, b{{to.beta, 4.0}};
  return protocol::Trajectory::from_physical(a, b).value();
}

// Robots 1-3 (gateway 1, bus 1) from the fold to alpha 30.
std::map<std::uint16_t, protocol::Trajectory> first_bus_run() {
  std::map<std::uint16_t, protocol::Trajectory> t;
  for (std::uint16_t id = 1; id <= 3; ++id) t.emplace(id, fold_to({30, 170}));
  return t;
}

// Robot 10 (gateway 2, bus 2) loads a trajectory and keeps it (a load-only run).
asio::awaitable<void> load_robot_10(PlaneRig& rig) {
  TrajectoryOptions load;
  load.start = false;
  std::map<std::uint16_t, protocol::Trajectory> t;
  t.emplace(10, fold_to({40, 160}));
  auto r = co_await rig.fpa->array().run_trajectories(std::move(t), load);
  EXPECT_TRUE(r.has_value());
  if (r) {
    EXPECT_EQ(r.value().find(10)->state, RobotState::loaded) << r.value().summary();
  }
}

}  // namespace

TEST(SyncStartOutsideTheRun, RobotOnAnotherBusHoldingATrajectoryDoesNotMove) {
  PlaneRig rig;
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    co_await load_robot_10(rig);
    const auto* m10 = rig.sim->simulator().find(10);
    const double alpha0 = m10->physical_deg(sim::Arm::alpha), beta0 = m10->physical_deg(sim::Arm::beta);

    auto r = co_await rig.fpa->run_trajectories(first_bus_run(), {}, /*by_sync_line=*/true);
    EXPECT_TRUE(r.has_value()) << r.error().message();
    if (r) {
      EXPECT_TRUE(r.value().completed) << r.value().summary();
    }
    EXPECT_EQ(rig.sim->counters().sync_edges, 1u);
    EXPECT_NEAR(rig.sim->simulator().find(1)->physical_deg(sim::Arm::alpha), 30.0, 0.1);
    EXPECT_FALSE(m10->moving());
    EXPECT_NEAR(m10->physical_deg(sim::Arm::alpha), alpha0, 1e-6);
    EXPECT_NEAR(m10->physical_deg(sim::Arm::beta), beta0, 1e-6);
  });
}

TEST(SyncStartOutsideTheRun, RefusedWhenARobotOutsideTheRunDoesNotAcknowledgeTheAbort) {
  auto so = plane_sim_options();
  // Robot 10 answers the abort of its own load-only run, then no more aborts.
  so.simulator.reply_faults.rules.push_back(drop_rule(replies_of(10, protocol::CommandId::trajectory_abort), 1));
  PlaneRig rig(std::move(so));
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    co_await load_robot_10(rig);
    auto r = co_await rig.fpa->run_trajectories(first_bus_run(), {}, /*by_sync_line=*/true);
    EXPECT_FALSE(r.has_value());
    if (!r) {
      EXPECT_EQ(r.error(), HostErrc::not_ready);
      EXPECT_NE(r.error().message().find("10"), std::string::npos) << r.error().message();
      EXPECT_NE(r.error().message().find("sync line"), std::string::npos) << r.error().message();
    }
    EXPECT_EQ(rig.sim->counters().sync_edges, 0u);
    for (auto* m : rig.sim->simulator().robots()) EXPECT_FALSE(m->moving());
  });
}

TEST(SyncStartOutsideTheRun, BroadcastStartLeavesOtherBusesAlone) {
  PlaneRig rig;
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    co_await load_robot_10(rig);
    auto r = co_await rig.fpa->run_trajectories(first_bus_run(), {}, /*by_sync_line=*/false);
    EXPECT_TRUE(r.has_value());
    if (r) {
      EXPECT_TRUE(r.value().completed) << r.value().summary();
    }
    // The START_TRAJECTORY broadcast went to bus 1 only: robot 10 kept its trajectory, unstarted.
    EXPECT_FALSE(rig.sim->simulator().find(10)->moving());
    EXPECT_NEAR(rig.sim->simulator().find(10)->physical_deg(sim::Arm::alpha), 0.0, 1e-6);
  });
}

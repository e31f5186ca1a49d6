// Array against the simulator: discovery over several buses, the status table, the trajectory
// sequence (valid, too fast, out of range, too many points, robot not ready, start not
// acknowledged, interrupted by a collision), and the collision lock and unlock.
#include "sim_rig.hpp"

#include "axon/fps/protocol/error.hpp"

#include <gtest/gtest.h>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::host;
using namespace axon::fps::host::testing;
using protocol::CommandId;
using protocol::ResponseCode;
using protocol::StatusBit;

namespace {

using Trajectories = std::map<std::uint16_t, protocol::Trajectory>;

// Robots start folded at (0, 180); this takes alpha to 20 and beta to 170 within 2 s.
protocol::Trajectory gentle() { return trajectory({{10, 1.0}, {20, 2.0}}, {{175, 1.0}, {170, 2.0}}); }

}  // namespace

TEST(ArraySim, DiscoveryRecordsWhichBusEachRobotIsOnWithFirmwareAndStatus) {
  SimRig rig(2);
  rig.add(3, 0);
  rig.add(12, 0);
  rig.add(5, 1);
  rig.add(40, 1, [](sim::PositionerConfig& c) { c.sync_line_low_at_power_on = true; });
  rig.add(41, 1, [](sim::PositionerConfig& c) { c.datums_initialized = false; });
  rig.start();
  DiscoveryReport rep;
  rig.run([&]() -> asio::awaitable<void> {
    rep = co_await rig.discover();
    // Unknown robots are typed errors.
    auto unknown = rig.array->positioner(99);
    EXPECT_FALSE(unknown.has_value());
    if (!unknown) { EXPECT_EQ(unknown.error(), HostErrc::unknown_positioner); }
  });
  EXPECT_TRUE(rep.problems.empty()) << (rep.problems.empty() ? "" : rep.problems.front());
  EXPECT_EQ(rig.array->ids(), (std::vector<std::uint16_t>{3, 5, 12, 40, 41}));
  EXPECT_EQ(rig.array->ids_on(0), (std::vector<std::uint16_t>{3, 12}));
  EXPECT_EQ(rig.array->bus_of(5).value(), 1u);
  const auto& t = rep.table;
  ASSERT_NE(t.find(3), nullptr);
  EXPECT_EQ(t.find(3)->bus_name, "fps0");
  EXPECT_EQ(t.find(5)->bus_name, "fps1");
  EXPECT_EQ(t.find(3)->state(), "ready");
  EXPECT_TRUE(t.find(3)->ready());
  EXPECT_EQ(t.find(3)->firmware, (protocol::FirmwareVersion{4, 1, 13}));
  ASSERT_TRUE(t.find(3)->position.has_value());
  EXPECT_NEAR(t.find(3)->position->beta, 180.0, 1e-3);
  ASSERT_NE(t.find(40), nullptr);
  EXPECT_EQ(t.find(40)->state(), "bootloader");
  EXPECT_TRUE(t.find(40)->bootloader_status.has_value());
  EXPECT_FALSE(t.find(40)->status.has_value());
  ASSERT_NE(t.find(41), nullptr);
  EXPECT_EQ(t.find(41)->state(), "no-datum");
  EXPECT_FALSE(t.find(41)->ready());
  EXPECT_EQ(t.count_ready(), 3u);
  const auto text = t.to_text();
  EXPECT_NE(text.find("bootloader"), std::string::npos);
  EXPECT_NE(text.find("DATUM_ALPHA_INITIALIZED"), std::string::npos);
}

TEST(ArraySim, DiscoveryNotesRobotsThatStoppedAnswering) {
  SimRig rig(1);
  rig.add(3, 0);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    EXPECT_TRUE(rig.array->add(8, 0).has_value());  // configured, but not on the bus
    auto rep = co_await rig.array->discover();
    EXPECT_TRUE(rep.has_value());
    if (!rep) co_return;
    EXPECT_EQ(rep.value().problems.size(), 1u);
    EXPECT_NE(rep.value().problems.front().find("positioner 8"), std::string::npos);
    const auto* row = rep.value().table.find(8);
    EXPECT_NE(row, nullptr);
    if (row) {
      EXPECT_EQ(row->state(), "no-reply");
      EXPECT_NE(row->error.find("no reply"), std::string::npos) << row->error;
    }
  });
}

TEST(ArraySim, TrajectoriesOnTwoBusesRunToTheirLastPoints) {
  SimRig rig(2);
  rig.add(3, 0);
  rig.add(5, 1);
  rig.add(6, 1);  // on a bus of the run, but without a trajectory: must not move
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    Trajectories t;
    t.emplace(3, gentle());
    t.emplace(5, trajectory({{30, 3.0}}, {}));  // beta stays where it is
    auto rep = co_await rig.array->run_trajectories(std::move(t));
    EXPECT_TRUE(rep.has_value());
    if (!rep) co_return;
    EXPECT_TRUE(rep.value().completed) << rep.value().summary();
    EXPECT_TRUE(rep.value().started);
    EXPECT_TRUE(rep.value().ok());
    const auto* r5 = rep.value().find(5);
    EXPECT_NE(r5, nullptr);
    if (r5 && r5->reached) {
      EXPECT_NEAR(r5->reached->alpha, 30.0, 0.1);
      EXPECT_NEAR(r5->reached->beta, 180.0, 0.1);
      EXPECT_EQ(r5->upload.points_accepted, 1u);
    }
  });
  EXPECT_NEAR(rig.model(3).reported_deg(sim::Arm::alpha), 20.0, 0.1);
  EXPECT_NEAR(rig.model(3).reported_deg(sim::Arm::beta), 170.0, 0.1);
  EXPECT_NEAR(rig.model(6).reported_deg(sim::Arm::alpha), 0.0, 1e-6);
  EXPECT_FALSE(rig.array->locked());
}

TEST(ArraySim, ATooFastPointIsReportedPreciselyAndNothingStarts) {
  SimRig rig(1);
  rig.add(3, 0);
  rig.add(4, 0);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    Trajectories t;
    t.emplace(3, gentle());
    // Beta point 1 asks for 100 degrees in 0.5 s: faster than the motors go.
    t.emplace(4, trajectory({{5, 1.0}}, {{175, 1.0}, {75, 1.5}, {70, 3.0}}));
    auto rep = co_await rig.array->run_trajectories(std::move(t));
    EXPECT_TRUE(rep.has_value());
    if (!rep) co_return;
    const auto& r = rep.value();
    EXPECT_FALSE(r.started);
    EXPECT_FALSE(r.completed);
    EXPECT_EQ(r.in_state(RobotState::upload_failed), (std::vector<std::uint16_t>{4}));
    EXPECT_EQ(r.in_state(RobotState::withdrawn), (std::vector<std::uint16_t>{3}));
    const auto* r4 = r.find(4);
    EXPECT_NE(r4, nullptr);
    if (r4) {
      EXPECT_EQ(r4->upload.stage, UploadResult::Stage::points);
      EXPECT_EQ(r4->upload.arm, Arm::beta);
      EXPECT_EQ(r4->upload.point, std::optional<std::size_t>(1));
      EXPECT_TRUE(r4->upload.error.has_value());
      if (r4->upload.error) { EXPECT_EQ(*r4->upload.error, ResponseCode::value_out_of_range); }
      EXPECT_NE(r.summary().find("beta point 1"), std::string::npos) << r.summary();
    }
    EXPECT_NE(r.outcome.find("failed the checks or the upload"), std::string::npos) << r.outcome;
  });
  EXPECT_FALSE(rig.model(3).moving());
  EXPECT_NEAR(rig.model(3).reported_deg(sim::Arm::alpha), 0.0, 1e-6);  // never started
  EXPECT_FALSE(rig.model(3).status().has(StatusBit::trajectory_alpha_received));  // withdrawn
}

TEST(ArraySim, APointBeyondTheHardStopIsRefused) {
  SimRig rig(1);
  rig.add(3, 0);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    Trajectories t;
    t.emplace(3, trajectory({{100, 10.0}, {200, 20.0}, {370, 40.0}}, {}));
    auto rep = co_await rig.array->run_trajectories(std::move(t));
    EXPECT_TRUE(rep.has_value());
    if (!rep) co_return;
    const auto* r3 = rep.value().find(3);
    EXPECT_NE(r3, nullptr);
    if (!r3) co_return;
    EXPECT_EQ(r3->state, RobotState::upload_failed);
    EXPECT_EQ(r3->upload.arm, Arm::alpha);
    EXPECT_EQ(r3->upload.point, std::optional<std::size_t>(2));
    EXPECT_EQ(r3->upload.points_accepted, 2u);
    EXPECT_FALSE(rep.value().started);
  });
}

TEST(ArraySim, TooManyPointsNeverLeaveTheHost) {
  std::vector<protocol::ArmPoint> many;
  for (int i = 1; i <= 1024; ++i) many.push_back({0.01 * i, 0.1 * i});
  auto t = protocol::Trajectory::from_physical(many, {});
  EXPECT_FALSE(t.has_value());
  if (!t) { EXPECT_EQ(t.error(), protocol::ProtocolErrc::invalid_trajectory); }
  // Sent by hand anyway, the announcement is refused by the robot.
  SimRig rig(1);
  rig.add(3, 0);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    auto r = co_await rig.array->client(0).call<CommandId::send_new_trajectory>(3, {1024, 0});
    EXPECT_FALSE(r.has_value());
    if (!r) { EXPECT_EQ(r.error(), ResponseCode::value_out_of_range); }
  });
}

TEST(ArraySim, RobotsThatAreNotReadyStopTheRunBeforeAnyUpload) {
  SimRig rig(1);
  rig.add(3, 0);
  rig.add(4, 0, [](sim::PositionerConfig& c) { c.datums_initialized = false; });
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    Trajectories t;
    t.emplace(3, gentle());
    t.emplace(4, gentle());
    auto rep = co_await rig.array->run_trajectories(std::move(t));
    EXPECT_TRUE(rep.has_value());
    if (!rep) co_return;
    EXPECT_EQ(rep.value().in_state(RobotState::not_ready), (std::vector<std::uint16_t>{4}));
    EXPECT_EQ(rep.value().in_state(RobotState::withdrawn), (std::vector<std::uint16_t>{3}));
    const auto* r4 = rep.value().find(4);
    if (r4) {
      EXPECT_NE(r4->detail.find("datum"), std::string::npos) << r4->detail;
      EXPECT_EQ(r4->upload.stage, UploadResult::Stage::not_sent);
    }
  });
  EXPECT_FALSE(rig.model(3).moving());
}

TEST(ArraySim, LoadOnlyValidatesWithoutStarting) {
  SimRig rig(1);
  rig.add(3, 0);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    Trajectories t;
    t.emplace(3, gentle());
    TrajectoryOptions o;
    o.start = false;
    auto rep = co_await rig.array->run_trajectories(std::move(t), o);
    EXPECT_TRUE(rep.has_value());
    if (rep) { EXPECT_TRUE(rep.value().ok(true)) << rep.value().summary(); }
    EXPECT_TRUE(rig.model(3).status().trajectory_received());
    EXPECT_FALSE(rig.model(3).moving());
  });
}

TEST(ArraySim, ARobotThatDoesNotAcknowledgeTheStartStopsEveryone) {
  SimRig rig(2);
  rig.add(3, 0);
  rig.add(5, 1);
  rig.start();
  // Robot 5's acknowledgement of the START_TRAJECTORY broadcast (uid 0) is lost.
  can::FaultPlan plan;
  can::FaultRule drop;
  drop.action = can::FaultRule::Action::drop;
  drop.match = can::Filter{(5u << 18) | (14u << 10), 0x1FFFFFF0u, can::Filter::Format::extended};
  plan.rules.push_back(drop);
  rig.media[1]->set_fault_plan(plan);
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    Trajectories t;
    t.emplace(3, trajectory({{200, 20.0}}, {}));
    t.emplace(5, trajectory({{200, 20.0}}, {}));
    TrajectoryOptions o;
    o.start_window = 300ms;
    auto rep = co_await rig.array->run_trajectories(std::move(t), o);
    EXPECT_TRUE(rep.has_value());
    if (!rep) co_return;
    EXPECT_FALSE(rep.value().started);
    EXPECT_EQ(rep.value().in_state(RobotState::not_started), (std::vector<std::uint16_t>{5}));
    EXPECT_EQ(rep.value().in_state(RobotState::stopped), (std::vector<std::uint16_t>{3}));
    EXPECT_NE(rep.value().outcome.find("start failed"), std::string::npos);
    const bool stopped = co_await eventually([&] { return !rig.model(3).moving() && !rig.model(5).moving(); });
    EXPECT_TRUE(stopped);
  });
  EXPECT_EQ(rig.array->counters().start_failures, 1u);
  EXPECT_EQ(rig.array->counters().emergency_stops, 1u);
  EXPECT_FALSE(rig.array->locked());  // a start failure stops, it does not lock
  EXPECT_LT(rig.model(3).reported_deg(sim::Arm::alpha), 199.0);  // stopped on the way
}

TEST(ArraySim, ACollisionLocksTheArrayStopsEveryRobotAndRefusesMotionUntilUnlock) {
  SimRig rig(2);
  rig.add(3, 0);
  rig.add(4, 0);
  rig.add(5, 1);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    // Long moves on every robot, then robot 4 collides.
    for (std::uint16_t id : {3, 4, 5}) {
      auto eta = co_await rig.array->find(id)->start_goto({300, 20}, false);
      EXPECT_TRUE(eta.has_value());
    }
    EXPECT_TRUE(rig.model(5).moving());
    EXPECT_TRUE(rig.simulator.force_collision(4, sim::Arm::beta).has_value());
    const bool locked = co_await eventually([&] { return rig.array->locked(); });
    EXPECT_TRUE(locked);
    const bool all_stopped = co_await eventually(
        [&] { return !rig.model(3).moving() && !rig.model(4).moving() && !rig.model(5).moving(); });
    EXPECT_TRUE(all_stopped);
    const auto& lock = rig.array->lock_state();
    EXPECT_EQ(lock.collisions.size(), 1u);
    if (!lock.collisions.empty()) {
      EXPECT_EQ(lock.collisions[0].positioner, 4);
      EXPECT_EQ(lock.collisions[0].code, ResponseCode::beta_collision);
      EXPECT_TRUE(lock.collisions[0].caused_lock);
    }
    EXPECT_NE(lock.reason.find("positioner 4"), std::string::npos);
    // The abort keeps the flag for diagnosis.
    EXPECT_TRUE(rig.model(4).status().has(StatusBit::collision_beta));
    // Motion is refused, reads still work.
    auto move = co_await rig.array->find(3)->goto_absolute({10, 170});
    EXPECT_FALSE(move.has_value());
    if (!move) { EXPECT_EQ(move.error(), HostErrc::locked); }
    std::map<std::uint16_t, ArmAngles> targets;
    targets.emplace(5, ArmAngles{10, 170});
    auto many = co_await rig.array->goto_absolute(targets);
    EXPECT_FALSE(many.has_value());
    Trajectories t;
    t.emplace(3, gentle());
    auto traj = co_await rig.array->run_trajectories(std::move(t));
    EXPECT_FALSE(traj.has_value());
    if (!traj) { EXPECT_EQ(traj.error(), HostErrc::locked); }
    auto datum = co_await rig.array->find(5)->go_to_datums();
    EXPECT_FALSE(datum.has_value());
    const bool readable = (co_await rig.array->find(3)->read_status()).has_value();
    EXPECT_TRUE(readable);
    // A further report after the stop is expected, not a new event.
    EXPECT_TRUE(rig.simulator.force_collision(5, sim::Arm::alpha).has_value());
    const bool second = co_await eventually([&] { return rig.array->lock_state().collisions.size() == 2; });
    EXPECT_TRUE(second);
    EXPECT_FALSE(rig.array->lock_state().collisions.back().caused_lock);
    EXPECT_EQ(rig.array->counters().collision_locks, 1u);
    EXPECT_EQ(rig.array->counters().expected_collisions, 1u);
    EXPECT_EQ(rig.array->counters().emergency_stops, 1u);
    // Unlock clears the flags on every bus and allows motion again.
    auto un = co_await rig.array->unlock();
    EXPECT_TRUE(un.has_value()) << (un ? "" : un.error().message());
    if (un) {
      EXPECT_EQ(un.value().acknowledged, (std::vector<std::uint16_t>{3, 4, 5}));
      EXPECT_TRUE(un.value().silent.empty());
    }
    EXPECT_FALSE(rig.array->locked());
    EXPECT_FALSE(rig.model(4).status().collided());
    EXPECT_FALSE(rig.model(5).status().collided());
    auto again = co_await rig.array->find(3)->goto_absolute({10, 170});
    EXPECT_TRUE(again.has_value()) << (again ? "" : again.error().message());
  });
  EXPECT_EQ(rig.array->counters().unlocks, 1u);
}

TEST(ArraySim, ACollisionDuringATrajectoryReportsWhoCollidedAndWhoWasStopped) {
  SimRig rig(2);
  rig.add(3, 0);
  rig.add(5, 1);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    Trajectories t;
    t.emplace(3, trajectory({{100, 10.0}}, {}));
    t.emplace(5, trajectory({{100, 10.0}}, {}));
    std::optional<Result<TrajectoryReport>> rep;
    spawn(rig.runner.io, rig.array->run_trajectories(std::move(t)),
          [&](Result<TrajectoryReport> r) { rep = std::move(r); });
    const bool moving = co_await eventually([&] { return rig.model(5).moving(); });
    EXPECT_TRUE(moving);
    EXPECT_TRUE(rig.simulator.force_collision(5, sim::Arm::alpha).has_value());
    const bool done = co_await eventually([&] { return rep.has_value(); }, 20000);
    EXPECT_TRUE(done);
    if (!rep || !*rep) co_return;
    const auto& r = rep->value();
    EXPECT_TRUE(r.started);
    EXPECT_FALSE(r.completed);
    EXPECT_EQ(r.in_state(RobotState::collided), (std::vector<std::uint16_t>{5}));
    EXPECT_EQ(r.in_state(RobotState::stopped), (std::vector<std::uint16_t>{3}));
    EXPECT_NE(r.outcome.find("collision"), std::string::npos) << r.outcome;
    EXPECT_TRUE(rig.array->locked());
  });
  EXPECT_FALSE(rig.model(3).moving());
}

TEST(ArraySim, HallSwitchesAreBroadcastOnEveryBusAndChecked) {
  SimRig rig(2);
  rig.add(3, 0);
  rig.add(5, 1);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    auto off = co_await rig.array->set_hall(false);
    EXPECT_TRUE(off.has_value()) << (off ? "" : off.error().message());
    EXPECT_TRUE(rig.model(5).status().has(StatusBit::switch_off_hall_after_move));
    auto on = co_await rig.array->set_hall(true);
    EXPECT_TRUE(on.has_value());
    EXPECT_FALSE(rig.model(3).status().has(StatusBit::switch_off_hall_after_move));
    auto stop = co_await rig.array->stop_all(false);
    EXPECT_TRUE(stop.has_value());
  });
}

TEST(ArraySim, GoToMovesRobotsOnSeveralBusesAtOnce) {
  SimRig rig(2);
  rig.add(3, 0);
  rig.add(5, 1);
  rig.start();
  std::map<std::uint16_t, ArmAngles> targets, deltas;
  targets.emplace(3, ArmAngles{30, 150});
  targets.emplace(5, ArmAngles{40, 160});
  deltas.emplace(3, ArmAngles{-10, 5});
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    auto a = co_await rig.array->goto_absolute(targets);
    EXPECT_TRUE(a.has_value());
    if (a) {
      for (const auto& [id, r] : a.value()) EXPECT_TRUE(r.has_value()) << id << ": " << (r ? "" : r.error().message());
    }
    auto r = co_await rig.array->goto_relative(deltas);
    EXPECT_TRUE(r.has_value());
    if (r && r.value().at(3)) { EXPECT_NEAR(r.value().at(3).value().reached.alpha, 20.0, 0.1); }
    std::map<std::uint16_t, ArmAngles> unknown;
    unknown.emplace(77, ArmAngles{});
    auto u = co_await rig.array->goto_absolute(unknown);
    EXPECT_FALSE(u.has_value());
    if (!u) { EXPECT_EQ(u.error(), HostErrc::unknown_positioner); }
  });
  EXPECT_NEAR(rig.model(5).reported_deg(sim::Arm::alpha), 40.0, 0.1);
  EXPECT_NEAR(rig.model(3).reported_deg(sim::Arm::beta), 155.0, 0.1);
}

// A sextant's worth: four buses of 21 robots each, discovered and moved by one trajectory run.
TEST(ArraySim, FourBusesOfTwentyOneRobots) {
  SimRig rig(4);
  std::vector<std::uint16_t> ids;
  for (std::uint16_t bus = 0; bus < 4; ++bus) {
    for (std::uint16_t k = 0; k < 21; ++k) {
      const auto id = static_cast<std::uint16_t>(100 * (bus + 1) + k);
      rig.add(id, bus);
      ids.push_back(id);
    }
  }
  rig.start();
  std::optional<TrajectoryReport> report;
  rig.run([&]() -> asio::awaitable<void> {
    std::map<std::size_t, std::size_t> expected{{0, 21}, {1, 21}, {2, 21}, {3, 21}};
    auto found = co_await rig.array->discover(expected);
    EXPECT_TRUE(found.has_value());
    if (found) {
      EXPECT_EQ(found.value().table.count_ready(), 84u) << found.value().table.to_text();
    }
    std::map<std::uint16_t, protocol::Trajectory> t;
    for (auto id : ids) t.emplace(id, trajectory({{10, 1.0}, {25, 2.0}}, {{170, 1.5}}));
    auto r = co_await rig.array->run_trajectories(std::move(t));
    EXPECT_TRUE(r.has_value());
    if (r) report = r.value();
  });
  ASSERT_TRUE(report.has_value());
  EXPECT_TRUE(report->completed) << report->summary();
  EXPECT_EQ(report->in_state(RobotState::completed).size(), 84u);
  EXPECT_EQ(rig.array->ids_on(3).size(), 21u);
  EXPECT_EQ(rig.array->client_totals().timeouts, 0u);
  EXPECT_EQ(rig.simulator.receive_overflows(), 0u);
  for (auto id : ids) EXPECT_NEAR(rig.model(id).reported_deg(sim::Arm::alpha), 25.0, 0.1) << id;
}

// The host against the simulator with faults on the wire (the simulator's reply fault plan, which
// touches only what the robots send): dropped, delayed and duplicated replies, late replies, and
// a lost collision report. Each test asserts the host's state afterwards.
#include "sim_rig.hpp"

#include <gtest/gtest.h>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::host;
using namespace axon::fps::host::testing;
using protocol::CommandId;
using protocol::ResponseCode;

namespace {

// Frames robot `id` sends for `command`.
can::Filter from(std::uint16_t id, CommandId command) {
  return can::Filter{(std::uint32_t{id} << 18) | (std::uint32_t{protocol::number(command)} << 10), 0x1FFFFC00u,
                     can::Filter::Format::extended};
}

can::FaultRule rule(can::FaultRule::Action a, can::Filter f, std::uint64_t skip = 0,
                    std::uint64_t count = std::numeric_limits<std::uint64_t>::max()) {
  can::FaultRule r;
  r.action = a;
  r.match = f;
  r.skip = skip;
  r.count = count;
  return r;
}

}  // namespace

TEST(FaultSim, DroppedStatusRepliesAreRetriedAndTheTableIsComplete) {
  ArrayOptions ao = fast_array();
  ao.client.timeout = 200ms;
  auto so = fast_sim();
  // Robot 3's status reply is lost twice (after discovery's own read).
  so.reply_faults.rules.push_back(rule(can::FaultRule::Action::drop, from(3, CommandId::get_status), 1, 2));
  SimRig rig(1, so, ao);
  rig.add(3, 0);
  rig.add(4, 0);
  rig.start();
  StatusTable table;
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    table = co_await rig.array->status_table();
  });
  ASSERT_NE(table.find(3), nullptr);
  EXPECT_TRUE(table.find(3)->status.has_value()) << table.to_text();
  EXPECT_TRUE(table.find(3)->error.empty());
  EXPECT_EQ(table.count_ready(), 2u);
  EXPECT_EQ(rig.array->client_totals().retries, 2u);
  EXPECT_EQ(rig.array->client_totals().timeouts, 2u);
  EXPECT_EQ(rig.simulator.stats().faults_dropped, 2u);
}

TEST(FaultSim, AReplyThatNeverComesIsATimeoutForThatRobotOnly) {
  ArrayOptions ao = fast_array();
  ao.client.timeout = 100ms;
  auto so = fast_sim();
  so.reply_faults.rules.push_back(rule(can::FaultRule::Action::drop, from(3, CommandId::switch_on_led)));
  SimRig rig(1, so, ao);
  rig.add(3, 0);
  rig.add(4, 0);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    auto r3 = co_await rig.array->find(3)->set_led(true);
    EXPECT_FALSE(r3.has_value());
    if (!r3) { EXPECT_EQ(r3.error(), HostErrc::timeout); }
    auto r4 = co_await rig.array->find(4)->set_led(true);
    EXPECT_TRUE(r4.has_value());
  });
  EXPECT_TRUE(rig.model(3).led_on());  // the robot did it; only its answer was lost
  EXPECT_EQ(rig.array->client(0).counters().retries, 0u);  // not a read: never repeated
}

TEST(FaultSim, DelayedRepliesWithinTheTimeoutChangeNothing) {
  auto so = fast_sim();
  auto delay = rule(can::FaultRule::Action::delay, can::Filter{3u << 18, 0x7FFu << 18, can::Filter::Format::extended});
  delay.delay = 20ms;
  so.reply_faults.rules.push_back(delay);
  SimRig rig(1, so);
  rig.add(3, 0);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    auto m = co_await rig.array->find(3)->goto_absolute({15, 170});
    EXPECT_TRUE(m.has_value()) << (m ? "" : m.error().message());
  });
  EXPECT_EQ(rig.array->client_totals().timeouts, 0u);
  EXPECT_GT(rig.simulator.stats().faults_delayed, 5u);
}

TEST(FaultSim, RepliesLaterThanTheTimeoutAreCountedAsLateAndIgnored) {
  ArrayOptions ao = fast_array();
  ao.client.timeout = 50ms;
  ao.client.read_retries = 0;
  auto so = fast_sim();
  auto delay = rule(can::FaultRule::Action::delay, from(3, CommandId::get_offsets), 0, 1);
  delay.delay = 300ms;
  so.reply_faults.rules.push_back(delay);
  SimRig rig(1, so, ao);
  rig.add(3, 0);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    auto late = co_await rig.array->find(3)->read_offsets();
    EXPECT_FALSE(late.has_value());
    const bool counted = co_await eventually([&] { return rig.array->client(0).counters().late == 1; });
    EXPECT_TRUE(counted);
    auto again = co_await rig.array->find(3)->read_offsets();
    EXPECT_TRUE(again.has_value());
  });
  EXPECT_EQ(rig.array->client(0).counters().late, 1u);
  EXPECT_EQ(rig.array->client(0).counters().unmatched, 0u);
}

TEST(FaultSim, DuplicatedRepliesDoNotDisturbATrajectoryRun) {
  auto so = fast_sim();
  so.reply_faults.rules.push_back(
      rule(can::FaultRule::Action::duplicate, can::Filter{3u << 18, 0x7FFu << 18, can::Filter::Format::extended}));
  SimRig rig(1, so);
  rig.add(3, 0);
  rig.add(4, 0);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    std::map<std::uint16_t, protocol::Trajectory> t;
    t.emplace(3, trajectory({{5, 0.5}, {10, 1.0}, {15, 1.5}, {20, 2.0}}, {{175, 1.0}}));
    t.emplace(4, trajectory({{10, 1.0}}, {}));
    auto rep = co_await rig.array->run_trajectories(std::move(t));
    EXPECT_TRUE(rep.has_value());
    if (rep) { EXPECT_TRUE(rep.value().completed) << rep.value().summary(); }
  });
  const auto c = rig.array->client(0).counters();
  EXPECT_GT(c.unmatched, 5u);            // the second copies of unicast replies
  EXPECT_GT(c.broadcast_duplicates, 0u);  // and of broadcast replies
  EXPECT_EQ(c.timeouts, 0u);
  EXPECT_FALSE(rig.array->locked());
}

TEST(FaultSim, ALostCollisionReportIsCaughtByTheStatusPollAndStillStopsEveryone) {
  auto so = fast_sim();
  so.reply_faults.rules.push_back(rule(can::FaultRule::Action::drop, from(3, CommandId::collision_detected)));
  SimRig rig(2, so);
  rig.add(3, 0);
  rig.add(5, 1);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    std::map<std::uint16_t, protocol::Trajectory> t;
    t.emplace(3, trajectory({{100, 10.0}}, {}));
    t.emplace(5, trajectory({{100, 10.0}}, {}));
    std::optional<Result<TrajectoryReport>> rep;
    spawn(rig.runner.io, rig.array->run_trajectories(std::move(t)),
          [&](Result<TrajectoryReport> r) { rep = std::move(r); });
    const bool moving = co_await eventually([&] { return rig.model(3).moving(); });
    EXPECT_TRUE(moving);
    EXPECT_TRUE(rig.simulator.force_collision(3, sim::Arm::beta).has_value());
    const bool done = co_await eventually([&] { return rep.has_value(); }, 20000);
    EXPECT_TRUE(done);
    if (rep && *rep) {
      EXPECT_EQ(rep->value().in_state(RobotState::collided), (std::vector<std::uint16_t>{3}));
      EXPECT_EQ(rep->value().in_state(RobotState::stopped), (std::vector<std::uint16_t>{5}));
    }
  });
  EXPECT_EQ(rig.array->client(0).counters().collisions, 0u);  // the frame never arrived
  EXPECT_TRUE(rig.array->locked());
  EXPECT_NE(rig.array->lock_state().reason.find("status of positioner 3"), std::string::npos);
  EXPECT_FALSE(rig.model(5).moving());
  EXPECT_EQ(rig.simulator.stats().faults_dropped, 1u);
}

// One lost reply in a trajectory upload (here the second point's acknowledgement) must not call
// the run off: the robot is uploaded again from SEND_NEW_TRAJECTORY, and the run starts and ends
// at the targets. Before the re-upload, this run was refused ("not started").
TEST(FaultSim, ALostReplyDuringAnUploadIsUploadedAgainAndTheRunCompletes) {
  auto so = fast_sim();
  so.reply_faults.rules.push_back(rule(can::FaultRule::Action::drop, from(3, CommandId::send_trajectory_data), 1, 1));
  SimRig rig(1, so);
  rig.add(3, 0);
  rig.add(4, 0);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    std::map<std::uint16_t, protocol::Trajectory> t;
    t.emplace(3, trajectory({{5, 0.5}, {10, 1.0}, {15, 1.5}}, {{175, 1.0}}));
    t.emplace(4, trajectory({{10, 1.0}}, {}));
    auto rep = co_await rig.array->run_trajectories(std::move(t));
    EXPECT_TRUE(rep.has_value());
    if (!rep) co_return;
    EXPECT_TRUE(rep.value().completed) << rep.value().summary();
    const RobotRun* r3 = rep.value().find(3);
    EXPECT_EQ(r3->upload_attempts, 2u);
    EXPECT_NE(r3->detail.find("loaded on attempt 2"), std::string::npos) << r3->detail;
    EXPECT_EQ(rep.value().find(4)->upload_attempts, 1u);
  });
  EXPECT_EQ(rig.simulator.stats().faults_dropped, 1u);
  EXPECT_NEAR(rig.model(3).physical_deg(sim::Arm::alpha), 15.0, 0.1);
  EXPECT_FALSE(rig.array->locked());
}

// A robot that stops answering mid-upload gets its retries, then the run is called off as before:
// nothing starts, the other robot's trajectory is withdrawn, and the report says how often it
// tried. With upload_retries 0 a single lost reply is enough.
TEST(FaultSim, ARobotThatStopsAnsweringMidUploadFailsAfterItsRetriesAndNothingStarts) {
  for (unsigned retries : {0u, 1u}) {
    auto so = fast_sim();
    so.reply_faults.rules.push_back(rule(can::FaultRule::Action::drop, from(3, CommandId::send_trajectory_data), 1));
    SimRig rig(1, so);
    rig.add(3, 0);
    rig.add(4, 0);
    rig.start();
    rig.run([&]() -> asio::awaitable<void> {
      co_await rig.discover();
      std::map<std::uint16_t, protocol::Trajectory> t;
      t.emplace(3, trajectory({{5, 0.5}, {10, 1.0}}, {}));
      t.emplace(4, trajectory({{10, 1.0}}, {}));
      TrajectoryOptions o;
      o.upload_retries = retries;
      auto rep = co_await rig.array->run_trajectories(std::move(t), o);
      EXPECT_TRUE(rep.has_value());
      if (!rep) co_return;
      EXPECT_FALSE(rep.value().started);
      const RobotRun* r3 = rep.value().find(3);
      EXPECT_EQ(r3->state, RobotState::upload_failed);
      EXPECT_EQ(r3->upload_attempts, retries + 1);
      if (retries > 0) { EXPECT_NE(r3->detail.find("after 2 attempts"), std::string::npos) << r3->detail; }
      EXPECT_EQ(rep.value().find(4)->state, RobotState::withdrawn);
    });
    EXPECT_FALSE(rig.model(3).moving());
    EXPECT_FALSE(rig.model(4).moving());
  }
}

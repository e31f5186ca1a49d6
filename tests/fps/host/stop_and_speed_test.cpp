// Stopping every robot on request (a signal handler's or a watchdog's stop) while a trajectory
// runs, and the speed check that refuses a trajectory the robots cannot make before anything is
// uploaded: the host driver against simulated robots on virtual buses.
#include "sim_rig.hpp"

#include "axon/fps/host/trajectory_speed.hpp"

#include <gtest/gtest.h>

#include <regex>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::host;
using namespace axon::fps::host::testing;

namespace {

// Both arms straight from (0, 180) to (alpha, beta) over `seconds`, in 10 points.
protocol::Trajectory straight(double alpha, double beta, double seconds) {
  std::vector<protocol::ArmPoint> a, b;
  for (int i = 1; i <= 10; ++i) {
    const double f = i / 10.0;
    a.push_back({alpha * f, seconds * f});
    b.push_back({180 + (beta - 180) * f, seconds * f});
  }
  return trajectory(a, b);
}

}  // namespace

TEST(StopRequest, ARequestedStopEndsTheRunAndStopsEveryRobotOnEveryBusWithItsReason) {
  SimRig rig(2, fast_sim(1));  // real time: the 20 s move is still running when the stop comes
  rig.add(1, 0);
  rig.add(2, 0);
  rig.add(3, 1);
  rig.start();
  Result<TrajectoryReport> report = Error(HostErrc::cancelled);
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    std::map<std::uint16_t, protocol::Trajectory> t;
    for (std::uint16_t id = 1; id <= 3; ++id) t.emplace(id, straight(90, 150, 20));
    TrajectoryOptions o;
    o.settle = 10ms;
    o.on_phase = [&](std::string_view phase) {
      if (phase != "started") return;
      EXPECT_EQ(rig.array->moving().size(), 3u);
      rig.array->request_stop("SIGTERM received");  // as a signal handler does: no co_await
    };
    report = co_await rig.array->run_trajectories(std::move(t), o);
    co_await rig.array->close();  // waits for the stop running in the background
  });
  ASSERT_TRUE(report.has_value()) << report.error().message();
  const auto& rep = report.value();
  EXPECT_TRUE(rep.started);
  EXPECT_FALSE(rep.completed);
  EXPECT_EQ(rep.outcome, "stopped: SIGTERM received");
  for (const auto& r : rep.robots) {
    EXPECT_EQ(r.state, RobotState::stopped) << r.id << ": " << r.detail;
    EXPECT_EQ(r.detail.find("collision"), std::string::npos) << r.detail;
  }
  EXPECT_TRUE(rig.array->moving().empty());
  const auto& stop = rig.array->last_stop();
  ASSERT_TRUE(stop.has_value());
  EXPECT_EQ(stop->reason, "SIGTERM received");
  EXPECT_EQ(stop->buses_sent(), 2u);
  EXPECT_EQ(stop->robots_reached(), 3u);
  EXPECT_EQ(stop->moving_reached(), 3u);
  EXPECT_NE(stop->to_text().find("stopped 3 robots"), std::string::npos) << stop->to_text();
  // The robots themselves: stopped on the way, far from the end of the move.
  for (std::uint16_t id = 1; id <= 3; ++id) {
    EXPECT_FALSE(rig.model(id).moving()) << id;
    EXPECT_LT(rig.model(id).physical_deg(sim::Arm::alpha), 45.0) << id;
  }
}

TEST(SpeedCheck, AStraightMoveNeedsItsLongestArmTravelOverTheArmSpeed) {
  const auto limits = plan::SpeedLimits::from_motor(kMaxMotorRpm, kGearRatio);  // 30 deg/s
  EXPECT_DOUBLE_EQ(limits.alpha_deg_s, 30.0);
  const auto fast = check_speed(straight(300, 180, 2), {0, 180}, limits);
  EXPECT_FALSE(fast.feasible());
  EXPECT_NEAR(fast.shortest_duration_s(), 10.0, 0.01);
  EXPECT_DOUBLE_EQ(feasible_duration_s(fast.shortest_duration_s()), 10.1);  // 0.5 % margin, rounded up
  const auto slow = check_speed(straight(300, 180, 12), {0, 180}, limits);
  EXPECT_TRUE(slow.feasible());
  // The first segment runs from where the robot stands: a robot far from the path's start is
  // too fast even when the path itself is slow.
  EXPECT_FALSE(check_speed(straight(10, 180, 10), {200, 180}, limits).feasible());
}

TEST(SpeedCheck, TheSlowestRobotNamesTheDurationEveryRobotCanMake) {
  const auto limits = plan::SpeedLimits::from_motor(3000, 1000);  // the cold policy's 18 deg/s
  std::map<std::uint16_t, protocol::Trajectory> t{{1, straight(90, 180, 4)}, {2, straight(180, 180, 4)}, {3, straight(9, 180, 4)}};
  std::map<std::uint16_t, ArmAngles> starts{{1, {0, 180}}, {2, {0, 180}}, {3, {0, 180}}};
  const auto slowest = slowest_robot(t, starts, limits);
  ASSERT_TRUE(slowest.has_value());
  EXPECT_EQ(slowest->id, 2);
  EXPECT_NEAR(slowest->needed_s, 10.0, 0.01);
  EXPECT_EQ(slowest->too_fast, 2u);
}

TEST(SpeedCheck, ARunWithSpeedLimitsUploadsNothingWhenARobotIsTooFastAndSaysOncePerRobot) {
  SimRig rig(1);
  for (std::uint16_t id = 1; id <= 6; ++id) rig.add(id, 0);
  rig.start();
  Result<TrajectoryReport> report = Error(HostErrc::cancelled);
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    std::map<std::uint16_t, protocol::Trajectory> t;
    // Robots 4, 5, 6 would need 10 s for 300 deg at 30 deg/s; 1, 2, 3 make it in 2 s.
    for (std::uint16_t id = 1; id <= 6; ++id) t.emplace(id, straight(id <= 3 ? 20 : 300, 180, 2));
    TrajectoryOptions o;
    o.settle = 10ms;
    o.speed_limits = plan::SpeedLimits::from_motor(kMaxMotorRpm, kGearRatio);
    report = co_await rig.array->run_trajectories(std::move(t), o);
  });
  ASSERT_TRUE(report.has_value()) << report.error().message();
  const auto& rep = report.value();
  EXPECT_FALSE(rep.started);
  EXPECT_EQ(rep.in_state(RobotState::not_ready), (std::vector<std::uint16_t>{4, 5, 6}));
  EXPECT_EQ(rep.in_state(RobotState::withdrawn), (std::vector<std::uint16_t>{1, 2, 3}));
  EXPECT_NE(rep.find(4)->detail.find("needs at least 10.1 s"), std::string::npos) << rep.find(4)->detail;
  // Each failure once, on its own robot's line: no line lists the other robots' ids.
  EXPECT_EQ(rep.outcome, "not started: 3 of 6 positioners failed the checks or the upload (each listed once below)");
  const std::regex other_ids(R"(\b[456]\b)");
  for (std::uint16_t id = 1; id <= 3; ++id)
    EXPECT_FALSE(std::regex_search(rep.find(id)->detail, other_ids)) << rep.find(id)->detail;
  for (std::uint16_t id = 1; id <= 6; ++id) {
    EXPECT_FALSE(rig.model(id).moving()) << id;
    EXPECT_FALSE(rig.model(id).status().has(protocol::StatusBit::trajectory_alpha_received)) << id;
  }
}

TEST(StopRequest, ARobotTheRunStopsWatchingIsStoppedNotLeftMoving) {
  ArrayOptions ao = fast_array();
  ao.client.timeout = 100ms;
  auto so = fast_sim(1);  // real time: robot 2's 20 s move is still running when the host gives up
  // Robot 2's status replies are lost once the run watches it (discovery and the check read it first).
  can::FaultRule lost;
  lost.action = can::FaultRule::Action::drop;
  lost.match = can::Filter{(std::uint32_t{2} << 18) | (std::uint32_t{protocol::number(protocol::CommandId::get_status)} << 10),
                           0x1FFFFC00u, can::Filter::Format::extended};
  lost.skip = 2;
  lost.count = std::numeric_limits<std::uint64_t>::max();
  so.reply_faults.rules.push_back(lost);
  SimRig rig(1, so, ao);
  rig.add(1, 0);
  rig.add(2, 0);
  rig.start();
  Result<TrajectoryReport> report = Error(HostErrc::cancelled);
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    std::map<std::uint16_t, protocol::Trajectory> t{{1, straight(5, 180, 1)}, {2, straight(90, 150, 20)}};
    TrajectoryOptions o;
    o.settle = 10ms;
    report = co_await rig.array->run_trajectories(std::move(t), o);
  });
  ASSERT_TRUE(report.has_value()) << report.error().message();
  const auto* r2 = report.value().find(2);
  ASSERT_NE(r2, nullptr);
  EXPECT_EQ(r2->state, RobotState::timeout) << r2->detail;
  EXPECT_NE(r2->detail.find("TRAJECTORY_ABORT sent"), std::string::npos) << r2->detail;
  EXPECT_FALSE(rig.model(2).moving());
  EXPECT_LT(rig.model(2).physical_deg(sim::Arm::alpha), 45.0);
}

TEST(StopRequest, AGotoTheHostGivesUpOnIsAbortedNotLeftMoving) {
  ArrayOptions ao = fast_array();
  ao.client.timeout = 100ms;
  auto so = fast_sim(1);  // real time: a 90 deg go-to at 12 deg/s takes 7.5 s
  // Status replies are lost after discovery's read: the host cannot see the move end.
  can::FaultRule lost;
  lost.action = can::FaultRule::Action::drop;
  lost.match = can::Filter{(std::uint32_t{1} << 18) | (std::uint32_t{protocol::number(protocol::CommandId::get_status)} << 10),
                           0x1FFFFC00u, can::Filter::Format::extended};
  lost.skip = 1;
  lost.count = std::numeric_limits<std::uint64_t>::max();
  so.reply_faults.rules.push_back(lost);
  SimRig rig(1, so, ao);
  rig.add(1, 0);
  rig.start();
  Result<Array::MoveResults> moved = Error(HostErrc::cancelled);
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    std::map<std::uint16_t, ArmAngles> target;  // named: gcc 12 and braced temporaries in co_await
    target[1] = ArmAngles{90, 180};
    moved = co_await rig.array->goto_absolute(std::move(target));
  });
  ASSERT_TRUE(moved.has_value()) << moved.error().message();
  const auto& r1 = moved.value().at(1);
  ASSERT_FALSE(r1.has_value());
  EXPECT_EQ(r1.error(), HostErrc::timeout);
  EXPECT_NE(r1.error().detail.find("TRAJECTORY_ABORT sent"), std::string::npos) << r1.error().message();
  EXPECT_FALSE(rig.model(1).moving());
  EXPECT_LT(rig.model(1).physical_deg(sim::Arm::alpha), 45.0);
}

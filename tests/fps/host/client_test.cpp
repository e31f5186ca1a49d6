// The blocking fps::Client against an in-process simulated plane (fps::sim::SimulatedPlane), over
// the real CAN@net TCP transport on loopback: discovery, status, moves, plan-and-move, the
// collision lock, stops and the call timeout.
#include "axon/fps/host/client.hpp"
#include "axon/fps/host/error.hpp"
#include "axon/fps/plan/error.hpp"
#include "axon/fps/sim/simulated_plane.hpp"

#include "axon/fps/plan/layout_model.hpp"
#include "axon/fps/plan/safe_zone.hpp"
#include "axon/fps/plan/stop_sweep.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <iostream>
#include <thread>

namespace axon::fps {
namespace {

sim::SimulatedPlaneOptions fast_plane() {
  sim::SimulatedPlaneOptions o;
  o.time_scale = 20;
  o.plc = false;
  return o;
}

ClientConfig fast_client() {
  ClientConfig c;
  c.poll_interval_s = 0.02;
  c.discover_window_s = 0.3;
  c.call_timeout_s = 60;
  return c;
}

double error_deg(const Angles& a, const Angles& b) { return std::max(std::abs(a.alpha - b.alpha), std::abs(a.beta - b.beta)); }

class ClientOnPlane : public ::testing::Test {
 protected:
  void SetUp() override {
    fps.open(plane.plane());
    robots = fps.discover();
  }
  sim::SimulatedPlane plane{"benchtop", fast_plane()};
  Client fps{fast_client()};
  std::vector<RobotStatus> robots;
};

TEST_F(ClientOnPlane, DiscoversEveryRobotOfTheLayoutReady) {
  ASSERT_EQ(robots.size(), 6u);
  for (const auto& r : robots) {
    EXPECT_TRUE(r.ready) << r.id << ": " << r.state;
    EXPECT_FALSE(r.firmware.empty());
  }
  const auto table = fps.status();
  ASSERT_EQ(table.size(), 6u);
  ASSERT_TRUE(table[0].position.has_value());
  EXPECT_NEAR(table[0].position->beta, 180.0, 0.5);
}

TEST_F(ClientOnPlane, GotoAbsoluteLeavesTheArmsAtTheTarget) {
  const auto out = fps.goto_absolute({{3, {30, 150}}});
  ASSERT_TRUE(out.completed) << out.summary;
  ASSERT_NE(out.find(3), nullptr);
  EXPECT_LT(error_deg(*out.find(3)->reached, {30, 150}), 0.1);
  EXPECT_LT(error_deg(*plane.arms(3), {30, 150}), 0.1);
}

TEST_F(ClientOnPlane, RunTrajectoriesMovesEveryRobotTogether) {
  std::map<std::uint16_t, ArmPath> paths;
  for (std::uint16_t id : {1, 2}) paths[id] = ArmPath{{{20, 2.0}, {40, 4.0}}, {{170, 4.0}}};
  const auto out = fps.run_trajectories(paths);
  ASSERT_TRUE(out.completed) << out.summary;
  for (std::uint16_t id : {1, 2}) EXPECT_LT(error_deg(*plane.arms(id), {40, 170}), 0.1);
}

TEST_F(ClientOnPlane, PlanAndMoveTakesEveryRobotToItsTargetWithoutCollisions) {
  std::map<std::uint16_t, Angles> targets;
  for (std::uint16_t id = 1; id <= 6; ++id) targets[id] = {60.0 + 10.0 * id, 160};
  const auto out = fps.plan_and_move(targets);
  EXPECT_TRUE(out.plan.verified);
  EXPECT_EQ(out.plan.not_reached, 0u) << out.plan.notes;
  ASSERT_TRUE(out.moved);
  ASSERT_TRUE(out.move.completed) << out.move.summary;
  for (const auto& [id, target] : targets) EXPECT_LT(error_deg(*plane.arms(id), target), 0.1) << id;
  EXPECT_EQ(plane.collisions(), 0u);
}

TEST_F(ClientOnPlane, ACollisionLocksTheClientUntilUnlock) {
  plane.inject_collision(4);
  for (int i = 0; i < 200 && !fps.locked(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_TRUE(fps.locked());
  EXPECT_NE(fps.lock_reason().find("4"), std::string::npos) << fps.lock_reason();
  try {
    fps.goto_absolute({{1, {10, 170}}});
    FAIL() << "a move went out while the array was locked";
  } catch (const Exception& e) {
    EXPECT_EQ(e.code(), host::HostErrc::locked) << e.what();
  }
  const auto u = fps.unlock();
  EXPECT_FALSE(fps.locked());
  EXPECT_EQ(u.acknowledged.size(), 6u);
  EXPECT_TRUE(fps.goto_absolute({{1, {10, 170}}}).completed);
}

TEST_F(ClientOnPlane, EmergencyStopLocksAndReachesEveryBus) {
  const auto stop = fps.emergency_stop("test");
  EXPECT_EQ(stop.buses_sent, stop.buses);
  EXPECT_EQ(stop.robots_reached, 6u);
  EXPECT_TRUE(fps.locked());
  fps.unlock();
  EXPECT_FALSE(fps.locked());
}

TEST_F(ClientOnPlane, GoToDatumsDrivesIntoTheHardStopsAndReportsWhereTheRobotStands) {
  ASSERT_TRUE(fps.goto_absolute({{3, {30, 150}}}).completed);
  const Angles at = fps.go_to_datums(3);
  const auto truth = plane.arms(3);
  ASSERT_TRUE(truth.has_value());
  EXPECT_LT(error_deg(at, *truth), 0.1);
  EXPECT_GT(error_deg(at, {30, 150}), 1.0) << "the arms did not leave where they stood";
  const auto table = fps.status();
  const auto row = std::find_if(table.begin(), table.end(), [](const RobotStatus& r) { return r.id == 3; });
  ASSERT_NE(row, table.end());
  EXPECT_TRUE(row->ready) << row->state;
}

// With the layout known, a datum search whose way to the hard stops passes a neighbour is refused
// before anything moves, naming the neighbour (protocol document 5.3.11: a collision on the way
// would be taken for the stop).
TEST_F(ClientOnPlane, ADatumSearchWhoseWayToTheStopsIsBlockedIsRefusedNamingTheNeighbour) {
  const auto model = plan::model_from_layout(plane.plane()).value();
  const auto idx = model.index_of(3).value();
  std::vector<plan::Pose> poses(model.size());
  for (const auto& r : fps.status())
    if (r.position) poses[model.index_of(r.id).value()] = {r.position->alpha, r.position->beta};
  auto clear = [&] {
    std::vector<plan::Segment> segs(model.size());
    std::vector<plan::Contact> contacts;
    model.segments(poses, segs);
    model.find_contacts(segs, contacts);
    return contacts.empty();
  };
  std::optional<double> blocked;  // an alpha of robot 3 (beta 150) from which the way is blocked
  for (double a = 0; a < 360 && !blocked; a += 10) {
    poses[idx] = {a, 150};
    if (clear() && !plan::check_sweep_to_stops(model, idx, poses).clear) blocked = a;
  }
  ASSERT_TRUE(blocked.has_value());
  ASSERT_TRUE(fps.goto_absolute({{3, {*blocked, 150}}}).completed);
  try {
    fps.go_to_datums(3);
    FAIL() << "a datum search went out through a neighbour";
  } catch (const Exception& e) {
    EXPECT_EQ(e.code(), host::HostErrc::not_ready) << e.what();
    EXPECT_NE(std::string(e.what()).find("may touch robot"), std::string::npos) << e.what();
  }
  const auto truth = plane.arms(3);
  ASSERT_TRUE(truth.has_value());
  EXPECT_LT(error_deg(*truth, {*blocked, 150}), 0.1) << "the robot moved";
}

// The poses the simulator says the robots stand at, in model order.
std::vector<plan::Pose> true_poses(const sim::SimulatedPlane& plane, const plan::CollisionModel& model) {
  std::vector<plan::Pose> poses(model.size());
  for (std::size_t i = 0; i < model.size(); ++i) {
    const auto a = plane.arms(static_cast<std::uint16_t>(model.robot(i).id()));
    if (a) poses[i] = {a->alpha, a->beta};
  }
  return poses;
}

std::vector<plan::Contact> contacts_at(const plan::CollisionModel& model, const std::vector<plan::Pose>& poses) {
  std::vector<plan::Segment> segs(model.size());
  std::vector<plan::Contact> out;
  model.segments(poses, segs);
  model.find_contacts(segs, out);
  return out;
}

// A collision leaves the robot where the simulator's collision check stopped it, inside its
// neighbour's collision buffer (so does a power loss mid-move, for the robots that stop dead).
// After unlock() (which clears the flags), back_off() finds the pair and moves one robot out,
// certified, by the document's 2 degrees or more (9.4.1); the simulator's truth has no contact left.
TEST_F(ClientOnPlane, BackOffSeparatesARobotLeftInsideItsNeighboursBuffer) {
  const auto model = plan::model_from_layout(plane.plane()).value();
  const auto start = true_poses(plane, model);
  // A robot stretched (beta down from folded) until it is 0.3 to 0.5 mm inside one neighbour's
  // buffer and touches nothing else: where it is sent, and where the collision check stops it.
  std::optional<plan::Pose> inside;
  std::size_t moved = 0;
  for (std::size_t r = 0; r < model.size() && !inside; ++r) {
    for (double a = 0; a < 360 && !inside; a += 5) {
      auto poses = start;
      for (double b = 180; b > 0; b -= 0.02) {
        poses[r] = {a, b};
        const auto c = contacts_at(model, poses);
        if (c.empty()) continue;
        if (c.size() != 1 || c[0].kind != plan::Contact::Kind::robot || c[0].clearance_mm < -0.5) break;
        if (c[0].clearance_mm < -0.3) {
          inside = poses[r];
          moved = r;
          break;
        }
      }
    }
  }
  ASSERT_TRUE(inside.has_value());
  const auto id = static_cast<std::uint16_t>(model.robot(moved).id());
  ASSERT_TRUE(fps.goto_absolute({{id, {inside->alpha_deg, 180}}}).completed);  // alpha first, folded
  const auto crash = fps.goto_absolute({{id, {inside->alpha_deg, inside->beta_deg}}});
  EXPECT_FALSE(crash.completed) << crash.summary;
  EXPECT_GE(plane.collisions(), 1u);
  const auto left = contacts_at(model, true_poses(plane, model));
  ASSERT_EQ(left.size(), 1u) << "the simulator stopped the robot outside the buffer";
  try {
    fps.back_off();
    FAIL() << "a back-off went out while the array was locked";
  } catch (const Exception& e) {
    EXPECT_EQ(e.code(), host::HostErrc::locked) << e.what();
  }
  fps.unlock();

  const auto out = fps.back_off();
  EXPECT_TRUE(out.ok) << out.summary;
  ASSERT_EQ(out.contacts_before.size(), 1u) << out.summary;
  ASSERT_EQ(out.moves.size(), 1u) << out.summary;
  EXPECT_TRUE(out.moves[0].moved) << out.moves[0].problem;
  EXPECT_GE(std::abs(out.moves[0].step_deg), 2.0);
  EXPECT_LT(out.moves[0].clearance_before_mm, 0.0);
  EXPECT_TRUE(out.contacts_after.empty()) << out.summary;
  EXPECT_TRUE(contacts_at(model, true_poses(plane, model)).empty()) << "the simulator's robots still touch";
  std::cout << out.summary;
}

// After a collision (the array locks by itself) and unlock(), which clears the flags, the robot
// that reported it moves the document's 2 degrees away.
TEST_F(ClientOnPlane, AfterACollisionAndUnlockTheRobotBacksOffTwoDegrees) {
  plane.inject_collision(3);
  for (int i = 0; i < 500 && !fps.locked(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_TRUE(fps.locked()) << "the collision did not lock the array";
  fps.unlock();
  const auto before = *plane.arms(3);
  const auto out = fps.back_off({3});
  ASSERT_EQ(out.moves.size(), 1u);
  EXPECT_TRUE(out.moves[0].moved) << out.summary;
  EXPECT_TRUE(out.ok) << out.summary;
  EXPECT_NEAR(error_deg(*plane.arms(3), before), 2.0, 0.1);
}

TEST_F(ClientOnPlane, CalibrateRunsMotorsAndDatumsAndSaves) {
  fps.set_call_timeout(120);
  const auto out = fps.calibrate(3);
  EXPECT_TRUE(out.saved);
  EXPECT_TRUE(out.motor_error.has_value());
  EXPECT_TRUE(out.datum_error.has_value());
  EXPECT_FALSE(out.flags.empty());
  CalibrationSteps only_motors;
  only_motors.datums = false;
  only_motors.save = false;
  const auto motors = fps.calibrate(3, only_motors);
  EXPECT_FALSE(motors.saved);
  EXPECT_TRUE(motors.motor_error.has_value());
  EXPECT_FALSE(motors.datum_error.has_value());
}

TEST_F(ClientOnPlane, DatumAndCalibrationAreRefusedWhileLocked) {
  fps.emergency_stop("test");
  for (const auto& call : {std::function<void()>([&] { fps.go_to_datums(1); }), std::function<void()>([&] { fps.calibrate(1); })}) {
    try {
      call();
      ADD_FAILURE() << "a datum or calibration went out while the array was locked";
    } catch (const Exception& e) {
      EXPECT_EQ(e.code(), host::HostErrc::locked) << e.what();
    }
  }
  fps.unlock();
  EXPECT_NO_THROW(fps.go_to_datums(3));
}

TEST_F(ClientOnPlane, BadTargetsAreRefusedWhenNotParked) {
  PlanSettings s;
  s.park_bad_targets = false;
  try {
    fps.plan_and_move({{1, {30, 150}}, {99, {0, 180}}}, s);
    FAIL() << "a target for a robot the layout lacks was accepted";
  } catch (const Exception& e) {
    EXPECT_EQ(e.code(), plan::PlanErrc::bad_target_file) << e.what();
  }
}

// Targets for every robot of the layout: folded, except the first robot, whose arm comes closer
// to a neighbour than both safe zones allow (spec section 11) without touching it.
std::map<std::uint16_t, Angles> targets_with_one_outside_safe_zone(const FocalPlane& layout, std::uint16_t& outside) {
  const auto model = plan::model_from_layout(layout).value();
  std::vector<plan::Pose> poses(model.size(), plan::Pose{10, 170});
  for (double a = 0; a < 360; a += 5) {
    for (double b = 0; b < 180; b += 0.5) {
      poses[0] = {a, b};
      std::vector<plan::Segment> segs(model.size());
      std::vector<plan::Contact> contacts;
      model.segments(poses, segs);
      if (model.find_contacts(segs, contacts) < 0.5) continue;
      const auto r = plan::check_safe_zone(model, poses);
      if (r.issues.size() != 1 || r.issues[0].kind != plan::SafeZoneIssue::Kind::robot_clearance) continue;
      outside = static_cast<std::uint16_t>(r.issues[0].robot);
      std::map<std::uint16_t, Angles> t;
      for (std::size_t i = 0; i < model.size(); ++i)
        t[static_cast<std::uint16_t>(model.robot(i).id())] = {poses[i].alpha_deg, poses[i].beta_deg};
      return t;
    }
  }
  ADD_FAILURE() << "no pose of the first robot is clear but outside the safe zone";
  return {};
}

TEST_F(ClientOnPlane, TargetsOutsideTheSafeZoneAreRefusedBeforeAnythingMoves) {
  std::uint16_t outside = 0;
  const auto targets = targets_with_one_outside_safe_zone(plane.plane(), outside);
  const auto before = *plane.arms(outside);
  PlanSettings s;
  s.refuse_outside_safe_zone = true;
  try {
    fps.plan_and_move(targets, s);
    FAIL() << "targets outside the safe zone were planned and run";
  } catch (const Exception& e) {
    EXPECT_EQ(e.code(), plan::PlanErrc::outside_safe_zone) << e.what();
    EXPECT_NE(std::string(e.what()).find(fmt::format("robot {}: target", outside)), std::string::npos) << e.what();
  }
  EXPECT_LT(error_deg(*plane.arms(outside), before), 0.01);
}

TEST_F(ClientOnPlane, TargetsOutsideTheSafeZoneAreReportedAndRunByDefault) {
  std::uint16_t outside = 0;
  const auto targets = targets_with_one_outside_safe_zone(plane.plane(), outside);
  const auto out = fps.plan_and_move(targets);
  EXPECT_EQ(out.plan.outside_safe_zone, std::vector<std::uint16_t>{outside});
  EXPECT_NE(out.plan.safe_zone.find("mm too close to robot"), std::string::npos) << out.plan.safe_zone;
  ASSERT_TRUE(out.move.completed) << out.move.summary << out.plan.notes;
  EXPECT_LT(error_deg(*plane.arms(outside), targets.at(outside)), 0.1);
}

TEST(Client, ACallThatOverrunsItsTimeoutStopsEveryRobotAndThrows) {
  auto slow = fast_plane();
  slow.time_scale = 2;  // the move takes seconds of wall time
  sim::SimulatedPlane plane("benchtop", slow);
  Client fps(fast_client());
  fps.open(plane.bus_specs());
  ASSERT_EQ(fps.discover().size(), 6u);
  fps.set_call_timeout(0.3);
  try {
    fps.goto_absolute({{2, {180, 90}}});
    FAIL() << "the move finished within 0.2 s";
  } catch (const Exception& e) {
    EXPECT_EQ(e.code(), CoreErrc::timeout) << e.what();
  }
  EXPECT_TRUE(fps.locked());
  EXPECT_GT(error_deg(*plane.arms(2), {180, 90}), 1.0);  // stopped on the way
}

TEST(Client, InterruptFromAnotherThreadStopsEveryRobotAndEndsTheWaitingCall) {
  auto slow = fast_plane();
  slow.time_scale = 2;  // the move takes seconds of wall time
  sim::SimulatedPlane plane("benchtop", slow);
  Client fps(fast_client());
  fps.open(plane.plane());
  ASSERT_EQ(fps.discover().size(), 6u);
  std::thread watchdog([&fps] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    fps.interrupt("watchdog");
  });
  try {
    const auto out = fps.goto_absolute({{2, {180, 90}}});
    EXPECT_FALSE(out.completed) << "the move finished before the interrupt";
  } catch (const Exception& e) {
    EXPECT_EQ(e.code(), host::HostErrc::locked) << e.what();
  }
  watchdog.join();
  EXPECT_TRUE(fps.locked());
  EXPECT_NE(fps.lock_reason().find("watchdog"), std::string::npos) << fps.lock_reason();
  EXPECT_GT(error_deg(*plane.arms(2), {180, 90}), 1.0);  // stopped on the way
}

TEST(Client, OpenedFromBusSpecsPlansOnceGivenTheLayout) {
  sim::SimulatedPlane plane("benchtop", fast_plane());
  Client fps(fast_client());
  fps.open(plane.bus_specs());
  ASSERT_EQ(fps.discover().size(), 6u);
  try {
    fps.plan_and_move({{1, {30, 150}}});
    FAIL() << "planned without a layout";
  } catch (const Exception& e) {
    EXPECT_EQ(e.code(), host::HostErrc::invalid_argument);
  }
  fps.set_layout(plane.plane());
  const auto out = fps.plan_and_move({{1, {30, 150}}});
  EXPECT_TRUE(out.move.completed) << out.move.summary;
  EXPECT_LT(error_deg(*plane.arms(1), {30, 150}), 0.1);
}

TEST(Client, TheVersionByteOrderOptionReachesEveryRobotsRead) {
  sim::SimulatedPlane plane("benchtop", fast_plane());  // robots send the field's order
  auto config = fast_client();
  config.document_version_byte_order = true;
  Client fps(config);
  fps.open(plane.plane());
  const auto robots = fps.discover();
  ASSERT_EQ(robots.size(), 6u);
  for (const auto& r : robots) {
    EXPECT_TRUE(r.firmware.empty()) << r.id << ": " << r.firmware;
    EXPECT_NE(r.error.find("byte order"), std::string::npos) << r.id << ": " << r.error;
  }
}

TEST(Client, CallsBeforeOpenAreErrors) {
  Client fps;
  EXPECT_FALSE(fps.is_open());
  EXPECT_THROW(fps.discover(), Exception);
}

}  // namespace
}  // namespace axon::fps

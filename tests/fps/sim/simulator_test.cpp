// Simulator: robots on a virtual bus answering raw frames from a host node.
#include "axon/can/virtual_bus.hpp"
#include "axon/fps/protocol/message.hpp"
#include "axon/fps/protocol/payloads.hpp"
#include "axon/fps/protocol/trajectory.hpp"
#include "axon/fps/sim/simulator.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/io_context.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <vector>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::sim;
using protocol::CommandId;
using protocol::ResponseCode;
using namespace std::chrono_literals;

namespace {

void run(asio::io_context& io, std::function<asio::awaitable<void>()> body) {
  asio::co_spawn(io, std::move(body), [](std::exception_ptr e) {
    if (e) std::rethrow_exception(e);
  });
  io.run();
  io.restart();
}

can::Frame request(std::uint16_t to, CommandId c, std::uint8_t uid, const protocol::Payload& p = {}) {
  return protocol::make_request(to, c, uid, p).value();
}

// Frames received by `host` until `n` arrived or `timeout` (real time) passed.
asio::awaitable<std::vector<protocol::Message>> collect(can::Bus& host, std::size_t n, core::Duration timeout) {
  std::vector<protocol::Message> out;
  while (out.size() < n) {
    auto f = co_await host.receive(timeout);
    if (!f) break;
    out.push_back(protocol::from_frame(f.value()).value());
  }
  co_return out;
}

// Waits `d` of real time inside a coroutine.
asio::awaitable<void> pause(core::Duration d) {
  asio::steady_timer t(co_await asio::this_coro::executor);
  t.expires_after(d);
  co_await t.async_wait(asio::use_awaitable);
}

struct Rig {
  explicit Rig(SimulatorOptions o = {}) : sim(io.get_executor(), std::move(o)) {
    medium = can::VirtualBus::create(io.get_executor(), "fps0");
    host = medium->attach("host");
  }
  ~Rig() { sim.stop(); }
  PositionerModel* add(std::uint16_t id, double x = 0, double y = 0, PositionerConfig c = {}) {
    c.id = id;
    c.x_mm = x;
    c.y_mm = y;
    return sim.add(c, *medium).value();
  }
  asio::io_context io;
  Simulator sim;
  std::shared_ptr<can::VirtualBus> medium;
  std::unique_ptr<can::Bus> host;
};

}  // namespace

TEST(FpsSimulator, BroadcastGetIdIsAnsweredByEveryRobot) {
  Rig rig;
  for (std::uint16_t id : {12, 3, 7}) rig.add(id);
  rig.sim.start();
  std::vector<protocol::Message> got;
  run(rig.io, [&]() -> asio::awaitable<void> {
    (void)co_await rig.host->send(request(0, CommandId::get_id, 0));
    got = co_await collect(*rig.host, 3, 2s);
    rig.sim.stop();
  });
  ASSERT_EQ(got.size(), 3u);
  std::vector<std::uint16_t> ids;
  for (const auto& m : got) {
    EXPECT_EQ(m.id.command, 1);
    EXPECT_EQ(m.id.uid, 0);
    ids.push_back(m.id.positioner);
  }
  // The robots answer as they finish processing; which arbitration round each reply joins is
  // up to the scheduler, so compare the set.
  std::sort(ids.begin(), ids.end());
  EXPECT_EQ(ids, (std::vector<std::uint16_t>{3, 7, 12}));
}

TEST(FpsSimulator, UnicastReachesOnlyItsRobot) {
  Rig rig;
  rig.add(1);
  rig.add(2);
  rig.sim.start();
  std::vector<protocol::Message> got;
  run(rig.io, [&]() -> asio::awaitable<void> {
    (void)co_await rig.host->send(request(2, CommandId::get_status, 5));
    got = co_await collect(*rig.host, 2, 100ms);
    rig.sim.stop();
  });
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].id.positioner, 2);
  EXPECT_EQ(got[0].id.uid, 5);
  EXPECT_EQ(got[0].payload.size(), 8u);
}

TEST(FpsSimulator, GoToMovesTheRobotWithTheScaledClock) {
  SimulatorOptions o;
  o.time_scale = 200;  // a 7.6 s move takes about 40 ms
  Rig rig(o);
  auto* robot = rig.add(4);
  rig.sim.start();
  std::vector<protocol::Message> got;
  run(rig.io, [&]() -> asio::awaitable<void> {
    protocol::ArmPositions target{protocol::Angle::from_degrees(90).value(), protocol::Angle::from_degrees(180).value()};
    (void)co_await rig.host->send(request(4, CommandId::go_to_absolute_position, 1, target.encode()));
    got = co_await collect(*rig.host, 1, 2s);
    // Poll the status until the move is over (generous: 5 s real for 7.6 s simulated at 200x).
    for (int i = 0; i < 500 && robot->moving(); ++i) {
      asio::steady_timer t(rig.io);
      t.expires_after(10ms);
      co_await t.async_wait(asio::use_awaitable);
    }
    rig.sim.stop();
  });
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].id.response, ResponseCode::accepted);
  EXPECT_FALSE(robot->moving());
  EXPECT_NEAR(robot->reported_deg(Arm::alpha), 90.0, 1e-6);
}

TEST(FpsSimulator, FloodingOneRobotOverflowsItsReceiveBuffer) {
  SimulatorOptions o;
  o.processing_delay = 1ms;
  Rig rig(o);
  rig.add(9);  // 16 frames of buffer
  rig.sim.start();
  std::vector<protocol::Message> got;
  run(rig.io, [&]() -> asio::awaitable<void> {
    // Without wire pacing the medium delivers the whole burst at once, faster than any robot.
    for (int i = 0; i < 100; ++i) {
      (void)co_await rig.host->send(request(9, CommandId::get_status, static_cast<std::uint8_t>(1 + i % 63)));
    }
    got = co_await collect(*rig.host, 100, 300ms);
    rig.sim.stop();
  });
  const auto lost = rig.sim.endpoint(9)->stats().rx_dropped;
  EXPECT_GT(lost, 0u);
  EXPECT_EQ(got.size() + lost, 100u);
  EXPECT_LE(got.size(), 17u);  // the buffer plus the one frame in processing
  EXPECT_EQ(rig.sim.receive_overflows(), lost);
}

TEST(FpsSimulator, AHostThatWaitsForRepliesLosesNothing) {
  Rig rig;
  rig.add(9);
  rig.sim.start();
  int answered = 0;
  run(rig.io, [&]() -> asio::awaitable<void> {
    for (int i = 0; i < 100; ++i) {
      (void)co_await rig.host->send(request(9, CommandId::get_status, static_cast<std::uint8_t>(1 + i % 63)));
      if (auto f = co_await rig.host->receive(1s)) ++answered;
    }
    rig.sim.stop();
  });
  EXPECT_EQ(answered, 100);
  EXPECT_EQ(rig.sim.receive_overflows(), 0u);
}

TEST(FpsSimulator, NonFpsFramesAreCountedAndIgnored) {
  Rig rig;
  rig.add(9);
  rig.sim.start();
  std::vector<protocol::Message> got;
  run(rig.io, [&]() -> asio::awaitable<void> {
    (void)co_await rig.host->send(can::Frame::remote(9u << 18 | 1u << 10, can::IdFormat::extended, 0).value());
    (void)co_await rig.host->send(can::Frame::standard(0x123, {}).value());  // filtered by the robot
    got = co_await collect(*rig.host, 1, 100ms);
    rig.sim.stop();
  });
  EXPECT_TRUE(got.empty());
  EXPECT_EQ(rig.sim.stats().non_fps_frames, 1u);
}

namespace {

// A manual clock moved in steps of `dt` with a simulator step after each, `n` times; collects
// whatever reaches the host meanwhile.
asio::awaitable<std::vector<protocol::Message>> drive(Rig& rig, core::ManualClock& clock, core::Duration dt, int n) {
  std::vector<protocol::Message> out;
  for (int i = 0; i < n; ++i) {
    clock.advance(dt);
    rig.sim.step();
    co_await pause(0ms);  // let the robots' senders run
    while (auto f = rig.host->try_receive()) out.push_back(protocol::from_frame(*f).value());
  }
  co_return out;
}

protocol::Payload degrees(double a, double b) {
  return protocol::ArmPositions{protocol::Angle::from_degrees(a).value(), protocol::Angle::from_degrees(b).value()}
      .encode();
}

}  // namespace

TEST(FpsSimulator, NeighboursCollideWhenTheirBetaArmsMeet) {
  core::ManualClock clock;
  SimulatorOptions o;
  o.clock = &clock;
  Rig rig(o);
  // Two robots one hex pitch apart, both folded. Stretching A's beta arm along +x sweeps it into
  // B's folded beta arm.
  auto* a = rig.add(1, 0, 0);
  auto* b = rig.add(2, 22.4, 0);
  rig.sim.start();
  std::vector<protocol::Message> seen;
  run(rig.io, [&]() -> asio::awaitable<void> {
    (void)co_await rig.host->send(request(1, CommandId::go_to_absolute_position, 1, degrees(0, 0)));
    auto reply = co_await collect(*rig.host, 1, 1s);
    EXPECT_EQ(reply.size(), 1u);
    seen = co_await drive(rig, clock, 100ms, 200);  // 20 s of simulated time
    rig.sim.stop();
  });
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].id.positioner, 1);
  EXPECT_EQ(seen[0].id.command, 18);
  EXPECT_EQ(seen[0].id.uid, 0);
  EXPECT_EQ(seen[0].id.response, ResponseCode::beta_collision);
  EXPECT_FALSE(a->moving());
  EXPECT_TRUE(a->status().has(protocol::StatusBit::collision_beta));
  EXPECT_GT(a->physical_deg(Arm::beta), 0);  // stopped on the way
  EXPECT_FALSE(b->status().collided());      // B stood still
  EXPECT_EQ(rig.sim.stats().neighbour_collisions, 1u);
  EXPECT_EQ(rig.sim.stats().unsolicited, 1u);
  // The capsules touch (segments < 4 mm apart) but the step resolution keeps them from passing
  // through.
  const auto& model = rig.sim.collision_model();
  ASSERT_EQ(model.robot_pairs().size(), 1u);
  const std::vector<plan::Pose> poses{{a->physical_deg(Arm::alpha), a->physical_deg(Arm::beta)}, {0, 180}};
  std::vector<Segment> segs(2);
  model.segments(poses, segs);
  const double c = model.clearance(model.robot_pairs()[0], segs);
  EXPECT_LT(c, 0.0);
  EXPECT_GT(c, -2.0);
}

TEST(FpsSimulator, NeighbourCheckCanBeSwitchedOff) {
  core::ManualClock clock;
  SimulatorOptions o;
  o.clock = &clock;
  o.neighbour_collisions = false;
  Rig rig(o);
  auto* a = rig.add(1, 0, 0);
  rig.add(2, 22.4, 0);
  rig.sim.start();
  std::vector<protocol::Message> seen;
  run(rig.io, [&]() -> asio::awaitable<void> {
    (void)co_await rig.host->send(request(1, CommandId::go_to_absolute_position, 1, degrees(0, 0)));
    (void)co_await collect(*rig.host, 1, 1s);
    seen = co_await drive(rig, clock, 100ms, 200);
    rig.sim.stop();
  });
  EXPECT_TRUE(seen.empty());
  EXPECT_NEAR(a->physical_deg(Arm::beta), 0, 1e-9);
}

TEST(FpsSimulator, ObstacleStopsTheRobotThatRunsIntoIt) {
  core::ManualClock clock;
  SimulatorOptions o;
  o.clock = &clock;
  Rig rig(o);
  auto* a = rig.add(1, 0, 0);
  // A fiducial-like point 3 mm in radius, 20 mm out along +x.
  rig.sim.add_obstacle(Obstacle{"fiducial", {{20, 0}, {20, 0}}, 3.0});
  rig.sim.start();
  std::vector<protocol::Message> seen;
  run(rig.io, [&]() -> asio::awaitable<void> {
    (void)co_await rig.host->send(request(1, CommandId::go_to_absolute_position, 1, degrees(0, 0)));
    (void)co_await collect(*rig.host, 1, 1s);
    seen = co_await drive(rig, clock, 100ms, 200);
    rig.sim.stop();
  });
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].id.response, ResponseCode::beta_collision);
  EXPECT_EQ(rig.sim.stats().obstacle_collisions, 1u);
  EXPECT_GT(a->physical_deg(Arm::beta), 0);
}

TEST(FpsSimulator, ForcedCollisionIsSentOnTheBus) {
  Rig rig;
  rig.add(5);
  rig.sim.start();
  std::vector<protocol::Message> seen;
  run(rig.io, [&]() -> asio::awaitable<void> {
    EXPECT_TRUE(rig.sim.force_collision(5, Arm::alpha).has_value());
    EXPECT_FALSE(rig.sim.force_collision(6, Arm::alpha).has_value());
    seen = co_await collect(*rig.host, 1, 1s);
    rig.sim.stop();
  });
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].id.command, 18);
  EXPECT_EQ(seen[0].id.response, ResponseCode::alpha_collision);
}

TEST(FpsSimulator, ReplyFaultPlanDropsAndDuplicates) {
  SimulatorOptions o;
  can::FaultRule drop;
  drop.action = can::FaultRule::Action::drop;
  drop.match = can::Filter{0x00040400, 0x1FFFFC00, can::Filter::Format::extended};  // robot 1, GET_ID
  drop.count = 1;
  can::FaultRule dup;
  dup.action = can::FaultRule::Action::duplicate;
  dup.match = can::Filter{0x00040C00, 0x1FFFFC00, can::Filter::Format::extended};  // robot 1, GET_STATUS
  o.reply_faults.rules = {drop, dup};
  Rig rig(o);
  rig.add(1);
  rig.sim.start();
  std::vector<protocol::Message> got;
  run(rig.io, [&]() -> asio::awaitable<void> {
    (void)co_await rig.host->send(request(1, CommandId::get_id, 1));
    (void)co_await rig.host->send(request(1, CommandId::get_id, 2));
    (void)co_await rig.host->send(request(1, CommandId::get_status, 3));
    got = co_await collect(*rig.host, 4, 200ms);
    rig.sim.stop();
  });
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].id.uid, 2);  // the first GET_ID reply was lost
  EXPECT_EQ(got[1].id.uid, 3);
  EXPECT_EQ(got[2].id.uid, 3);  // and the status came twice
  EXPECT_EQ(rig.sim.stats().faults_dropped, 1u);
  EXPECT_EQ(rig.sim.stats().faults_duplicated, 1u);
}

TEST(FpsSimulator, ReplyFaultPlanDelaysAReply) {
  SimulatorOptions o;
  can::FaultRule delay;
  delay.action = can::FaultRule::Action::delay;
  delay.match = can::Filter{0x00040400, 0x1FFFFC00, can::Filter::Format::extended};  // robot 1, GET_ID
  delay.count = 1;
  delay.delay = 50ms;
  o.reply_faults.rules = {delay};
  Rig rig(o);
  rig.add(1);
  rig.sim.start();
  std::vector<protocol::Message> got;
  run(rig.io, [&]() -> asio::awaitable<void> {
    (void)co_await rig.host->send(request(1, CommandId::get_id, 1));
    (void)co_await rig.host->send(request(1, CommandId::get_status, 2));
    got = co_await collect(*rig.host, 2, 2s);
    rig.sim.stop();
  });
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].id.uid, 2);  // the status overtook the delayed id
  EXPECT_EQ(got[1].id.uid, 1);
  EXPECT_EQ(rig.sim.stats().faults_delayed, 1u);
}

TEST(FpsSimulator, PowerCycleIntoTheBootloaderKeepsTheRealTimeWindow) {
  SimulatorOptions o;
  o.time_scale = 50;
  Rig rig(o);
  auto* robot = rig.add(3);
  EXPECT_EQ(robot->config().bootloader_timeout, 500s);  // 10 s for the host at 50x
  EXPECT_EQ(robot->config().watchdog_timeout, 1500s);
  EXPECT_EQ(robot->config().hall_wake_up, 5s);           // physical: scaled
  rig.sim.start();
  std::vector<protocol::Message> got;
  run(rig.io, [&]() -> asio::awaitable<void> {
    rig.sim.power_cycle(/*sync_line_low=*/true);
    (void)co_await rig.host->send(request(0, CommandId::get_firmware_version, 0));
    got = co_await collect(*rig.host, 1, 1s);
    rig.sim.stop();
  });
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(protocol::FirmwareVersion::decode(got[0].payload.span()).value().to_string(), "03.80.01");
  EXPECT_EQ(robot->run_state(), RunState::bootloader);
}

TEST(FpsSimulator, ScaledProtocolTimeoutsWhenAsked) {
  SimulatorOptions o;
  o.time_scale = 50;
  o.scale_protocol_timeouts = true;
  Rig rig(o);
  EXPECT_EQ(rig.add(3)->config().bootloader_timeout, 10s);
}

TEST(FpsSimulator, SyncLineStartsLoadedTrajectoriesAndRepliesWithUidZero) {
  Rig rig;
  auto* a = rig.add(1);
  rig.add(2);
  rig.sim.start();
  std::vector<protocol::Message> got;
  run(rig.io, [&]() -> asio::awaitable<void> {
    const std::vector<protocol::ArmPoint> alpha{{10, 100}};
    const auto t = protocol::Trajectory::from_physical(alpha, {}).value();
    const auto frames = protocol::upload_frames(1, t).value();
    for (const auto& f : frames) {
      (void)co_await rig.host->send(f);
      auto r = co_await rig.host->receive(1s);
      EXPECT_TRUE(r.has_value() && protocol::from_frame(r.value()).value().id.response == ResponseCode::accepted);
    }
    rig.sim.set_sync_line(true);  // held: the tick passes the robots' second look
    got = co_await collect(*rig.host, 2, 1s);
    rig.sim.stop();
  });
  ASSERT_EQ(got.size(), 2u);
  for (const auto& m : got) {
    EXPECT_EQ(m.id.command, 14);
    EXPECT_EQ(m.id.uid, 0);
    EXPECT_EQ(m.id.response, ResponseCode::accepted);  // robot 2 had nothing loaded and stays
  }
  EXPECT_TRUE(a->moving());
  EXPECT_EQ(rig.sim.stats().unsolicited, 2u);
}

TEST(FpsSimulator, RefusesDuplicateIdsAndBadOptions) {
  Rig rig;
  rig.add(4);
  PositionerConfig c;
  c.id = 4;
  EXPECT_FALSE(rig.sim.add(c, *rig.medium).has_value());
  c.id = 0;
  EXPECT_FALSE(rig.sim.add(c, *rig.medium).has_value());
  SimulatorOptions o;
  o.time_scale = 0;
  EXPECT_THROW(Simulator(rig.io.get_executor(), o), Exception);
}

namespace {

// Uploads `t` to robot `id` from the host node, every reply checked.
asio::awaitable<void> upload(Rig& rig, std::uint16_t id, protocol::Trajectory t) {
  const auto frames = protocol::upload_frames(id, t).value();
  for (const auto& f : frames) {
    (void)co_await rig.host->send(f);
    auto r = co_await rig.host->receive(1s);
    EXPECT_TRUE(r.has_value());
    if (r) {
      EXPECT_EQ(protocol::from_frame(r.value()).value().id.response, ResponseCode::accepted);
    }
  }
}

// The sync line up, the manual clock to the robots' second look and a step: every loaded robot
// starts then. Returns their replies.
asio::awaitable<std::vector<protocol::Message>> sync_start(Rig& rig, core::ManualClock& clock) {
  rig.sim.set_sync_line(true);
  clock.advance(std::chrono::duration_cast<core::Duration>(PositionerConfig{}.sync_recheck));
  rig.sim.step();
  rig.sim.set_sync_line(false);
  co_return co_await collect(*rig.host, 2, 1s);
}

protocol::Trajectory alpha_to(double deg, double seconds) {
  const std::vector<protocol::ArmPoint> alpha{{deg, seconds}};
  return protocol::Trajectory::from_physical(alpha, {}).value();
}

// Two neighbours, beta arms straight out, that turn their alpha arms 120 deg the same way at the
// same rate over 10 s, A (at the origin) 45 deg behind B (one pitch along +x). At equal instants
// the capsules stay at least 4.7 mm apart (the buffers need 4 mm); with A a second or more ahead
// of B, A's arm crosses where B's arm still is.
struct Chase {
  static constexpr double a_from = 225, a_to = 345, b_from = 180, b_to = 300, seconds = 10, pitch = 22.4;
  static double distance(double ta, double tb) {
    const auto at = [](double from, double to, double t) { return from + (to - from) * std::clamp(t / seconds, 0.0, 1.0); };
    const plan::Positioner a({1, {0, 0}}, {}), b({2, {pitch, 0}}, {});
    return plan::segment_distance(a.collision_segment({at(a_from, a_to, ta), 0}), b.collision_segment({at(b_from, b_to, tb), 0}));
  }
};

}  // namespace

TEST(FpsSimulator, ChaseGeometryIsClearOnlyAtEqualInstants) {
  double same = 1e9, skewed = 1e9;
  for (int i = 0; i <= 100; ++i) {
    const double t = Chase::seconds * i / 100;
    same = std::min(same, Chase::distance(t, t));
    skewed = std::min(skewed, Chase::distance(t + 2, t));
  }
  EXPECT_GT(same, 4.5);
  EXPECT_LT(skewed, 1.0);
}

// Under load the tick that moves every robot came late, while the host's poll of one robot moved
// that robot alone to the present: the collision check then compared it, seconds ahead, with
// neighbours still in the past, and reported collisions that one sync edge and one clock (the
// hardware) never produce. Every robot must be seen at the same instant.
TEST(FpsSimulator, ALateTickComparesEveryRobotAtTheSameInstant) {
  core::ManualClock clock;
  SimulatorOptions o;
  o.clock = &clock;
  o.tick = 1h;  // steps only by hand: the late tick is the test's
  Rig rig(o);
  PositionerConfig ca, cb;
  ca.start_position_deg = {{Chase::a_from, 0}};
  cb.start_position_deg = {{Chase::b_from, 0}};
  auto* a = rig.add(1, 0, 0, ca);
  auto* b = rig.add(2, Chase::pitch, 0, cb);
  rig.sim.start();
  std::vector<protocol::Message> seen;
  run(rig.io, [&]() -> asio::awaitable<void> {
    co_await upload(rig, 1, alpha_to(Chase::a_to, Chase::seconds));
    co_await upload(rig, 2, alpha_to(Chase::b_to, Chase::seconds));
    const auto acks = co_await sync_start(rig, clock);
    EXPECT_EQ(acks.size(), 2u);
    seen = co_await drive(rig, clock, 100ms, 40);  // 4 s, ticks on time
    clock.advance(2s);                             // then no tick for 2 s
    (void)co_await rig.host->send(request(1, CommandId::get_current_position, 1));  // but A is polled
    const auto reply = co_await collect(*rig.host, 1, 1s);
    EXPECT_EQ(reply.size(), 1u);
    const auto rest = co_await drive(rig, clock, 100ms, 50);  // the late tick, then to the end
    seen.insert(seen.end(), rest.begin(), rest.end());
    rig.sim.stop();
  });
  EXPECT_EQ(rig.sim.stats().neighbour_collisions, 0u);
  for (const auto& m : seen) EXPECT_NE(m.id.command, 18) << "collision reported by robot " << m.id.positioner;
  EXPECT_NEAR(a->physical_deg(Arm::alpha), Chase::a_to, 1e-6);
  EXPECT_NEAR(b->physical_deg(Arm::alpha), Chase::b_to, 1e-6);
}

// The sync line reaches every robot on the same edge: each starts its trajectory at that instant,
// however long ago the simulator last moved it.
TEST(FpsSimulator, SyncEdgeStartsEveryRobotAtTheSameInstant) {
  core::ManualClock clock;
  SimulatorOptions o;
  o.clock = &clock;
  o.tick = 1h;
  Rig rig(o);
  PositionerConfig ca, cb;
  ca.start_position_deg = {{Chase::a_from, 0}};
  cb.start_position_deg = {{Chase::b_from, 0}};
  auto* a = rig.add(1, 0, 0, ca);
  auto* b = rig.add(2, Chase::pitch, 0, cb);
  rig.sim.start();
  run(rig.io, [&]() -> asio::awaitable<void> {
    co_await upload(rig, 1, alpha_to(Chase::a_to, Chase::seconds));
    clock.advance(3s);  // B is answered 3 s later than A
    co_await upload(rig, 2, alpha_to(Chase::b_to, Chase::seconds));
    clock.advance(1s);
    EXPECT_EQ((co_await sync_start(rig, clock)).size(), 2u);
    (void)co_await drive(rig, clock, 100ms, 50);  // half of the move
    rig.sim.stop();
  });
  // Both half way: 60 deg from where each started.
  EXPECT_NEAR(a->physical_deg(Arm::alpha), Chase::a_from + 60, 1e-6);
  EXPECT_NEAR(b->physical_deg(Arm::alpha), Chase::b_from + 60, 1e-6);
}

// Interface document 6: a pulse shorter than the robots' second look after the rising edge is
// jitter and starts nothing; a line held past it starts every loaded robot at that instant, each
// replying as to START_TRAJECTORY with uid 0.
TEST(FpsSimulator, SyncLineStartsOnlyWhenStillHighAtTheSecondLook) {
  core::ManualClock clock;
  SimulatorOptions o;
  o.clock = &clock;
  o.tick = 1h;
  Rig rig(o);
  auto* a = rig.add(1);
  auto* b = rig.add(2, 30, 0);
  const auto recheck = std::chrono::duration_cast<core::Duration>(a->config().sync_recheck);
  rig.sim.start();
  run(rig.io, [&]() -> asio::awaitable<void> {
    co_await upload(rig, 1, alpha_to(20, 2));
    co_await upload(rig, 2, alpha_to(40, 2));
    // A glitch: up, and down again 1 ms before the second look.
    rig.sim.set_sync_line(true);
    clock.advance(recheck - 1ms);
    rig.sim.set_sync_line(false);
    (void)co_await drive(rig, clock, 100ms, 10);
    EXPECT_EQ(rig.sim.stats().unsolicited, 0u);  // nothing sent
    EXPECT_FALSE(a->moving());
    EXPECT_FALSE(b->moving());
    // Held: nothing until the second look, then both start.
    rig.sim.set_sync_line(true);
    (void)co_await drive(rig, clock, recheck - 1ms, 1);
    EXPECT_EQ(rig.sim.stats().unsolicited, 0u);
    EXPECT_FALSE(a->moving());
    clock.advance(1ms);
    rig.sim.step();
    EXPECT_TRUE(a->moving());
    EXPECT_TRUE(b->moving());
    const auto seen = co_await collect(*rig.host, 2, 1s);
    EXPECT_EQ(seen.size(), 2u);
    for (const auto& m : seen) {
      EXPECT_EQ(m.id.command, 14);
      EXPECT_EQ(m.id.uid, 0);
      EXPECT_EQ(m.id.response, ResponseCode::accepted);
    }
    rig.sim.set_sync_line(false);
    (void)co_await drive(rig, clock, 100ms, 30);
    rig.sim.stop();
  });
  for (auto* m : {a, b}) {
    EXPECT_EQ(m->counters().sync_glitches, 1u) << "robot " << m->id();
    EXPECT_EQ(m->counters().sync_starts, 1u) << "robot " << m->id();
  }
  EXPECT_NEAR(a->physical_deg(Arm::alpha), 20, 1e-6);
  EXPECT_NEAR(b->physical_deg(Arm::alpha), 40, 1e-6);
  EXPECT_EQ(rig.sim.stats().unsolicited, 2u);
}

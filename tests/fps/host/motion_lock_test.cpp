// The collision lock as one chokepoint: while an array is locked, no command that moves a robot
// leaves the host by any public path (raw requests and calls on Array::client(bus), pipelines,
// broadcasts, triggered broadcasts, broadcast_now, a Positioner built by hand on an array's
// client, the Positioner and Array motion calls); reads, settings and stops still go out, and
// after unlock() the moves go out again. "Leaves the host" is checked on the wire: a listener node
// on each virtual bus records every frame, and a refused command must not appear there at all
// (neither its request nor a reply to it). The commands come from the command table's flags.
#include "fake_device.hpp"
#include "plane_rig.hpp"
#include "sim_rig.hpp"

#include "axon/fps/host/focal_plane_array.hpp"

#include "axon/fps/protocol/commands.hpp"

#include <gtest/gtest.h>

#include <vector>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::host;
using namespace axon::fps::host::testing;
using protocol::CommandId;

namespace {

using Trajectories = std::map<std::uint16_t, protocol::Trajectory>;

// The commands of the table with a given flag.
std::vector<CommandId> commands_where(bool protocol::CommandInfo::*flag) {
  std::vector<CommandId> out;
  for (const auto& c : protocol::kCommands) {
    if (c.*flag) out.push_back(c.id);
  }
  return out;
}
const std::vector<CommandId> kMoving = commands_where(&protocol::CommandInfo::moves);
const std::vector<CommandId> kReads = commands_where(&protocol::CommandInfo::read_only);

// A request payload of the size the command table asks for (zeros: a move to (0, 0), a
// trajectory of no points ...). Never sent while locked; valid enough for the ones that are.
protocol::Payload zeros_for(CommandId c) {
  protocol::Payload p;
  for (std::size_t i = 0; i < protocol::command_info(c).request.min_size; ++i) p.put_u8(0);
  return p;
}

// A START_TRAJECTORY broadcast started by a trigger, as the sync line starts one; `pulsed` says
// whether the trigger ran.
asio::awaitable<Result<BroadcastResult>> start_by_trigger(CommandClient& client, bool& pulsed) {
  BroadcastOptions by_sync;
  by_sync.trigger = [&pulsed]() -> asio::awaitable<Result<void>> {
    pulsed = true;
    co_return ok();
  };
  co_return co_await client.broadcast(CommandId::start_trajectory, {}, std::move(by_sync));
}

// Two buses, robot 3 on bus 0 and robot 5 on bus 1, a listener on each bus.
struct LockRig {
  LockRig() : rig(2) {
    rig.add(3, 0);
    rig.add(5, 1);
    for (auto& m : rig.media) listeners.push_back(std::make_unique<FakeDevice>(*m, silent()));
    rig.start();
    rig.runner.on_stop([this]() -> asio::awaitable<void> {
      for (auto& l : listeners) l->stop();
      co_return;
    });
  }
  // Frames of command `c` seen on any bus (requests and replies).
  [[nodiscard]] std::size_t on_wire(CommandId c) const {
    std::size_t n = 0;
    for (const auto& l : listeners) n += l->count(c);
    return n;
  }
  [[nodiscard]] std::size_t moving_frames() const {
    std::size_t n = 0;
    for (auto c : kMoving) n += on_wire(c);
    return n;
  }
  asio::awaitable<void> lock() {
    co_await rig.discover();
    co_await rig.array->emergency_stop("test lock");
    EXPECT_TRUE(rig.array->locked());
  }
  SimRig rig;
  std::vector<std::unique_ptr<FakeDevice>> listeners;
};

void expect_locked(const Result<void>& r, std::string_view what) {
  EXPECT_FALSE(r.has_value()) << what << " went through while locked";
  if (!r) { EXPECT_EQ(r.error(), HostErrc::locked) << what << ": " << r.error().message(); }
}
template <class T>
void expect_locked(const Result<T>& r, std::string_view what) {
  EXPECT_FALSE(r.has_value()) << what << " went through while locked";
  if (!r) { EXPECT_EQ(r.error(), HostErrc::locked) << what << ": " << r.error().message(); }
}

}  // namespace

TEST(MotionLock, RawRequestsOnTheArraysClientsDoNotMoveARobotWhileLocked) {
  LockRig t;
  t.rig.run([&]() -> asio::awaitable<void> {
    co_await t.lock();
    CommandClient& client = t.rig.array->client(0);
    for (auto c : kMoving) {
      auto r = co_await client.request(3, c, zeros_for(c));
      expect_locked(r, protocol::command_name(c));
    }
    auto call = co_await client.call<CommandId::go_to_absolute_position>(3, protocol::ArmPositions{});
    expect_locked(call, "call<GO_TO_ABSOLUTE_POSITION>");
    EXPECT_EQ(kMoving.size(), 18u);
    EXPECT_EQ(client.counters().refused, kMoving.size() + 1);  // each refusal counted once
    EXPECT_EQ(t.rig.array->client_totals().refused, kMoving.size() + 1);
    EXPECT_EQ(t.rig.array->motion_lock()->refused(), kMoving.size() + 1);
    EXPECT_EQ(t.moving_frames(), 0u);
    EXPECT_FALSE(t.rig.model(3).moving());
  });
}

TEST(MotionLock, PipelinesAndBroadcastsDoNotMoveARobotWhileLocked) {
  LockRig t;
  t.rig.run([&]() -> asio::awaitable<void> {
    co_await t.lock();
    CommandClient& client = t.rig.array->client(0);
    const auto traj = trajectory({{10, 1.0}, {20, 2.0}}, {{175, 1.0}});
    const auto reqs = traj.requests();
    auto piped = co_await client.pipeline(3, reqs, 4);
    EXPECT_FALSE(piped.ok());
    EXPECT_EQ(piped.accepted, 0u);
    if (piped.error) { EXPECT_EQ(*piped.error, HostErrc::locked) << piped.error->message(); }
    auto start = co_await client.broadcast(CommandId::start_trajectory);
    expect_locked(start, "START_TRAJECTORY broadcast");
    bool pulsed = false;
    auto synced = co_await start_by_trigger(client, pulsed);
    expect_locked(synced, "START_TRAJECTORY by trigger");
    EXPECT_FALSE(pulsed) << "the sync line trigger ran while locked";
    auto now = co_await client.broadcast_now(CommandId::start_trajectory);
    expect_locked(now, "START_TRAJECTORY broadcast_now");
    EXPECT_EQ(t.moving_frames(), 0u);
  });
}

TEST(MotionLock, APositionerBuiltByHandOnAnArraysClientCannotMoveWhileLocked) {
  LockRig t;
  t.rig.run([&]() -> asio::awaitable<void> {
    co_await t.lock();
    Positioner own(t.rig.array->client(0), 3, fast_array().positioner);  // no gate given
    {
      const auto r_ = co_await own.start_goto({90, 90}, false);
      expect_locked(r_, "start_goto");
    }
    {
      const auto r_ = co_await own.goto_relative({5, 5});
      expect_locked(r_, "goto_relative");
    }
    {
      const auto r_ = co_await own.go_to_datums(Arm::beta);
      expect_locked(r_, "go_to_datums");
    }
    const auto one = trajectory({{10, 1.0}}, {});
    const auto up = co_await own.upload_trajectory(one);
    EXPECT_FALSE(up.ok());
    if (up.error) { EXPECT_EQ(*up.error, HostErrc::locked) << up.error->message(); }
    EXPECT_EQ(t.moving_frames(), 0u);
  });
}

TEST(MotionLock, TheArraysPositionersAndMotionCallsDoNotMoveARobotWhileLocked) {
  LockRig t;
  t.rig.run([&]() -> asio::awaitable<void> {
    co_await t.lock();
    Positioner* p = t.rig.array->find(3);
    {
      const auto r_ = co_await p->start_goto({90, 90}, true);
      expect_locked(r_, "start_goto");
    }
    {
      const auto r_ = co_await p->goto_absolute({90, 90});
      expect_locked(r_, "goto_absolute");
    }
    {
      const auto r_ = co_await p->goto_relative({1, 1});
      expect_locked(r_, "goto_relative");
    }
    for (auto arm : {Arm::alpha, Arm::beta, Arm::both}) {
      {
        const auto r_ = co_await p->go_to_datums(arm);
        expect_locked(r_, "go_to_datums");
      }
      {
        const auto r_ = co_await p->calibrate_motors(arm);
        expect_locked(r_, "calibrate_motors");
      }
      {
        const auto r_ = co_await p->calibrate_datums(arm);
        expect_locked(r_, "calibrate_datums");
      }
      {
        const auto r_ = co_await p->calibrate_cogging(arm);
        expect_locked(r_, "calibrate_cogging");
      }
    }
    {
      const auto r_ = co_await p->calibrate(CalibrationPlan{});
      expect_locked(r_, "calibrate");
    }
    const auto one = trajectory({{10, 1.0}}, {});
    const auto up = co_await p->upload_trajectory(one);
    EXPECT_FALSE(up.ok());
    std::map<std::uint16_t, ArmAngles> targets{{3, {10, 170}}, {5, {10, 170}}};
    {
      const auto r_ = co_await t.rig.array->goto_absolute(targets);
      expect_locked(r_, "Array::goto_absolute");
    }
    {
      const auto r_ = co_await t.rig.array->goto_relative(targets);
      expect_locked(r_, "Array::goto_relative");
    }
    Trajectories runs;
    runs.emplace(3, trajectory({{10, 1.0}}, {}));
    {
      const auto r_ = co_await t.rig.array->run_trajectories(std::move(runs));
      expect_locked(r_, "Array::run_trajectories");
    }
    EXPECT_EQ(t.moving_frames(), 0u);
  });
}

TEST(MotionLock, ReadsSettingsAndStopsStillGoOutWhileLocked) {
  LockRig t;
  t.rig.run([&]() -> asio::awaitable<void> {
    co_await t.lock();
    CommandClient& client = t.rig.array->client(0);
    Positioner* p = t.rig.array->find(3);
    const bool ok1 = (co_await p->read_status()).has_value();
    EXPECT_TRUE(ok1);
    const bool ok2 = (co_await p->read_position()).has_value();
    EXPECT_TRUE(ok2);
    const bool ok3 = (co_await p->set_speed(1000, 1000)).has_value();
    EXPECT_TRUE(ok3);
    const bool ok4 = (co_await p->set_collision_margin(10, 20)).has_value();
    EXPECT_TRUE(ok4);
    const bool ok5 = (co_await p->set_loop(Arm::beta, Loop::open, false)).has_value();
    EXPECT_TRUE(ok5);
    const bool ok6 = (co_await p->abort()).has_value();
    EXPECT_TRUE(ok6);
    const bool ok7 = (co_await p->stop()).has_value();
    EXPECT_TRUE(ok7);
    const bool ok8 = (co_await client.broadcast_now(CommandId::trajectory_abort)).has_value();
    EXPECT_TRUE(ok8);
    auto st = co_await client.broadcast(CommandId::get_status);
    EXPECT_TRUE(st.has_value());
    EXPECT_GT(t.on_wire(CommandId::get_status), 0u);
    EXPECT_GT(t.on_wire(CommandId::set_speed), 0u);
    EXPECT_GT(t.on_wire(CommandId::stop_trajectory), 0u);
    EXPECT_EQ(t.moving_frames(), 0u);
  });
}

TEST(MotionLock, AfterUnlockTheSameRawMoveGoesOut) {
  LockRig t;
  t.rig.run([&]() -> asio::awaitable<void> {
    co_await t.lock();
    CommandClient& client = t.rig.array->client(1);
    const protocol::ArmPositions target{protocol::Angle::from_degrees(30).value(),
                                        protocol::Angle::from_degrees(150).value()};
    {
      const auto r_ = co_await client.call<CommandId::go_to_absolute_position>(5, target);
      expect_locked(r_, "locked move");
    }
    auto un = co_await t.rig.array->unlock();
    EXPECT_TRUE(un.has_value()) << (un ? "" : un.error().message());
    auto moved = co_await client.call<CommandId::go_to_absolute_position>(5, target);
    EXPECT_TRUE(moved.has_value()) << (moved ? "" : moved.error().message());
    EXPECT_EQ(t.on_wire(CommandId::go_to_absolute_position), 2u);  // the request and its reply
    EXPECT_TRUE(t.rig.model(5).moving());
  });
}

TEST(MotionLock, EveryReadOnlyCommandStillGoesOutWhileLocked) {
  LockRig t;
  t.rig.run([&]() -> asio::awaitable<void> {
    co_await t.lock();
    CommandClient& client = t.rig.array->client(0);
    for (auto c : kReads) {
      if (!protocol::command_info(c).application) continue;  // robot 3 runs its main application
      auto r = co_await client.request(3, c, zeros_for(c));
      if (!r) { EXPECT_NE(r.error(), HostErrc::locked) << protocol::command_name(c); }
      EXPECT_GT(t.on_wire(c), 0u) << protocol::command_name(c) << " was not sent";
    }
    EXPECT_EQ(client.counters().refused, 0u);
  });
}

TEST(MotionLock, AFocalPlaneRunStartedByTheSyncLineIsRefusedWithoutAPulse) {
  PlaneRig rig;
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    auto found = co_await rig.fpa->discover();
    EXPECT_TRUE(found.has_value());
    co_await rig.fpa->array().emergency_stop("test lock");
    Trajectories runs;
    runs.emplace(1, trajectory({{10, 1.0}}, {}));
    auto run = co_await rig.fpa->run_trajectories(std::move(runs), {}, true);
    expect_locked(run, "FocalPlaneArray::run_trajectories by the sync line");
    EXPECT_EQ(rig.fpa->array().motion_lock()->refused(), 1u);  // refused up front, for the whole run
    // The chokepoint itself, below the array's up-front check: a triggered start on a bus client.
    bool pulsed = false;
    auto start = co_await start_by_trigger(rig.fpa->array().client(0), pulsed);
    expect_locked(start, "START_TRAJECTORY by trigger");
    EXPECT_FALSE(pulsed);
    EXPECT_EQ(rig.sim->counters().sync_edges, 0u);
  });
}

TEST(MotionLock, AClientWithALockOfItsOwnRefusesMovesCountsThemAndLetsTheRestThrough) {
  Runner runner;
  auto medium = can::VirtualBus::create(runner.io.get_executor(), "fps0");
  auto host_bus = medium->attach("host");
  FakeDevice device(*medium, [](const protocol::Message& m) {
    std::vector<Outgoing> out;
    if (!m.id.is_broadcast()) out.push_back({reply_to(m, m.id.positioner)});
    return out;
  });
  auto lock = std::make_shared<MotionLock>();
  CommandClient client(*host_bus, {}, lock);
  runner.on_stop([&]() -> asio::awaitable<void> {
    co_await client.stop();
    device.stop();
  });
  runner.run([&]() -> asio::awaitable<void> {
    EXPECT_EQ(client.motion_lock(), lock.get());
    EXPECT_TRUE(lock->lock("operator"));
    EXPECT_FALSE(lock->lock("second reason"));  // the first reason stays
    std::size_t broadcastable = 0;
    for (auto c : kMoving) {
      auto r = co_await client.request(7, c, zeros_for(c));
      expect_locked(r, protocol::command_name(c));
      if (!r) { EXPECT_NE(r.error().message().find("operator"), std::string::npos) << r.error().message(); }
      if (protocol::command_info(c).broadcast) {
        ++broadcastable;
        {
          const auto r_ = co_await client.broadcast(c, zeros_for(c));
          expect_locked(r_, "broadcast");
        }
        {
          const auto r_ = co_await client.broadcast_now(c);
          expect_locked(r_, "broadcast_now");
        }
      }
    }
    EXPECT_EQ(broadcastable, 1u);  // START_TRAJECTORY
    EXPECT_EQ(client.counters().refused, kMoving.size() + 2 * broadcastable);
    EXPECT_EQ(client.counters().sent, 0u);
    EXPECT_TRUE(device.requests().empty());
    // Stops and settings go out.
    const bool ok9 = (co_await client.request(7, CommandId::stop_trajectory)).has_value();
    EXPECT_TRUE(ok9);
    const bool ok10 = (co_await client.request(7, CommandId::set_speed, zeros_for(CommandId::set_speed))).has_value();
    EXPECT_TRUE(ok10);
    const bool ok11 = (co_await client.broadcast_now(CommandId::trajectory_abort)).has_value();
    EXPECT_TRUE(ok11);
    // Released: the same moves go out.
    lock->clear();
    EXPECT_FALSE(lock->locked());
    for (auto c : kMoving) {
      auto r = co_await client.request(7, c, zeros_for(c));
      EXPECT_TRUE(r.has_value()) << protocol::command_name(c) << ": " << (r ? "" : r.error().message());
    }
    EXPECT_EQ(device.requests().size(), kMoving.size() + 3);
  });
}

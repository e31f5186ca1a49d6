// Simulator: robots on a virtual bus answering raw frames from a host node.
#include "can/virtual_bus.hpp"
#include "fps/protocol/message.hpp"
#include "fps/protocol/payloads.hpp"
#include "fps/sim/simulator.hpp"

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

struct Rig {
  explicit Rig(SimulatorOptions o = {}) : sim(io.get_executor(), std::move(o)) {
    medium = can::VirtualBus::create(io.get_executor(), "fps0");
    host = medium->attach("host");
  }
  ~Rig() { sim.stop(); }
  PositionerModel* add(std::uint16_t id, double x = 0, double y = 0) {
    PositionerConfig c;
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

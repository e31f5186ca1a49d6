// SimulatorConfig and make_simulator: a focal plane from YAML, served on named virtual buses.
#include "axon/can/virtual_bus.hpp"
#include "axon/fps/protocol/message.hpp"
#include "axon/fps/sim/simulator_config.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/io_context.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <set>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::sim;
using namespace std::chrono_literals;

namespace {
Result<SimulatorConfig> parse(std::string_view yaml) {
  AXON_TRY(node, core::ConfigNode::load_string(yaml, "sim.yaml"));
  return SimulatorConfig::from_config(node);
}
}  // namespace

TEST(FpsSimConfig, ReadsOptionsDefaultsRobotsGridAndObstacles) {
  const auto c = parse(R"(
time_scale: 50
tick_ms: 2
collision_step_ms: 10
processing_delay_us: 0
scale_protocol_timeouts: true
neighbour_collisions: false
reply_faults: {seed: 3, rules: [{action: drop, count: 1}]}
defaults: {gear_ratio: 1024, firmware: "04.01.21", hard_stop_lower_deg: [6, 7]}
robots:
  - {bus: fps1, id: 100, x_mm: 5, y_mm: 6, receive_buffer: 4}
grid: {count: 5, buses: [fps0, fps1], first_id: 10}
obstacles:
  - {x_mm: 30, y_mm: 1, name: fid}
  - {x_mm: 0, y_mm: 0, x2_mm: 10, y2_mm: 0, radius_mm: 1.5}
)").value();
  EXPECT_DOUBLE_EQ(c.options.time_scale, 50);
  EXPECT_EQ(c.options.tick, 2ms);
  EXPECT_EQ(c.options.collision_step, 10ms);
  EXPECT_EQ(c.options.processing_delay, 0us);
  EXPECT_TRUE(c.options.scale_protocol_timeouts);
  EXPECT_FALSE(c.options.neighbour_collisions);
  EXPECT_EQ(c.options.reply_faults.seed, 3u);
  ASSERT_EQ(c.robots.size(), 6u);
  EXPECT_EQ(c.robots[0].channel, "fps1");
  EXPECT_EQ(c.robots[0].config.id, 100);
  EXPECT_EQ(c.robots[0].config.receive_buffer, 4u);
  EXPECT_DOUBLE_EQ(c.robots[0].config.gear_ratio, 1024);
  EXPECT_EQ(c.robots[0].config.firmware, (protocol::FirmwareVersion{4, 1, 21}));
  EXPECT_DOUBLE_EQ(c.robots[0].config.hard_stop_lower_deg[Arm::beta], 7);
  // Grid: 5 robots over 2 buses in blocks of 3 and 2, ids from 10, defaults applied.
  EXPECT_EQ(c.robots[1].config.id, 10);
  EXPECT_EQ(c.robots[1].channel, "fps0");
  EXPECT_EQ(c.robots[3].channel, "fps0");
  EXPECT_EQ(c.robots[4].channel, "fps1");
  EXPECT_DOUBLE_EQ(c.robots[5].config.gear_ratio, 1024);
  ASSERT_EQ(c.obstacles.size(), 2u);
  EXPECT_EQ(c.obstacles[0].name, "fid");
  EXPECT_DOUBLE_EQ(c.obstacles[0].buffer_mm, 3.0);
  EXPECT_DOUBLE_EQ(c.obstacles[1].shape.b.x, 10);
}

TEST(FpsSimConfig, ErrorsNameTheKey) {
  auto r = parse("robots:\n  - {bus: fps0, id: 1, gear_ration: 3}\n");
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().detail.find("gear_ration"), std::string::npos) << r.error().detail;
  EXPECT_NE(r.error().detail.find("sim.yaml:2"), std::string::npos) << r.error().detail;
  EXPECT_FALSE(parse("robots:\n  - {id: 1}\n"));              // no bus
  EXPECT_FALSE(parse("robots:\n  - {bus: a}\n"));             // no id
  EXPECT_FALSE(parse("robots:\n  - {bus: a, id: 0}\n"));      // id out of range
  EXPECT_FALSE(parse("time_scale: 0\n"));
  EXPECT_FALSE(parse("tick_ms: 0\n"));
  EXPECT_FALSE(parse("speed: 3\n"));
  EXPECT_FALSE(parse("grid: {count: 3}\n"));                  // no buses
  EXPECT_FALSE(parse("grid: {count: 3, buses: [a], first_id: 2046}\n"));
  EXPECT_FALSE(parse("defaults: {hard_stop_lower_deg: [1, 2, 3]}\n"));
  auto dup = parse("robots: [{bus: a, id: 3}]\ngrid: {count: 3, buses: [b], first_id: 2}\n");
  ASSERT_FALSE(dup);
  EXPECT_NE(dup.error().detail.find("id 3 appears twice"), std::string::npos) << dup.error().detail;
}

TEST(FpsSimConfig, HexGridIsCompactAtThePitch) {
  const auto g = hex_grid(7, 22.4);
  ASSERT_EQ(g.size(), 7u);
  EXPECT_DOUBLE_EQ(g[0].x, 0);
  EXPECT_DOUBLE_EQ(g[0].y, 0);
  for (std::size_t i = 1; i < 7; ++i) EXPECT_NEAR(std::hypot(g[i].x, g[i].y), 22.4, 1e-9);
  const auto big = hex_grid(500);
  ASSERT_EQ(big.size(), 500u);
  double nearest = 1e9;
  for (std::size_t i = 0; i < 50; ++i) {
    for (std::size_t j = i + 1; j < big.size(); ++j) {
      nearest = std::min(nearest, std::hypot(big[i].x - big[j].x, big[i].y - big[j].y));
    }
  }
  EXPECT_NEAR(nearest, 22.4, 1e-9);
}

TEST(FpsSimConfig, MakeSimulatorServesEveryRobotOnItsBus) {
  asio::io_context io;
  can::VirtualBusRegistry registry(io.get_executor());
  ASSERT_TRUE(registry.add("fps0"));
  ASSERT_TRUE(registry.add("fps1"));
  auto config = SimulatorConfig::grid(5, {"fps0", "fps1"}, 20).value();
  auto sim = make_simulator(io.get_executor(), config, registry).value();
  EXPECT_EQ(sim->size(), 5u);
  EXPECT_TRUE(sim->running());
  auto host0 = registry.open("fps0").value();
  auto host1 = registry.open("fps1").value();
  std::set<std::uint16_t> on0, on1;
  asio::co_spawn(io, [&]() -> asio::awaitable<void> {
    const auto get_id = protocol::make_request(0, protocol::CommandId::get_id, 0).value();
    (void)co_await host0->send(get_id);
    (void)co_await host1->send(get_id);
    for (auto* bus : {host0.get(), host1.get()}) {
      while (auto f = co_await bus->receive(200ms)) {
        (bus == host0.get() ? on0 : on1).insert(protocol::from_frame(f.value()).value().id.positioner);
      }
    }
    sim->stop();
  }, asio::detached);
  io.run();
  EXPECT_EQ(on0, (std::set<std::uint16_t>{20, 21, 22}));
  EXPECT_EQ(on1, (std::set<std::uint16_t>{23, 24}));
}

TEST(FpsSimConfig, MakeSimulatorReportsUnknownBuses) {
  asio::io_context io;
  can::VirtualBusRegistry registry(io.get_executor());
  auto config = SimulatorConfig::grid(1, {"nowhere"}).value();
  auto sim = make_simulator(io.get_executor(), config, registry);
  ASSERT_FALSE(sim);
  EXPECT_NE(sim.error().detail.find("nowhere"), std::string::npos) << sim.error().detail;
}

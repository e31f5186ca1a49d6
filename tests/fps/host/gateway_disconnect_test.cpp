// The gateway connection drops in the middle of a trajectory upload: robots simulated behind a
// CAN@net gateway emulator, the host's array on the gateway client's bus. A spy node on the
// robots' bus counts the trajectory points going out and cuts the connection after a few. The run
// must come back with a report naming every robot's state, and no robot may have moved.
#include "sim_rig.hpp"

#include "axon/can/cannet_client.hpp"
#include "axon/can/cannet_server.hpp"
#include "axon/can/virtual_bus.hpp"
#include "axon/fps/sim/simulator_config.hpp"

#include <boost/asio/detached.hpp>
#include <gtest/gtest.h>

#include <map>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::host;
using namespace axon::fps::host::testing;
using protocol::CommandId;

namespace {

// A trajectory with many points on both arms, so that its upload takes many frames.
protocol::Trajectory long_trajectory() {
  std::vector<protocol::ArmPoint> alpha, beta;
  for (int i = 1; i <= 20; ++i) {
    alpha.push_back({10.0 + i, 0.5 * i});
    beta.push_back({170.0 - i, 0.5 * i});
  }
  return trajectory(alpha, beta);
}

}  // namespace

TEST(GatewayDisconnect, ACutDuringTheUploadStartsNothingAndReportsEveryRobot) {
  Runner runner;
  const asio::any_io_executor ex = runner.io.get_executor();
  can::VirtualBusRegistry registry(ex);
  ASSERT_TRUE(registry.add("can0"));
  auto config = sim::SimulatorConfig::grid(4, {"can0"}, 1).value();
  config.options = fast_sim();
  auto simulator = sim::make_simulator(ex, config, registry).value();

  can::CanNetEmulatorOptions eo;
  eo.port = 0;
  can::CanNetGatewayEmulator emulator(ex, registry, {"can0"}, eo);
  ASSERT_TRUE(emulator.start());

  // Where every robot stands before the run.
  std::map<std::uint16_t, std::pair<double, double>> before;
  for (std::uint16_t id = 1; id <= 4; ++id) {
    auto* m = simulator->find(id);
    ASSERT_NE(m, nullptr);
    before[id] = {m->physical_deg(sim::Arm::alpha), m->physical_deg(sim::Arm::beta)};
  }

  constexpr int kCutAfter = 6;  // trajectory points seen on the robots' bus before the cut
  int points_seen = 0;
  bool cut = false;
  auto spy = registry.find("can0")->attach("spy");
  std::shared_ptr<can::CanNetGateway> gateway;
  std::unique_ptr<can::Bus> host_bus;
  std::unique_ptr<Array> array;
  Result<TrajectoryReport> report = Error(HostErrc::cancelled);

  runner.on_stop([&]() -> asio::awaitable<void> {
    if (array) co_await array->close();
    if (gateway) gateway->close();
    spy->close();
    emulator.stop();
    simulator->stop();
  });
  runner.run([&]() -> asio::awaitable<void> {
    // The spy: a host request carrying a point (replies to it have no payload).
    asio::co_spawn(
        ex,
        [&]() -> asio::awaitable<void> {
          for (;;) {
            auto f = co_await spy->receive();
            if (!f) co_return;
            auto m = protocol::from_frame(f.value());
            if (!m || m.value().id.command != protocol::number(CommandId::send_trajectory_data)) continue;
            if (f.value().dlc() == 0) continue;
            if (++points_seen == kCutAfter && !cut) {
              cut = true;
              emulator.stop();  // the connection goes away as when the gateway loses power
            }
          }
        },
        asio::detached);

    const net::Endpoint ep = emulator.local_endpoint();
    std::vector<int> channels{1};
    auto g = co_await can::CanNetGateway::connect(ex, ep, channels);
    EXPECT_TRUE(g.has_value());
    if (!g) co_return;
    gateway = g.value();
    auto b = gateway->bus(1);
    EXPECT_TRUE(b.has_value());
    if (!b) co_return;
    host_bus = std::move(b).value();
    ArrayOptions ao = fast_array();
    ao.client.timeout = 300ms;
    array = std::make_unique<Array>(std::vector<can::Bus*>{host_bus.get()}, ao);
    auto found = co_await array->discover();
    EXPECT_TRUE(found.has_value());
    if (!found) co_return;
    EXPECT_EQ(found.value().table.rows.size(), 4u);

    std::map<std::uint16_t, protocol::Trajectory> t;
    for (std::uint16_t id = 1; id <= 4; ++id) t.emplace(id, long_trajectory());
    TrajectoryOptions o;
    o.settle = 10ms;
    report = co_await array->run_trajectories(std::move(t), o);
  });

  EXPECT_TRUE(cut) << "the upload never reached " << kCutAfter << " points";
  ASSERT_TRUE(report.has_value()) << report.error().message();
  const auto& rep = report.value();
  EXPECT_FALSE(rep.started);
  EXPECT_FALSE(rep.completed);
  EXPECT_NE(rep.outcome.find("not started"), std::string::npos) << rep.summary();
  ASSERT_EQ(rep.robots.size(), 4u);
  for (const auto& r : rep.robots) {
    // Each robot is accounted for: its upload failed, or it loaded and was withdrawn, or it loaded
    // and the abort could not reach it (the connection is gone): it still holds its trajectory.
    EXPECT_TRUE(r.state == RobotState::upload_failed || r.state == RobotState::withdrawn ||
                r.state == RobotState::still_loaded)
        << r.id << ": " << to_string(r.state) << " " << r.detail;
    EXPECT_FALSE(r.detail.empty()) << r.id;
    // ... and a robot whose upload failed says the connection is what failed.
    if (r.state == RobotState::upload_failed) {
      EXPECT_NE(r.detail.find("closed"), std::string::npos) << r.id << ": " << r.detail;
    }
  }
  EXPECT_FALSE(rep.in_state(RobotState::upload_failed).empty()) << rep.summary();
  const auto summary = rep.summary();
  for (std::uint16_t id = 1; id <= 4; ++id) {
    EXPECT_NE(summary.find(std::to_string(id)), std::string::npos) << summary;
  }

  // Nothing moved: every robot idle where it stood.
  for (std::uint16_t id = 1; id <= 4; ++id) {
    const auto& m = *simulator->find(id);
    EXPECT_FALSE(m.moving()) << id;
    EXPECT_DOUBLE_EQ(m.physical_deg(sim::Arm::alpha), before[id].first) << id;
    EXPECT_DOUBLE_EQ(m.physical_deg(sim::Arm::beta), before[id].second) << id;
  }
}

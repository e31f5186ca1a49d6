// Trajectory uploads on a saturated bus: every robot of a bus uploads at once while the wire is the
// bottleneck (paced wire model at a low bitrate, so that the bus saturates whatever the machine's
// load), several rounds in a row. Every point of every robot must be accepted: a point refused or
// lost here means frames were reordered, duplicated or dropped somewhere between the host's
// pipeline and the robot.
#include "sim_rig.hpp"

#include "axon/can/cannet_client.hpp"
#include "axon/can/cannet_server.hpp"
#include "axon/fps/host/concurrent.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/post.hpp>

#include <future>
#include <thread>

namespace axon::fps::host::testing {
namespace {

protocol::Trajectory twenty_points() {
  std::vector<protocol::ArmPoint> a, b;
  for (int i = 1; i <= 20; ++i) {
    a.push_back({1.5 * i, 0.5 * i});
    b.push_back({180.0 - 1.0 * i, 0.5 * i});
  }
  return trajectory(a, b);
}

struct Saturated {
  static constexpr std::uint16_t kRobots = 20;
  Runner runner;            // the host
  asio::io_context sim_io;  // the simulated side when it runs on a thread of its own
  std::unique_ptr<can::VirtualBusRegistry> registry_ptr;
  std::shared_ptr<can::VirtualBus> medium;
  std::unique_ptr<sim::Simulator> simulator_ptr;

  // 20 robots on one paced bus at `bitrate`, on the host's io_context or (threaded) on sim_io.
  explicit Saturated(std::uint32_t bitrate, bool threaded = false) {
    const auto ex = threaded ? sim_io.get_executor() : runner.io.get_executor();
    registry_ptr = std::make_unique<can::VirtualBusRegistry>(ex);
    simulator_ptr = std::make_unique<sim::Simulator>(ex, fast_sim());
    can::WireModel w;
    w.enabled = true;
    w.pace_realtime = true;
    w.bitrate = bitrate;
    medium = registry_ptr->add("sat", w).value();
    for (std::uint16_t id = 1; id <= kRobots; ++id) {
      sim::PositionerConfig c;
      c.id = id;
      c.x_mm = 100.0 * id;
      simulator_ptr->add(c, *medium).value();
    }
    simulator_ptr->start();
  }
  sim::Simulator& simulator() { return *simulator_ptr; }
  can::VirtualBusRegistry& registry() { return *registry_ptr; }

  // Uploads to every robot at once, `rounds` times; returns the failures as text.
  asio::awaitable<std::vector<std::string>> upload_all(Array& array, int rounds) {
    std::vector<std::string> failures;
    const auto traj = twenty_points();
    const auto ids = array.ids();
    for (int round = 0; round < rounds; ++round) {
      co_await for_each_concurrently(ids.size(), [&](std::size_t i) -> asio::awaitable<void> {
        auto r = co_await array.find(ids[i])->upload_trajectory(traj);
        if (!r.ok()) failures.push_back(fmt::format("round {} robot {}: {}", round, ids[i], r.describe()));
      });
    }
    co_return failures;
  }
};

TEST(UploadSaturatedBus, EveryPointAcceptedOnAVirtualBus) {
  Saturated s(500'000);
  auto host = s.medium->attach("host");
  std::vector<can::Bus*> buses{host.get()};
  auto options = fast_array();
  options.client.timeout = 5s;  // the highest ids lose arbitration to the others for a while
  Array array(buses, options);
  for (std::uint16_t id = 1; id <= Saturated::kRobots; ++id) ASSERT_TRUE(array.add(id, 0).has_value());
  s.runner.run([&]() -> asio::awaitable<void> {
    auto failures = co_await s.upload_all(array, 4);
    EXPECT_TRUE(failures.empty()) << fmt::format("{}", fmt::join(failures, "\n"));
    EXPECT_EQ(array.client_totals().timeouts, 0u);
    co_await array.close();
    s.simulator().stop();
  });
}

TEST(UploadSaturatedBus, EveryPointAcceptedThroughACanNetGateway) {
  Saturated s(500'000);
  can::CanNetEmulatorOptions eo;
  eo.port = 0;
  can::CanNetGatewayEmulator gateway(s.runner.io.get_executor(), s.registry(), {"sat"}, eo);
  ASSERT_TRUE(gateway.start().has_value());
  s.runner.run([&]() -> asio::awaitable<void> {
    const net::Endpoint where = gateway.local_endpoint();
    const std::vector<int> channels{1};
    can::CanNetOptions co;
    co.bitrate_kbit = 500;
    auto connected = co_await can::CanNetGateway::connect(s.runner.io.get_executor(), where, channels, co);
    EXPECT_TRUE(connected.has_value());
    if (!connected) co_return;
    auto link = std::move(connected).value();
    auto host = link->bus(1).value();
    std::vector<can::Bus*> buses{host.get()};
    auto options = fast_array();
    options.client.timeout = 5s;
    Array array(buses, options);
    for (std::uint16_t id = 1; id <= Saturated::kRobots; ++id) EXPECT_TRUE(array.add(id, 0).has_value());
    auto failures = co_await s.upload_all(array, 4);
    EXPECT_TRUE(failures.empty()) << fmt::format("{}", fmt::join(failures, "\n"));
    EXPECT_EQ(array.client_totals().timeouts, 0u);
    EXPECT_EQ(gateway.stats().tx_overflow_drops, 0u);
    co_await array.close();
    host->close();
    link->close();
    gateway.stop();
    s.simulator().stop();
  });
}

// The same with the simulated side (robots, bus, gateway emulator) on a thread of its own, as in the
// demo and the benches: the host's frames then reach the emulator in bursts of many lines.
TEST(UploadSaturatedBus, EveryPointAcceptedThroughACanNetGatewayOnAnotherThread) {
  Saturated s(500'000, true);
  can::CanNetEmulatorOptions eo;
  eo.port = 0;
  can::CanNetGatewayEmulator gateway(s.sim_io.get_executor(), s.registry(), {"sat"}, eo);
  ASSERT_TRUE(gateway.start().has_value());
  auto work = asio::make_work_guard(s.sim_io);
  std::thread sim_thread([&] { s.sim_io.run(); });
  const net::Endpoint where = gateway.local_endpoint();
  s.runner.run([&]() -> asio::awaitable<void> {
    const std::vector<int> channels{1};
    can::CanNetOptions co;
    co.bitrate_kbit = 500;
    auto connected = co_await can::CanNetGateway::connect(s.runner.io.get_executor(), where, channels, co);
    EXPECT_TRUE(connected.has_value());
    if (!connected) co_return;
    auto link = std::move(connected).value();
    auto host = link->bus(1).value();
    std::vector<can::Bus*> buses{host.get()};
    auto options = fast_array();
    options.client.timeout = 5s;
    Array array(buses, options);
    for (std::uint16_t id = 1; id <= Saturated::kRobots; ++id) EXPECT_TRUE(array.add(id, 0).has_value());
    auto failures = co_await s.upload_all(array, 6);
    EXPECT_TRUE(failures.empty()) << fmt::format("{}", fmt::join(failures, "\n"));
    EXPECT_EQ(array.client_totals().timeouts, 0u);
    co_await array.close();
    host->close();
    link->close();
  });
  std::promise<void> stopped;
  asio::post(s.sim_io, [&] {
    EXPECT_EQ(gateway.stats().tx_overflow_drops, 0u);
    gateway.stop();
    s.simulator().stop();
    stopped.set_value();
  });
  stopped.get_future().wait();
  work.reset();
  s.sim_io.stop();
  sim_thread.join();
}

}  // namespace
}  // namespace axon::fps::host::testing

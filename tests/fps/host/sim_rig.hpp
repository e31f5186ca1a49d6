// The host driver against the positioner simulator: virtual buses, simulated robots on them, and
// an Array on the host's side of every bus. Simulated time runs faster than real time (the
// protocol is unchanged; physical processes take less wall time), and the host polls quickly, so
// that moves and calibrations take a fraction of a second. No test asserts on wall-clock time.
#pragma once

#include "rig.hpp"

#include "axon/can/virtual_bus.hpp"
#include "axon/fps/host/array.hpp"
#include "axon/fps/sim/simulator.hpp"

#include <functional>
#include <memory>
#include <vector>

namespace axon::fps::host::testing {

inline sim::SimulatorOptions fast_sim(double scale = 20) {
  sim::SimulatorOptions o;
  o.time_scale = scale;
  o.neighbour_collisions = false;  // robots are placed far apart anyway
  return o;
}

inline ArrayOptions fast_array() {
  ArrayOptions o;
  o.client.timeout = 1s;
  o.client.broadcast_window = 300ms;
  o.discover_window = 300ms;
  o.positioner.poll_interval = 5ms;
  o.positioner.move_margin = 10s;
  o.positioner.datum_timeout = 60s;
  o.positioner.motor_calibration_timeout = 60s;
  o.positioner.datum_calibration_timeout = 60s;
  o.positioner.cogging_calibration_timeout = 60s;
  return o;
}

class SimRig {
 public:
  explicit SimRig(std::size_t buses = 1, sim::SimulatorOptions so = fast_sim(), ArrayOptions ao = fast_array())
      : simulator(runner.io.get_executor(), std::move(so)), array_options_(std::move(ao)) {
    for (std::size_t i = 0; i < buses; ++i) {
      const std::string name = "fps" + std::to_string(i);
      media.push_back(can::VirtualBus::create(runner.io.get_executor(), name));
      host_buses.push_back(media.back()->attach(name));  // the host's endpoint carries the bus's name
    }
  }

  // A simulated robot on bus `bus`, placed far from every other one.
  sim::PositionerModel* add(std::uint16_t id, std::size_t bus, std::function<void(sim::PositionerConfig&)> tweak = {}) {
    sim::PositionerConfig c;
    c.id = id;
    c.x_mm = 100.0 * id;
    if (tweak) tweak(c);
    return simulator.add(c, *media.at(bus)).value();
  }

  // Starts the simulator and builds the array (before run()).
  void start() {
    simulator.start();
    std::vector<can::Bus*> b;
    for (auto& h : host_buses) b.push_back(h.get());
    array = std::make_unique<Array>(b, array_options_);
    runner.on_stop([this]() -> asio::awaitable<void> {
      co_await array->close();
      simulator.stop();
    });
  }

  void run(std::function<asio::awaitable<void>()> body) { runner.run(std::move(body)); }

  // Discovery inside a test body; fails the test when a robot is missing.
  asio::awaitable<DiscoveryReport> discover() {
    auto r = co_await array->discover();
    EXPECT_TRUE(r.has_value());
    if (!r) co_return DiscoveryReport{};
    EXPECT_EQ(r.value().table.rows.size(), simulator.size()) << r.value().table.to_text();
    co_return std::move(r).value();
  }

  sim::PositionerModel& model(std::uint16_t id) { return *simulator.find(id); }

  Runner runner;
  sim::Simulator simulator;
  std::vector<std::shared_ptr<can::VirtualBus>> media;
  std::vector<std::unique_ptr<can::Bus>> host_buses;
  std::unique_ptr<Array> array;

 private:
  ArrayOptions array_options_;
};

// A trajectory from physical points; fails the test when it does not build.
inline protocol::Trajectory trajectory(std::vector<protocol::ArmPoint> alpha, std::vector<protocol::ArmPoint> beta) {
  auto t = protocol::Trajectory::from_physical(alpha, beta);
  EXPECT_TRUE(t.has_value()) << (t ? "" : t.error().message());
  return t.value();
}

}  // namespace axon::fps::host::testing

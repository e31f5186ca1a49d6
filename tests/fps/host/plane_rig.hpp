// A small simulated focal plane for tests of whole-plane operations: 2 sextants, 2 CAN@net gateway
// emulators, 4 buses, 12 robots and the PLC emulator (FocalPlaneSimulator), driven by a
// FocalPlaneArray over real TCP on loopback.
#pragma once

#include "sim_rig.hpp"

#include "axon/fps/host/focal_plane_array.hpp"
#include "axon/fps/sim/focal_plane_sim.hpp"

#include <limits>

namespace axon::fps::host::testing {

// Robots 1-6 in sextant 1 (gateway 1: bus 1 ids 1-3, bus 2 ids 4-6), 7-12 in sextant 2 (gateway 2),
// two rows of the hexagonal grid apart.
inline FocalPlane two_sextant_plane() {
  FocalPlaneSpec spec;
  spec.name = "two-sextants";
  spec.gateways = {GatewaySite{1, "127.0.0.1:1", 1, 4}, GatewaySite{2, "127.0.0.1:1", 2, 4}};
  for (std::uint16_t id = 1; id <= 12; ++id) {
    RobotSite r;
    r.id = id;
    const int k = (id - 1) % 6;
    r.x_mm = 22.4 * k;
    r.y_mm = id <= 6 ? 0.0 : 38.8;
    r.sextant = id <= 6 ? 1 : 2;
    r.bus = BusRef{static_cast<std::uint16_t>(id <= 6 ? 1 : 2), static_cast<std::uint8_t>(k < 3 ? 1 : 2)};
    r.fibres = {Fibre::boss};
    spec.robots.push_back(r);
  }
  return FocalPlane::build(spec).value();
}

// Frames robot `id` sends for `command` (for reply fault plans).
inline can::Filter replies_of(std::uint16_t id, protocol::CommandId command) {
  return can::Filter{(std::uint32_t{id} << 18) | (std::uint32_t{protocol::number(command)} << 10), 0x1FFFFC00u,
                     can::Filter::Format::extended};
}

inline can::FaultRule drop_rule(can::Filter f, std::uint64_t skip = 0,
                                std::uint64_t count = std::numeric_limits<std::uint64_t>::max()) {
  can::FaultRule r;
  r.action = can::FaultRule::Action::drop;
  r.match = f;
  r.skip = skip;
  r.count = count;
  return r;
}

inline sim::FocalPlaneSimOptions plane_sim_options(sim::Scenario scenario = {}) {
  sim::FocalPlaneSimOptions so;
  so.simulator.time_scale = 20;
  so.random_start = false;
  so.scenario = std::move(scenario);
  return so;
}

struct PlaneRig {
  Runner runner;
  FocalPlane plane = two_sextant_plane();
  std::unique_ptr<sim::FocalPlaneSimulator> sim;
  std::unique_ptr<FocalPlaneArray> fpa;

  explicit PlaneRig(sim::FocalPlaneSimOptions so = plane_sim_options()) {
    sim = sim::FocalPlaneSimulator::start(runner.io.get_executor(), plane, std::move(so)).value();
    runner.on_stop([this]() -> asio::awaitable<void> {
      if (fpa) co_await fpa->close();
      sim->stop();
    });
  }

  // Connects the array (inside a test body); starts by the sync line hold it `sync_hold` (nullopt:
  // the library's default).
  asio::awaitable<void> connect(std::optional<core::Duration> sync_hold = 20ms) {
    FocalPlaneArrayOptions o;
    o.array = fast_array();
    o.check_window = 300ms;
    for (const auto& g : sim->gateways()) o.addresses[g.id] = g.endpoint;
    o.plc = sim->plc()->endpoint();
    if (sync_hold) o.sync_hold = *sync_hold;
    auto r = co_await FocalPlaneArray::connect(runner.io.get_executor(), plane, o);
    EXPECT_TRUE(r.has_value()) << r.error().message();
    if (r) fpa = std::move(r).value();
  }
};

// Every simulated robot runs `rpm` on both arms and holds with (alpha, beta) percent.
inline bool robots_at(sim::FocalPlaneSimulator& s, std::uint32_t rpm, std::uint32_t alpha, std::uint32_t beta) {
  for (auto* m : s.simulator().robots()) {
    if (m->speed_rpm(sim::Arm::alpha) != rpm || m->speed_rpm(sim::Arm::beta) != rpm) return false;
    if (m->calibration().holding_current[sim::Arm::alpha] != alpha) return false;
    if (m->calibration().holding_current[sim::Arm::beta] != beta) return false;
  }
  return true;
}

}  // namespace axon::fps::host::testing

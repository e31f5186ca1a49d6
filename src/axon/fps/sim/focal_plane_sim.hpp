// A whole simulated focal plane from a layout: every robot of the layout on its bus, one CAN@net
// gateway emulator per gateway of the layout (its channels are its buses), and the PLC emulator
// whose relays act on the robots and gateways, all on one executor.
//
// Buses are virtual media with the wire model on (exact frame bits at the layout's bitrate,
// 1 Mbit/s by default) and real-time pacing, so that a bus carries no more than a real one would.
//
// The PLC's relays (docs/fps-plc.md) act as the electronics box's do:
//   - positioner power of sextant s: the robots of sextant s lose power (volatile state gone,
//     saved calibration and the position stored at power-down kept); when power comes back with the
//     sync line low, as it normally is, they enter their bootloader (the spec's way to upgrade
//     firmware); with the sync line held high, they boot the application.
//   - sync line: every powered robot on every bus sees the line change at the same instant; a
//     rising edge starts each one's loaded trajectory if the line is still high at the robot's
//     second look (PositionerConfig::sync_recheck, interface document 6), and each answers
//     START_TRAJECTORY with uid 0, as the spec describes. A shorter pulse starts nothing.
//   - gateway power of sextant s: the gateways serving sextant s stop (the host's connection
//     drops, nothing is forwarded); power back starts them again on the same port. A gateway of
//     sextant 0 (a bench-top one) has no relay and stays on.
//
// Geometry: the collision check uses the planner's model of the layout (plan::model_spec_from_layout):
// each robot's own arm lengths, orientation and zero offsets, the fiducials and the guide cameras,
// so the simulated plane touches exactly where the planner says it does.
//
// Start state: robots are calibrated, datums initialised; alpha is random (per the seed) or 0,
// beta folded (180, with a little scatter when random): a folded beta keeps every arm inside its
// own cell, so no start state is a collision. A scenario (YAML, see docs/fps-simulator.md) can mark
// robots as datum lost, uncalibrated, collided, in the bootloader, or absent.
//
// Threading: everything runs on the executor given to start() (the PLC's hooks are posted
// there). The PLC server has its own thread.
#pragma once

#include "axon/can/cannet_server.hpp"
#include "axon/can/virtual_bus.hpp"
#include "axon/core/config.hpp"
#include "axon/core/error.hpp"
#include "axon/fps/layout/focal_plane.hpp"
#include "axon/fps/plc/emulator.hpp"
#include "axon/fps/sim/simulator.hpp"

#include <boost/asio/any_io_executor.hpp>

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string_view>
#include <string>
#include <vector>

namespace axon::fps::sim {

// Robots that do not start in the normal state. Ids must be in the layout.
struct Scenario {
  std::set<std::uint16_t> datum_lost;    // datums not initialised (position unknown)
  std::set<std::uint16_t> uncalibrated;  // motors and datums never calibrated
  std::set<std::uint16_t> collided;      // a collision flag set at start (beta arm)
  std::set<std::uint16_t> bootloader;    // powered with the sync line low: in the bootloader
  std::set<std::uint16_t> absent;        // not simulated at all (a dead robot: discovery misses it)
  std::set<std::uint16_t> collide_on_move;  // report a collision (beta) the first time they move
  // Robots the layout does not have, on a bus of the layout (discovery finds them "unexpected").
  std::map<std::uint16_t, BusRef> extra;
  // Troubleshooting faults (PositionerModel::set_friction_fault, set_hall_fault) from the start.
  struct FrictionFault {
    std::uint16_t id = 0;
    Arm arm = Arm::beta;
    std::int32_t level = 0;
  };
  struct SensorFault {
    std::uint16_t id = 0;
    Arm arm = Arm::beta;
    HallFault fault = HallFault::stuck;
  };
  std::vector<FrictionFault> friction;
  std::vector<SensorFault> hall;

  // YAML: {datum_lost: [ids], uncalibrated: [...], collided: [...], bootloader: [...],
  //        absent: [...], collide_on_move: [...], extra: [{id: 900, gateway: 1, bus: 2}],
  //        friction: [{id: 3, arm: beta, level: 10}], hall: [{id: 4, arm: alpha, fault: stuck|dead}]}.
  static Result<Scenario> from_config(const core::ConfigNode& node);
};

// Where the gateway emulators listen. Installations reach their six gateways at six addresses on
// one port (19228); a host configured that way works unchanged against the simulator when each
// emulator has its own address too.
struct GatewayBinding {
  // kLayoutAddresses: each gateway at the HOST:PORT its layout names (the port defaults to 19228).
  // An IPv4 address: the layout's gateways, in layout order, at this address, the next one, ...
  // (127.0.0.11 gives 127.0.0.11..127.0.0.16 for six; all of 127.0.0.0/8 is loopback on Linux).
  // Any other host (0.0.0.0, a name, IPv6): every gateway on that one address.
  static constexpr std::string_view kLayoutAddresses = "layout";
  std::string address = "127.0.0.1";
  std::uint16_t port = 0;                          // every gateway on this port (0: any free one)
  std::map<std::uint16_t, std::uint16_t> ports;    // per gateway id, instead of `port`
};

// The endpoint of every gateway of `plane` under `binding`. Errors (CoreErrc::invalid_argument): a
// layout address that does not parse, counting beyond 255.255.255.255, two gateways on one endpoint.
Result<std::map<std::uint16_t, net::Endpoint>> gateway_endpoints(const FocalPlane& plane, const GatewayBinding& binding);

struct FocalPlaneSimOptions {
  SimulatorOptions simulator;            // time scale, collision step, ...
  std::uint64_t seed = 1;                // random start positions, per-robot noise
  bool random_start = true;              // random alpha (beta folded); false: alpha 0, beta 180
  std::uint32_t bitrate = 1'000'000;     // of every bus
  bool pace_realtime = true;             // frames take their wire time
  // Timer slack of the executor's core::DeadlineQueue (set by start(), so it applies to everything
  // on that execution context): frames and replies are handed over up to this much after their
  // scheduled time (the schedule itself stays exact), so that one kernel timer wake-up serves
  // many of them. The CPU a wake-up costs (a timer system call, dear on a VM) was a third of the
  // simulator's thread at 170 000 frames/s. 0: every deadline waited for exactly.
  core::Duration timer_slack = std::chrono::microseconds(200);
  GatewayBinding binding;                // where the gateway emulators listen
  bool plc = true;                       // run the PLC emulator
  plc::EmulatorOptions plc_options;      // bind address and port, register map, sensor script
  can::CanNetEmulatorOptions gateway_options;  // bind address and port are set per gateway (binding)
  PositionerConfig defaults;             // for every robot (id, geometry, seed are set per robot)
  // The fiducials' buffer in the collision check (the planner keeps 3 mm off them; the simulator
  // models the fibre's body). Robots' buffer: defaults.collision_buffer_mm.
  double fiducial_radius_mm = 1.5;
  Scenario scenario;
};

struct GatewayInfo {
  std::uint16_t id = 0;
  int sextant = 0;
  net::Endpoint endpoint;                      // where its emulator listens
  std::vector<std::pair<int, std::string>> channels;  // CAN@net channel -> virtual medium
  std::size_t robots = 0;
  bool powered = true;
};

class FocalPlaneSimulator {
 public:
  // Builds and starts everything. Errors: bind failures (CanErrc::io, PlcErrc::server_failed),
  // scenario ids not in the layout (CoreErrc::invalid_argument).
  static Result<std::unique_ptr<FocalPlaneSimulator>> start(asio::any_io_executor executor, const FocalPlane& plane,
                                                            FocalPlaneSimOptions options = {});
  ~FocalPlaneSimulator();  // stop()s
  FocalPlaneSimulator(const FocalPlaneSimulator&) = delete;
  FocalPlaneSimulator& operator=(const FocalPlaneSimulator&) = delete;

  void stop();

  [[nodiscard]] Simulator& simulator() noexcept;
  [[nodiscard]] can::VirtualBusRegistry& registry() noexcept;
  [[nodiscard]] const std::vector<GatewayInfo>& gateways() const noexcept;
  // nullptr without the PLC.
  [[nodiscard]] plc::PlcEmulator* plc() noexcept;
  // The emulator of a gateway (fault hooks: inject_bus_off ...); nullptr for an unknown id or while
  // its power is off.
  [[nodiscard]] can::CanNetGatewayEmulator* gateway_emulator(std::uint16_t id) noexcept;
  // The virtual medium of a bus ("gw1c2").
  [[nodiscard]] static std::string medium_name(const BusRef& bus);
  [[nodiscard]] std::shared_ptr<can::VirtualBus> medium(const BusRef& bus) const;
  // Robot ids by sextant (simulated robots only).
  [[nodiscard]] const std::map<int, std::vector<std::uint16_t>>& sextants() const noexcept;

  // What the relays do, callable directly too (tests, the CLI). Errors for sextants outside 1..6.
  Result<void> set_positioner_power(int sextant, bool on);
  Result<void> set_gateway_power(int sextant, bool on);
  void set_sync_line(bool high);
  [[nodiscard]] bool sync_line() const noexcept;

  struct Counters {
    std::uint64_t sync_edges = 0;            // rising edges
    core::Duration sync_last_high{};         // how long the line was high the last time, by the PLC's clock
    std::uint64_t sextant_power_changes = 0;
    std::uint64_t gateway_power_changes = 0;
  };
  [[nodiscard]] const Counters& counters() const noexcept;

  struct Impl;

 private:
  explicit FocalPlaneSimulator(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace axon::fps::sim

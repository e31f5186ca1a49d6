// A whole simulated focal plane from one configuration: simulator options, robots (listed one by
// one or laid out on a hexagonal grid), which bus each robot sits on, and fixed obstacles.
// make_simulator() builds it on the buses a BusProvider serves (e.g. a VirtualBusRegistry), which
// is what `axon sim fps` runs.
//
// YAML (every key optional unless noted):
//
//   time_scale: 50                 # simulated seconds per real second
//   tick_ms: 5                     # real time between advances
//   collision_step_ms: 20          # simulated time between collision checks
//   processing_delay_us: 100       # per command, real time
//   flash_delay_us: 1000           # per flash-writing command (53, 200, 201)
//   scale_protocol_timeouts: false # true: boot time, bootloader wait and watchdog shrink too
//   neighbour_collisions: true
//   reply_faults: {seed: 1, rules: [...]}   # can::FaultPlan, applied to the robots' frames
//   defaults: {gear_ratio: 1000, ...}       # PositionerConfig keys for every robot
//   robots:                                 # explicit robots: bus (required), id (required), any key
//     - {bus: fps0, id: 1, x_mm: 0, y_mm: 0}
//   grid:                                   # or generated robots (both lists may be combined)
//     count: 20                             # required
//     buses: [fps0, fps1]                   # required; consecutive blocks of robots per bus
//     first_id: 1
//     pitch_mm: 22.4
//   obstacles:                              # points (x_mm, y_mm) or segments (x2_mm, y2_mm too)
//     - {x_mm: 30, y_mm: 0, radius_mm: 3, name: fiducial1}   # radius_mm: the obstacle's buffer
#pragma once

#include "axon/can/provider.hpp"
#include "axon/core/config.hpp"
#include "axon/fps/sim/simulator.hpp"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace axon::fps::sim {

struct RobotPlacement {
  PositionerConfig config;
  std::string channel;  // the bus it sits on, as the provider names it
};

struct SimulatorConfig {
  SimulatorOptions options;
  std::vector<RobotPlacement> robots;
  std::vector<Obstacle> obstacles;
  // The plane's collision geometry (Simulator::set_geometry), e.g. a layout's; not read from YAML.
  std::optional<plan::ModelSpec> geometry;

  static Result<SimulatorConfig> from_config(const core::ConfigNode& node);

  // `count` robots on a hexagonal grid of the given pitch around (0, 0), nearest the centre first,
  // spread over `channels` in consecutive blocks (like daisy chains), ids first_id, first_id + 1...
  // Errors: no channels, or ids beyond 2047.
  static Result<SimulatorConfig> grid(std::size_t count, const std::vector<std::string>& channels,
                                      std::uint16_t first_id = 1, const PositionerConfig& defaults = {},
                                      double pitch_mm = 22.4);
};

// Hexagonal lattice points of the given pitch around (0, 0), nearest first.
std::vector<Vec2> hex_grid(std::size_t count, double pitch_mm = 22.4);

// Builds the simulator, adds every robot on an endpoint `provider` opens for its channel, adds the
// obstacles, and starts it. The provider must outlive the simulator.
Result<std::unique_ptr<Simulator>> make_simulator(asio::any_io_executor executor, const SimulatorConfig& config,
                                                  can::BusProvider& provider);

}  // namespace axon::fps::sim

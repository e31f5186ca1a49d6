// A simulated focal plane: many positioner models served on CAN buses, driven by a clock.
//
// Every robot has its own endpoint on its bus (a node of a virtual bus, or whatever a BusProvider
// opens), filtered to its id and to broadcasts, so replies from many robots arbitrate on the bus
// like real ones. The endpoint's receive queue is the robot's receive buffer (PositionerConfig::
// receive_buffer, default 16 frames): frames arriving while it is full are lost and counted in the
// endpoint's stats().rx_dropped. Each frame taken from the buffer costs a processing delay (real
// time) before the model answers it, so a host that floods one robot overflows its buffer as a
// real one would.
//
// Time: simulated time = real time elapsed since construction x time_scale (e.g. 50: a 40-minute
// cogging calibration takes under a minute). A steady_timer tick moves every model to the current
// simulated time, sends what they report on their own (collision frames) and checks neighbours
// for collisions in steps of at most collision_step of simulated time. While anything moves only
// that step moves time on: frames, the sync edge and power switches happen at the instant of the
// last step, so every robot is at the same instant when the check compares them (with nothing
// moving, time jumps to the present first). The protocol is unchanged
// by the scale; only durations of physical processes shrink. Unless scale_protocol_timeouts is
// set, the robots' boot time, bootloader wait, watchdog and sync line recheck are stretched by the
// scale so that they keep their real-time length for the host.
//
// Everything runs on one executor (like every can::Bus). A test can inject a core::ManualClock
// and call step() after moving it, for runs that do not depend on the machine's speed.
#pragma once

#include "axon/can/bus.hpp"
#include "axon/can/fault_plan.hpp"
#include "axon/can/provider.hpp"
#include "axon/can/virtual_bus.hpp"
#include "axon/core/clock.hpp"
#include "axon/fps/sim/collision_monitor.hpp"
#include "axon/fps/sim/positioner_model.hpp"

#include <boost/asio/any_io_executor.hpp>

#include <chrono>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

namespace axon::fps::sim {

namespace asio = boost::asio;

struct SimulatorOptions {
  double time_scale = 1.0;                                   // simulated seconds per real second (> 0)
  core::Duration tick = std::chrono::milliseconds(5);        // real time between advances
  SimDuration collision_step = std::chrono::milliseconds(50);  // simulated time between collision checks
  core::Duration processing_delay = std::chrono::microseconds(100);  // real time per command
  core::Duration flash_delay = std::chrono::milliseconds(1);  // instead, for 53, 200 and 201
  bool scale_protocol_timeouts = false;                      // see above
  bool neighbour_collisions = true;                          // the geometric check between robots
  can::FaultPlan reply_faults;                               // applied to every frame the robots send
  const core::Clock* clock = nullptr;                        // default: core::SteadyClock::instance()

  [[nodiscard]] Result<void> validate() const;
};

struct SimulatorStats {
  std::uint64_t frames_processed = 0;     // fps frames taken from the receive buffers
  std::uint64_t non_fps_frames = 0;       // standard or remote frames: ignored, counted
  std::uint64_t frames_sent = 0;          // replies and unsolicited frames handed to the buses
  std::uint64_t unsolicited = 0;          // of which sent on the robots' own initiative (uid 0)
  std::uint64_t send_errors = 0;          // a bus refused a frame (closed, tx overflow)
  std::uint64_t faults_dropped = 0;       // reply fault plan
  std::uint64_t faults_delayed = 0;
  std::uint64_t faults_duplicated = 0;
  std::uint64_t faults_corrupted = 0;
  std::uint64_t neighbour_collisions = 0;
  std::uint64_t obstacle_collisions = 0;
};

class Simulator {
 public:
  // Throws axon::Exception for invalid options.
  Simulator(asio::any_io_executor executor, SimulatorOptions options = {});
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;
  ~Simulator();  // stop()s

  // Adds a robot on a new endpoint of `channel` (or of `medium`); the endpoint's receive queue is
  // the robot's buffer. Ids must be unique across the simulator (CoreErrc::invalid_argument);
  // invalid configs and unknown channels are errors too. Robots added after start() are served at
  // once. The model stays owned by the simulator.
  Result<PositionerModel*> add(PositionerConfig config, can::BusProvider& provider, std::string_view channel);
  Result<PositionerModel*> add(PositionerConfig config, can::VirtualBus& medium);

  // Starts serving (receive loops and the tick). Idempotent.
  void start();
  // Closes every endpoint and stops the tick. Idempotent; the models stay readable.
  void stop();
  [[nodiscard]] bool running() const noexcept;

  // Simulated time now.
  [[nodiscard]] SimTime now() const noexcept;
  [[nodiscard]] const SimulatorOptions& options() const noexcept;
  // Moves every robot to now(), sends what they report and checks for collisions (what the tick
  // does; call it directly with a manual clock).
  void step();

  [[nodiscard]] std::size_t size() const noexcept;
  [[nodiscard]] PositionerModel* find(std::uint16_t id) noexcept;
  [[nodiscard]] std::vector<PositionerModel*> robots();
  // The robot's endpoint (its stats().rx_dropped counts receive buffer overflows).
  [[nodiscard]] const can::Bus* endpoint(std::uint16_t id) const noexcept;
  // Frames lost to full receive buffers, all robots.
  [[nodiscard]] std::uint64_t receive_overflows() const noexcept;

  // Power and the sync line, for every robot (what the PLC switches). The sync line's level
  // reaches every robot at one instant, after a step() to the present; a robot starts its
  // trajectory PositionerConfig::sync_recheck after a rising edge if the line is still high then
  // (PositionerModel::set_sync_line), and its reply goes out with the step that passes that instant.
  void power_off(bool save_position = true);
  void power_on(bool sync_line_low = false);
  void power_cycle(bool sync_line_low = false);
  void set_sync_line(bool high);
  // The same for the listed robots only (a sextant's power relay, robots on one sync line).
  // CoreErrc::invalid_argument names an unknown id; nothing is switched then.
  Result<void> power_off(std::span<const std::uint16_t> ids, bool save_position = true);
  Result<void> power_on(std::span<const std::uint16_t> ids, bool sync_line_low = false);
  Result<void> set_sync_line(std::span<const std::uint16_t> ids, bool high);

  // Faults.
  Result<void> force_collision(std::uint16_t id, Arm arm);
  Result<void> set_friction_fault(std::uint16_t id, Arm arm, std::optional<std::int32_t> level);
  Result<void> set_hall_fault(std::uint16_t id, Arm arm, HallFault fault);
  void add_obstacle(Obstacle obstacle);
  void clear_obstacles();

  // Geometry. The plane's collision geometry (a layout's: plan::model_spec_from_layout): the robots
  // it lists collide with their geometry there, others with their config's; its fiducials and
  // obstacles join those add_obstacle() adds. Without it, every robot's config gives its geometry.
  void set_geometry(plan::ModelSpec geometry);
  // The collision model the check uses (robots in the order added). Rebuilt after a change of
  // robots, obstacles or geometry: the reference holds until then.
  [[nodiscard]] const plan::CollisionModel& collision_model();
  void set_reply_faults(can::FaultPlan plan);

  [[nodiscard]] const SimulatorStats& stats() const noexcept;

  struct State;

 private:
  std::shared_ptr<State> state_;
};

}  // namespace axon::fps::sim

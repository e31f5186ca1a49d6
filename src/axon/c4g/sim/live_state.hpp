// What a simulated controller is doing now, for a reader on another thread (a web page): a
// fixed-size copy taken on the controller's thread every few ticks, and its events in fixed-size
// records, both handed over through lock-free queues (SimulatedController::take_live). Nothing here
// allocates, so the copy costs the controller's thread a few kilobytes of memcpy and no lock.
//
// Units: motor positions in motor turns, joints at the link in degrees, currents in A, times in s.
#pragma once

#include "axon/c4g/protocol/packet.hpp"
#include "axon/c4g/sim/controller.hpp"
#include "axon/c4g/sim/events.hpp"
#include "axon/c4g/sim/scenario.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace axon::c4g::sim {

struct LiveAxis {
  std::uint8_t arm = 0;         // 1..4
  std::uint8_t axis = 0;        // logical 1..10
  std::int32_t mode = 0;        // the mode the axis is in (the code the packets carry)
  std::int32_t pc_request = 0;  // the code the PC's last good reply asked for
  double position = 0;          // the motor's position [turns]
  double target = 0;            // the target the packets report (D1) [turns]
  double current = 0;           // the reference current [A]
};

struct LiveArm {
  bool present = false;            // the arm has open axes
  bool drives_on = false;
  std::int32_t program_mode = 0;   // the open mode the program's GO OPEN asked for (0: none in force)
  std::size_t joints = 0;          // how many of the arrays below are the arm's
  std::array<double, protocol::kAxesPerArm> joint_deg{}, target_deg{};
};

struct LiveState {
  std::uint64_t sequence = 0;   // 1, 2, ... per snapshot taken
  double time_s = 0;            // simulated time since the first packet
  Phase phase = Phase::sync;
  bool ended = false;           // the run is over: this is the last snapshot
  bool communication_error = false;
  std::size_t axis_count = 0;
  std::array<LiveAxis, protocol::kMaxAxes> axes{};
  std::array<LiveArm, protocol::kMaxArms + 1> arms{};  // index 1..4
  std::size_t step = 0;         // the program's step under way, 0-based (== steps: the program ended)
  std::size_t steps = 0;
  StepKind step_kind = StepKind::run;  // of the step under way
  bool scenario_done = false, scenario_failed = false;
  ControllerStats stats{};
  int consecutive_misses = 0;
  std::uint64_t overruns = 0;   // ticks more than a period late
  std::uint64_t rtt_count = 0;  // accepted replies timed
  double rtt_mean_us = 0, rtt_max_us = 0;
};

struct LiveEvent {
  double time_s = 0;
  std::uint64_t cycle = 0;
  EventLevel level = EventLevel::info;
  std::array<char, 40> name{};   // NUL-terminated, cut to fit
  std::array<char, 216> text{};
  [[nodiscard]] std::string_view name_view() const noexcept { return name.data(); }
  [[nodiscard]] std::string_view text_view() const noexcept { return text.data(); }
};

// The controller's state now into `out` (its thread; no allocation). `sequence`, `ended`,
// `overruns` and the round-trip figures are the runner's, left to the caller.
void capture(const Controller& c, LiveState& out) noexcept;
// The event in a fixed-size record (its name and text cut to fit).
LiveEvent live_event(const Event& e) noexcept;

}  // namespace axon::c4g::sim

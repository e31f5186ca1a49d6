// FrontEnd: the control law split in two, for a program (a Python script, a GUI, a planner) that
// decides what the motors should do at its own rate and cannot run inside the 1 kHz cycle.
//
//   front end (any thread, any rate)          back end (the loop's real-time thread, every cycle)
//   fe.set_currents({0.3, 0})   --- slot --->   take the latest action, or the idle action
//   fe.applied(), fe.state()    <-- mirror --   publish what it applied and what it measured
//
//   axon::blmc::FrontEnd fe({.first_action_timeout = 1s, .stale_after = 100ms});
//   board.start_control(fe, settings);          // MotorBoard: the back end becomes the law
//   while (...) { fe.set(next_command(fe.state())); sleep(10ms); }
//   auto report = board.stop_control();         // report.actions: what the back end did
//
// The idle action is zero current on both motors (no PD term). The back end applies it
//   - until the first action arrives; when none arrives within first_action_timeout (counted from
//     the loop's start) it gives up: idle for good, gave_up() true, and MotorBoard ends the run,
//     disables the motors and reports ControlEnd::no_first_action;
//   - while the latest action is older than stale_after (the front end stalled or stopped): each
//     such cycle is counted (ActionStats::stale_cycles, stale_episodes) and applied() says
//     ActionSource::stale; a new action resumes control at once.
// An action's age runs from the cycle that first took it. An action set before the loop starts
// counts from the start. The safety limits (ControlSettings::limits) still apply after the law: a
// current above max_current_a is clamped there.
//
// Real time: the two sides meet in two triple buffers (three copies of a fixed-size value and one
// atomic index each): the back end never waits, locks or allocates; writers are serialised among
// themselves by a mutex, and so are readers, on their own side only.
//
// Errors: the constructor and set() throw axon::Exception with HostErrc::invalid_argument
// (blmc/host/error.hpp), in words: a timeout that is not > 0; a non-finite value or a negative
// gain. A FrontEnd is a handle: copies share one slot (MotorBoard keeps one for the run).
#pragma once

#include "axon/blmc/host/motor_board.hpp"

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>

namespace axon::blmc {

struct FrontEndOptions {
  std::chrono::milliseconds first_action_timeout = 1s;  // no action by then: the run ends
  std::chrono::milliseconds stale_after = 100ms;        // an older action gives way to the idle action
};

// Where the action the back end applied in a cycle came from.
enum class ActionSource : std::uint8_t {
  waiting,  // idle: no action yet
  action,   // the front end's latest action
  stale,    // idle: the latest action is older than stale_after
  gave_up,  // idle: no action within first_action_timeout (the run ends)
};
const char* to_string(ActionSource s) noexcept;

struct AppliedAction {
  std::uint64_t cycle = 0;
  double time_s = 0;  // since the loop started
  Command command{};  // what the law handed the loop (zeros when idle), before the safety clamp
  ActionSource source = ActionSource::waiting;
  std::uint64_t action = 0;  // the latest action taken (set() counts from 1; 0: none), applied
                             // when source is ActionSource::action
  double age_s = 0;          // since the back end first took that action
};

class FrontEnd {
 public:
  explicit FrontEnd(FrontEndOptions options = {});

  // The front end (any thread but the loop's): the next action, from now on.
  void set(const Command& command);
  void set_currents(std::array<double, 2> amperes);

  // The back end as a ControlLaw for MotorBoard::start_control(law ...) or a test; it starts a new
  // run (the counters and gave_up() restart). One run at a time per FrontEnd.
  [[nodiscard]] ControlLaw law() const;

  // Readers (any thread but the loop's): the latest cycle's action and measurements.
  [[nodiscard]] AppliedAction applied() const;
  [[nodiscard]] ControlState state() const;
  [[nodiscard]] ActionStats stats() const;
  [[nodiscard]] bool gave_up() const noexcept;
  [[nodiscard]] std::uint64_t actions_set() const noexcept;
  [[nodiscard]] const FrontEndOptions& options() const noexcept;

  struct Shared;

 private:
  std::shared_ptr<Shared> shared_;
};

}  // namespace axon::blmc

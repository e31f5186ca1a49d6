// Running a control law on one board for a while: the workflow under `axon blmc current|pd|home`
// and under the blocking MotorBoard (motor_board.hpp), as coroutines on the board's bus executor.
//
//   ControlOptions opt;  opt.limits = ...;  opt.loop.period = 1ms;  opt.duration = 5s;
//   if (auto v = validate(opt, board.options().recv_timeout_ms); !v) ...   // before enabling
//   auto r = co_await run_control(board, controller, opt, hooks);         // motors already enabled
//   r->fault, r->stats                                                    // board back out of cyclic mode
//
// run_control() starts cyclic mode, runs the ControlLoop on its real-time thread and, on the bus
// thread, wakes every `refresh` to drain the loop's records (hooks.record gets each one) and to
// call hooks.refresh with the time since the start and the latest record. The loop ends when the
// duration passed, hooks.done() or hooks.stop() says so, hooks.refresh returns false, the board was
// interrupted (Board::interrupt, a signal), or the safety supervisor tripped; then the loop is
// stopped (its last frame is IqRef = 0) and cyclic mode ended. Disabling the motors is still the
// caller's job (MotorSession, with_motors_enabled): run_control never enables or disables.
//
// run_pd() and run_homing() are run_control() with the provided PdController and HomingController,
// returning their figures (tracking errors; index positions, i.e. the offsets).
#pragma once

#include "axon/blmc/host/board.hpp"
#include "axon/blmc/host/control_loop.hpp"
#include "axon/blmc/host/homing.hpp"
#include "axon/blmc/host/pd_controller.hpp"

#include <boost/asio/awaitable.hpp>

#include <array>
#include <functional>
#include <optional>

namespace axon::blmc::host {

// The loop runs at most this fast (the board itself runs at 1 kHz).
inline constexpr double kMaxLoopRateHz = 10000;

struct ControlOptions {
  SafetyLimits limits;
  LoopOptions loop;
  core::Duration duration{0};                               // 0: until done, stopped or tripped
  core::Duration refresh = std::chrono::milliseconds(100);  // how often the bus-thread watcher runs
};

// HostErrc::invalid_argument, in words, for options that cannot work: a period that is not > 0 or
// shorter than 1/kMaxLoopRateHz, a period not shorter than the board's receive timeout (it would
// trip between two references; 0 = off), limits that fail SafetyLimits::validate(), a refresh
// that is not > 0. Call it before enabling the motors.
Result<void> validate(const ControlOptions& options, std::uint32_t recv_timeout_ms);

// Called on the bus thread (never on the real-time thread); each may be empty.
struct ControlHooks {
  std::function<void(const CycleRecord&)> record;                 // every record, in order
  std::function<bool(double t_s, const CycleRecord* last)> refresh;  // false stops the loop
  std::function<bool()> done;                                      // true ends the run (a result reached)
  std::function<bool()> stop;                                      // true ends the run (a request)
};

struct ControlOutcome {
  LoopStats stats;                // exact: read after the loop thread ended
  std::optional<LoopFault> fault; // the safety stop, if one ended the run
  bool stopped = false;           // ended by hooks.stop/refresh or an interrupt, not by time or done
  std::uint64_t records_dropped = 0;
};

// See above. Errors: start_cyclic's (HostErrc::cyclic_active, closed ...), the loop thread's start.
// The ControlLoop constructor's axon::Exception (invalid limits) propagates: validate() first.
asio::awaitable<Result<ControlOutcome>> run_control(Board& board, Controller& controller,
                                                    const ControlOptions& options, ControlHooks hooks = {});

// Board `board`'s measurements of one cycle record, as Board::latest() would hold them (the
// status only when its byte decodes; no time stamps).
Measurements measurements_of(const CycleRecord& record, std::size_t board = 0);

struct PdRun {
  ControlOutcome control;
  std::array<TrackingStats, 2> tracking{};  // per motor (samples 0 for a motor not in use)
  std::array<double, 2> start_rev{};        // where each motor was when the loop started
};
// A PdController (one board) under run_control. Throws like PdController for bad gains or targets.
asio::awaitable<Result<PdRun>> run_pd(Board& board, PdGains gains, std::array<PdTarget, 2> targets,
                                      const ControlOptions& options, ControlHooks hooks = {},
                                      core::Duration settle = std::chrono::milliseconds(500));

struct HomingRun {
  ControlOutcome control;
  std::array<MotorHoming, 2> motors{};  // index_rev is the offset of each motor found
  bool all_found = false;
};
// A HomingController (one board) under run_control, ending when every selected motor found its
// index or failed; options.duration is the time limit (0: none). Throws like HomingController.
asio::awaitable<Result<HomingRun>> run_homing(Board& board, HomingOptions homing, const ControlOptions& options,
                                              ControlHooks hooks = {});

}  // namespace axon::blmc::host

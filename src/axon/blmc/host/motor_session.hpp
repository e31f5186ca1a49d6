// MotorSession: the promise a program makes when it enables a board's motors. On every way out of
// the work done with them (a normal end, an error, an exception, a stop request) the board gets
// IqRef = 0 and ENABLE_MTR1/2 = 0, ENABLE_SYS = 0, and the caller learns whether that went out.
//
//   MotorSession session(board);
//   auto e = co_await session.enable();      // on failure the board is disabled again at once
//   ... start_cyclic, ControlLoop, ...        // any exit from here on:
//   auto d = co_await session.end();         // ends cyclic mode if needed, zero current, disable
//
// or, with the exits handled for you:
//
//   auto run = co_await with_motors_enabled<int>(board, [&]() -> asio::awaitable<int> { ... });
//   run.enable   the enable's result (the body did not run when it failed)
//   run.value    what the body returned (empty when it did not run)
//   run.disable  the final disable's result (sent whatever happened before)
//   An exception from the body is rethrown after the disable went out.
//
// end() may be called in cyclic mode once the real-time thread stopped (a ControlLoop that was
// stopped or destroyed): it ends cyclic mode first. A session destroyed while still enabled (a
// coroutine abandoned by a stopped io_context, a forgotten end()) queues the same frames on the
// bus without waiting (Board::queue_disable): best effort, the board's receive timeout is the last
// backstop. A stop request (Board::interrupt(), e.g. from a signal handler) ends a pending
// enable() early, so the session goes straight to the disable.
#pragma once

#include "axon/blmc/host/board.hpp"
#include "axon/can/bus_spec.hpp"

#include <exception>
#include <functional>
#include <optional>

namespace axon::blmc::host {

class MotorSession {
 public:
  explicit MotorSession(Board& board) noexcept : board_(&board) {}
  ~MotorSession();
  MotorSession(const MotorSession&) = delete;
  MotorSession& operator=(const MotorSession&) = delete;

  // Board::enable(). On failure (including HostErrc::interrupted) the session ends at once: the
  // motors are disabled before this returns the enable's error.
  asio::awaitable<Result<void>> enable();
  // Ends the session: Board::disable() (cyclic mode first ended). Idempotent: later calls return
  // the first call's result. Failures are logged as errors (they leave a board that may be on).
  asio::awaitable<Result<void>> end();

  // enable() was called and end() not yet.
  [[nodiscard]] bool active() const noexcept { return started_ && !ended_; }
  [[nodiscard]] Board& board() const noexcept { return *board_; }

 private:
  Board* board_;
  bool started_ = false;
  bool ended_ = false;
  Result<void> end_result_ = ok();
};

template <class T>
struct EnabledRun {
  Result<void> enable = ok();
  std::optional<T> value;
  Result<void> disable = ok();
};

// Enables the board, runs `body`, and ends the session whatever happened (see above).
template <class T>
asio::awaitable<EnabledRun<T>> with_motors_enabled(Board& board, std::function<asio::awaitable<T>()> body) {
  MotorSession session(board);
  EnabledRun<T> run;
  auto e = co_await session.enable();
  run.enable = e;
  if (!run.enable) {
    auto d = co_await session.end();  // already ended by enable(): its result
    run.disable = d;
    co_return run;
  }
  std::exception_ptr failure;
  try {
    run.value = co_await body();
  } catch (...) {
    failure = std::current_exception();
  }
  auto d = co_await session.end();
  run.disable = d;
  if (failure) std::rethrow_exception(failure);
  co_return run;
}

// The way out when the program's own event loop is gone with the motors possibly on (a second
// Ctrl-C stopped it mid-session): opens `spec` anew on an event loop of its own and sends IqRef = 0,
// ENABLE_MTR1/2 = 0, ENABLE_SYS = 0. Blocks for at most `timeout`; HostErrc::timeout when the bus
// did not let the frames out by then, the bus's error when it did not open.
Result<void> disable_over_new_connection(const can::BusSpec& spec, core::Duration timeout = std::chrono::seconds(3));

}  // namespace axon::blmc::host

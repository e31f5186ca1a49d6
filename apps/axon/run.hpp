// Running a command's coroutine on its own io_context, with Ctrl-C handling.
#pragma once

#include "axon/core/error.hpp"
#include "exit_codes.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/use_awaitable.hpp>

#include <chrono>

#include <csignal>
#include <cstdio>
#include <exception>
#include <functional>
#include <string>

namespace axon::app {

namespace asio = boost::asio;

// A command-line mistake (bad option value, missing file): reported to the user as such.
inline Error usage(std::string text) { return Error(CoreErrc::invalid_argument, std::move(text)); }

// How long a second stop signal lets the first one's stop of the devices finish (run_command).
inline constexpr std::chrono::milliseconds kSecondSignalGrace{500};

// The body's hold on run_command's signal handling (its second argument; cheap to copy, valid while
// run_command runs). Called with a function, it makes that function what the next stop signal does
// (stop the robots, zero the current). signal_ends_normally() marks a stop signal as the command's
// normal end (servers, simulators, monitors that run until Ctrl-C): its exit code then stays the
// body's own instead of 128+N. Both run on the command's event loop, never in a signal handler.
class SignalHook {
 public:
  SignalHook(std::function<void()>& on_signal, bool& normal_end) : on_signal_(&on_signal), normal_end_(&normal_end) {}
  void operator()(std::function<void()> f) const { *on_signal_ = std::move(f); }
  void signal_ends_normally() const { *normal_end_ = true; }

 private:
  std::function<void()>* on_signal_;
  bool* normal_end_;
};

// Runs `body` to completion and returns its exit code; exceptions thrown inside are rethrown here
// (axon::Exception becomes "axon: error: ..." in main). SIGINT/SIGTERM/SIGHUP call `on_signal`, which
// a command that drives devices sets to make them safe (stop the robots, zero the current) so that
// the body finishes normally and prints what it stopped; without one, the first signal stops the
// event loop. A second signal stops it within kSecondSignalGrace, a third at once. A command ended by a signal exits 128+N (see
// exit_codes.hpp) unless its normal end is a signal (SignalHook::signal_ends_normally()).
inline int run_command(const std::function<asio::awaitable<int>(asio::io_context&, SignalHook)>& body) {
  // Destroyed after `signals` below (whose end restores the default actions): from then on the
  // command is ending and a stop signal is ignored, on every way out of here.
  struct LateSignalsIgnored {
    ~LateSignalsIgnored() { ignore_late_stop_signals(); }
  } late_signals_ignored;
  asio::io_context io;
  asio::signal_set signals(io, SIGINT, SIGTERM, SIGHUP);
  std::function<void()> on_signal = [&io] { io.stop(); };
  bool normal_end = false;
  int signalled = 0;
  // A second signal (an impatient double Ctrl-C, `timeout` signalling the process and its group)
  // still lets the first one's stop go out: the loop runs on for at most kSecondSignalGrace (the
  // abort frames, the disable are queued by then), a third signal ends it at once.
  asio::steady_timer grace(io);
  std::function<void(const boost::system::error_code&, int)> handler = [&](const boost::system::error_code& ec, int signo) {
    if (ec) return;
    record_stop_signal(signo);
    const int n = ++signalled;
    if (n == 1) {
      on_signal();
    } else if (n == 2) {
      grace.expires_after(kSecondSignalGrace);
      grace.async_wait([&io](const boost::system::error_code& e) {
        if (!e) io.stop();
      });
    } else {
      io.stop();
    }
    signals.async_wait(handler);
  };
  signals.async_wait(handler);
  int rc = 0;
  std::exception_ptr failure;
  asio::co_spawn(io, body(io, SignalHook(on_signal, normal_end)),
                 [&](std::exception_ptr e, int r) {
                   failure = e;
                   rc = r;
                   signals.cancel();
                   grace.cancel();
                   io.stop();
                 });
  io.run();
  const int signo = received_stop_signal().load();
  if (failure && signo != 0 && !normal_end) {
    // The signal's stop made the body fail (a move refused because the devices were stopped): the
    // error is told, the exit code stays the signal's.
    try {
      std::rethrow_exception(failure);
    } catch (const Exception& e) {
      std::fprintf(stderr, "axon: error: %s\n", e.what());
      return signal_exit_code(signo);
    }
  }
  if (failure) std::rethrow_exception(failure);
  if (signo != 0 && !normal_end) return signal_exit_code(signo);
  return rc;
}

// For servers and simulators that run until told to stop: waits for `duration_s` seconds (0 or less:
// for ever) or until the first SIGINT/SIGTERM/SIGHUP, whichever comes first (a signal is then their
// normal end: exit code 0). `set_on_signal` is the second
// argument run_command gives the body (taken by value: no temporary lives across the co_await).
template <class SetOnSignal>
asio::awaitable<void> wait_for_stop(asio::io_context& io, double duration_s, SetOnSignal set_on_signal) {
  asio::steady_timer until(io, std::chrono::steady_clock::time_point::max());
  if (duration_s > 0) until.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                          std::chrono::duration<double>(duration_s)));
  set_on_signal([&until, set_on_signal] {
    set_on_signal.signal_ends_normally();
    until.cancel();
  });
  boost::system::error_code ec;
  co_await until.async_wait(asio::redirect_error(asio::use_awaitable, ec));
  set_on_signal([] {});  // `until` is about to go; as before, the next signal does nothing and a second one stops
}

// Unwraps a Result inside a command: its error becomes an axon::Exception for main to print.
// With a coroutine, first name the result (`auto r = co_await f(); need(std::move(r));`): gcc 12
// mishandles non-trivial temporaries that live across a co_await inside one expression.
template <class T>
T need(Result<T>&& r) {
  if (!r) throw Exception(r.error());
  if constexpr (!std::is_void_v<T>) return std::move(r).value();
}

}  // namespace axon::app

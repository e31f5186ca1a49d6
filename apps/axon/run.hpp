// Running a command's coroutine on its own io_context, with Ctrl-C handling.
#pragma once

#include "core/error.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/use_awaitable.hpp>

#include <chrono>

#include <csignal>
#include <exception>
#include <functional>
#include <string>

namespace axon::app {

namespace asio = boost::asio;

// A command-line mistake (bad option value, missing file): reported to the user as such.
inline Error usage(std::string text) { return Error(CoreErrc::invalid_argument, std::move(text)); }

// Runs `body` to completion and returns its exit code; exceptions thrown inside are rethrown here
// (axon::Exception becomes "axon: error: ..." in main). SIGINT/SIGTERM call `on_signal` (which
// should close buses so that the body finishes normally and prints its summary); a second signal
// stops at once.
inline int run_command(const std::function<asio::awaitable<int>(asio::io_context&, std::function<void(std::function<void()>)>)>& body) {
  asio::io_context io;
  asio::signal_set signals(io, SIGINT, SIGTERM);
  std::function<void()> on_signal = [&io] { io.stop(); };
  int signalled = 0;
  std::function<void(const boost::system::error_code&, int)> handler = [&](const boost::system::error_code& ec, int) {
    if (ec) return;
    if (signalled++ > 0) io.stop();
    else on_signal();
    signals.async_wait(handler);
  };
  signals.async_wait(handler);
  int rc = 0;
  std::exception_ptr failure;
  asio::co_spawn(io, body(io, [&](std::function<void()> f) { on_signal = std::move(f); }),
                 [&](std::exception_ptr e, int r) {
                   failure = e;
                   rc = r;
                   signals.cancel();
                   io.stop();
                 });
  io.run();
  if (failure) std::rethrow_exception(failure);
  return rc;
}

// For servers and simulators that run until told to stop: waits for `duration_s` seconds (0 or less:
// for ever) or until the first SIGINT/SIGTERM, whichever comes first. `set_on_signal` is the second
// argument run_command gives the body (taken by value: no temporary lives across the co_await).
template <class SetOnSignal>
asio::awaitable<void> wait_for_stop(asio::io_context& io, double duration_s, SetOnSignal set_on_signal) {
  asio::steady_timer until(io, std::chrono::steady_clock::time_point::max());
  if (duration_s > 0) until.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                          std::chrono::duration<double>(duration_s)));
  set_on_signal([&until] { until.cancel(); });
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

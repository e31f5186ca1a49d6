// Running a command's coroutine on its own io_context, with Ctrl-C handling.
#pragma once

#include "core/error.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>

#include <csignal>
#include <exception>
#include <functional>

namespace axon::app {

namespace asio = boost::asio;

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

// Unwraps a Result inside a command: its error becomes an axon::Exception for main to print.
// With a coroutine, first name the result (`auto r = co_await f(); need(std::move(r));`): gcc 12
// mishandles non-trivial temporaries that live across a co_await inside one expression.
template <class T>
T need(Result<T>&& r) {
  if (!r) throw Exception(r.error());
  if constexpr (!std::is_void_v<T>) return std::move(r).value();
}

}  // namespace axon::app

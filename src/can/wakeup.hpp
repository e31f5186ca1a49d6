// Small coroutine helpers for code that lives on one executor: a wake-up a coroutine parks on
// until another one wakes it, and a scope guard that also runs when a suspended coroutine is
// destroyed.
#pragma once

#include "core/clock.hpp"

#include <boost/asio/any_io_executor.hpp>
#include <boost/asio/awaitable.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/use_awaitable.hpp>

namespace axon::can {

// A coroutine waits on it; wake() resumes it with woken set. Cancelling the timer without wake()
// (or its expiry, when a deadline was set on it) resumes it with woken still false.
struct Wakeup {
  explicit Wakeup(const boost::asio::any_io_executor& ex) : timer(ex, core::TimePoint::max()) {}
  boost::asio::steady_timer timer;
  bool woken = false;

  void wake() {
    woken = true;
    timer.cancel();
  }
  boost::asio::awaitable<void> wait() {
    boost::system::error_code ec;  // expiry and cancellation both just resume the waiter
    co_await timer.async_wait(boost::asio::redirect_error(boost::asio::use_awaitable, ec));
  }
};

template <class F>
struct OnExit {
  F f;
  ~OnExit() { f(); }
};
template <class F>
OnExit(F) -> OnExit<F>;

}  // namespace axon::can

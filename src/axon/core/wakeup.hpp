// Waiting inside coroutines on a single-threaded executor (Boost 1.74 has no channels): a wake-up
// one coroutine parks on until another notifies it, a deadline passes or the wait is abandoned
// (shutdown); a sleep; and a scope guard that also runs when a suspended coroutine is destroyed.
#pragma once

#include "axon/core/clock.hpp"

#include <utility>  // before Asio: its awaitable.hpp uses std::exchange without including it

#include <boost/asio/any_io_executor.hpp>
#include <boost/asio/awaitable.hpp>
#include <boost/asio/steady_timer.hpp>

namespace axon::core {

class Wakeup {
 public:
  explicit Wakeup(boost::asio::any_io_executor ex) : timer_(std::move(ex)) {}
  Wakeup(const Wakeup&) = delete;
  Wakeup& operator=(const Wakeup&) = delete;

  // True when notified (now or before the call); false when the deadline passed first or the
  // wait was abandoned.
  boost::asio::awaitable<bool> wait_until(TimePoint deadline);
  boost::asio::awaitable<bool> wait() { return wait_until(TimePoint::max()); }

  // Wakes the waiter with true; remembered if nobody waits yet.
  void notify() noexcept {
    notified_ = true;
    timer_.cancel();
  }
  // Wakes the waiter with false (the thing it waited for will never come).
  void abandon() noexcept {
    abandoned_ = true;
    timer_.cancel();
  }
  [[nodiscard]] bool notified() const noexcept { return notified_; }
  void reset() noexcept { notified_ = abandoned_ = false; }

 private:
  boost::asio::steady_timer timer_;
  bool notified_ = false;
  bool abandoned_ = false;
};

// Sleeps on the calling coroutine's executor.
boost::asio::awaitable<void> sleep_for(Duration d);

// Runs f when the scope ends, including when a suspended coroutine frame is destroyed.
template <class F>
struct OnExit {
  F f;
  ~OnExit() { f(); }
};
template <class F>
OnExit(F) -> OnExit<F>;

}  // namespace axon::core

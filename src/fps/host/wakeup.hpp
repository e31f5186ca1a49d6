// A wake-up call for one waiting coroutine: the building block for "wait until something happens
// or a deadline passes" on a single-threaded executor (Boost 1.74 has no channels).
//
// notify() before wait_until() is remembered, so a wake-up that comes while the waiter is busy
// elsewhere is not lost.
#pragma once

#include "core/clock.hpp"

#include <utility>  // before Asio: its awaitable.hpp uses std::exchange without including it

#include <boost/asio/any_io_executor.hpp>
#include <boost/asio/awaitable.hpp>
#include <boost/asio/steady_timer.hpp>

namespace axon::fps::host {

namespace asio = boost::asio;

class Wakeup {
 public:
  explicit Wakeup(asio::any_io_executor ex) : timer_(std::move(ex)) {}
  Wakeup(const Wakeup&) = delete;
  Wakeup& operator=(const Wakeup&) = delete;

  // Returns true when notified (now or earlier), false when the deadline passed first.
  asio::awaitable<bool> wait_until(core::TimePoint deadline);
  void notify() noexcept {
    notified_ = true;
    timer_.cancel();
  }
  [[nodiscard]] bool notified() const noexcept { return notified_; }
  void reset() noexcept { notified_ = false; }

 private:
  asio::steady_timer timer_;
  bool notified_ = false;
};

// Sleeps on the current coroutine's executor.
asio::awaitable<void> sleep_for(core::Duration d);

}  // namespace axon::fps::host

// One timer for many deadlines: every object on one execution context that needs to be called at
// a point in time (a virtual bus ending the frame on its wire, a simulator ending a robot's
// processing) registers here instead of owning a steady_timer of its own.
//
// Why: every time the earliest of an io_context's timers changes or one of them fires, Asio
// reprograms a kernel timer (timerfd_settime), which costs a system call, and on a virtual machine
// a good deal more. Two dozen paced buses and a few hundred robots, each with a timer re-armed per
// frame, spent a quarter of their thread in that call. Here the deadlines sit in one heap behind
// one timer, and each wake-up handles everything that has come due, including deadlines the
// handlers set while it runs that have already passed (a process that woke up late catches up in
// one go instead of one reactor round per deadline).
//
// Threading: one queue per execution context (an Asio service), used only from the thread that
// runs that context, like everything else here (one executor, one thread).
#pragma once

#include "axon/core/clock.hpp"

#include <utility>  // before Asio: its awaitable.hpp uses std::exchange without including it

#include <boost/asio/any_io_executor.hpp>
#include <boost/asio/execution_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <cstdint>
#include <optional>
#include <vector>

namespace axon::core {

class DeadlineQueue;

// Something a DeadlineQueue calls back. At most one deadline per client is pending: arming again
// replaces it. Destroying a client removes its deadline.
class DeadlineClient {
 public:
  DeadlineClient() = default;
  DeadlineClient(const DeadlineClient&) = delete;
  DeadlineClient& operator=(const DeadlineClient&) = delete;

  // Called once, on the context's thread, at or after the armed time. May arm again (also for a
  // time already past: it is then called again in the same wake-up) or destroy the client.
  virtual void on_deadline() = 0;

  // The pending deadline, if any.
  [[nodiscard]] std::optional<TimePoint> armed() const noexcept {
    if (queue_ == nullptr || armed_ == TimePoint::max()) return std::nullopt;
    return armed_;
  }

 protected:
  ~DeadlineClient();

 private:
  friend class DeadlineQueue;
  DeadlineQueue* queue_ = nullptr;  // the queue holding its entries (null when it holds none)
  std::uint32_t entries_ = 0;       // entries in that queue's heap, stale ones included
  TimePoint armed_ = TimePoint::max();
  std::uint64_t generation_ = 0;    // entries of older generations are stale
};

class DeadlineQueue final : public boost::asio::execution_context::service {
 public:
  using key_type = DeadlineQueue;
  static inline boost::asio::execution_context::id id;

  explicit DeadlineQueue(boost::asio::execution_context& context);
  ~DeadlineQueue() override;

  // The queue of the executor's execution context (created on first use).
  static DeadlineQueue& of(const boost::asio::any_io_executor& executor);

  // Calls c.on_deadline() at or after `at` (replacing the client's pending deadline, if any).
  void arm(DeadlineClient& c, TimePoint at);
  // Removes the client's pending deadline.
  void disarm(DeadlineClient& c) noexcept;

  // Timer slack: how much later than a deadline the queue may call its client, so that one
  // kernel timer wake-up serves deadlines that lie close together (the wait runs until the
  // earliest deadline plus the slack, and an earlier deadline armed while waiting does not move
  // the wait unless the wait would end more than the slack after it). Clients are never called
  // early. Default 0: every deadline is waited for exactly.
  void set_slack(Duration slack) noexcept { slack_ = slack; }
  [[nodiscard]] Duration slack() const noexcept { return slack_; }

  // Deadlines pending (stale entries of re-armed clients included until they come up).
  [[nodiscard]] std::size_t size() const noexcept { return heap_.size(); }
  // Kernel timer waits started (for benches and tests).
  [[nodiscard]] std::uint64_t timer_waits() const noexcept { return waits_; }

 private:
  friend class DeadlineClient;
  struct Entry {
    TimePoint at;
    std::uint64_t seq;         // arming order: equal times are called in that order
    std::uint64_t generation;  // the client's generation when armed
    DeadlineClient* client;
  };
  static bool later(const Entry& a, const Entry& b) noexcept { return a.at != b.at ? a.at > b.at : a.seq > b.seq; }

  void shutdown() override;
  void wait_for(TimePoint at);
  void fire();
  void forget(DeadlineClient& c) noexcept;  // erases every entry of c (it is going away)

  std::optional<boost::asio::steady_timer> timer_;  // made on first use, from the executor given to of()
  TimePoint waiting_for_ = TimePoint::max();  // what the timer's current wait is for
  std::vector<Entry> heap_;                   // min-heap on (at, seq)
  std::uint64_t next_seq_ = 0;
  std::uint64_t waits_ = 0;
  bool firing_ = false;
  Duration slack_{0};
};

}  // namespace axon::core

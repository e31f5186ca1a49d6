// Clocks behind one interface so that code which measures or schedules time can be tested with a
// clock the test moves by hand.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>

namespace axon::core {

using Duration = std::chrono::nanoseconds;
using TimePoint = std::chrono::steady_clock::time_point;
// Wall-clock time as nanoseconds since the Unix epoch: what log files and capture formats store.
using WallTime = std::chrono::nanoseconds;

// The process's monotonic time (std::chrono::steady_clock), for code that measures without a Clock.
inline TimePoint steady_now() noexcept { return std::chrono::steady_clock::now(); }
// Seconds of the monotonic clock since `t0`.
inline double seconds_since(TimePoint t0) noexcept { return std::chrono::duration<double>(steady_now() - t0).count(); }

class Clock {
 public:
  virtual ~Clock() = default;
  // Monotonic time, for intervals and deadlines.
  [[nodiscard]] virtual TimePoint now() const noexcept = 0;
  // Calendar time, for timestamps that go into files.
  [[nodiscard]] virtual WallTime wall() const noexcept = 0;
};

// The process's real clocks (std::chrono::steady_clock and system_clock).
class SteadyClock final : public Clock {
 public:
  [[nodiscard]] TimePoint now() const noexcept override { return std::chrono::steady_clock::now(); }
  [[nodiscard]] WallTime wall() const noexcept override {
    return std::chrono::duration_cast<WallTime>(std::chrono::system_clock::now().time_since_epoch());
  }
  // A shared instance for code that was not given a clock.
  static SteadyClock& instance() noexcept;
};

// A clock that only moves when told to; safe to read from several threads.
class ManualClock final : public Clock {
 public:
  explicit ManualClock(WallTime wall_start = WallTime{1'700'000'000'000'000'000LL}) : wall_start_(wall_start) {}
  [[nodiscard]] TimePoint now() const noexcept override { return TimePoint(Duration(ticks_.load())); }
  [[nodiscard]] WallTime wall() const noexcept override { return wall_start_ + Duration(ticks_.load()); }
  void advance(Duration d) noexcept { ticks_.fetch_add(d.count()); }
  void set(TimePoint t) noexcept { ticks_.store(t.time_since_epoch().count()); }

 private:
  WallTime wall_start_;
  std::atomic<std::int64_t> ticks_{0};
};

}  // namespace axon::core

// ControlLoop: the real-time cycle over one or more boards.
//
// A dedicated thread (SCHED_FIFO, mlockall and CPU pinning through core::apply_realtime when the
// system grants them; a warning and plain scheduling otherwise) runs, every period:
//
//   1. poll every board's CyclicPort (frames that arrived are decoded into its Measurements),
//   2. call the Controller with the measurements; it writes the currents it wants,
//   3. pass each board's request through its Safety (clamp, velocity limit, faults),
//   4. queue one IqRef frame per board,
//   5. push a CycleRecord into a preallocated lock-free queue for logging and monitoring.
//
// Nothing in the cycle allocates, locks, throws or logs. On a fault in any board every board gets
// zero current and ENABLE_MTRx=0 in that same cycle (queued again in later cycles if the link was
// full), the fault is published (fault()) and the loop ends (or keeps sending zeros if
// LoopOptions::stop_on_fault is false). The caller reports it off the real-time thread:
// fault()->fault.describe() names the board's error code (or the undocumented code it sent). A
// loop stopped on request queues zero current to every board as its last frame; disabling the
// boards is the caller's next step (MotorSession does it on every way out).
//
// Pacing. Pacing::clock wakes at absolute deadlines (clock_nanosleep, TIMER_ABSTIME) and skips
// deadlines it missed (counted). Pacing::measurements starts a cycle as soon as every board
// delivered a fresh `trigger` frame (the board's own 1 kHz burst drives the loop, as a robot's
// state packet drives libfranka's), falling back to the clock deadline plus half a period.
//
// Timing goes through a LoopTiming (period, jitter, overruns); live counters are atomics, the
// full statistics are exact once the thread stopped.
#pragma once

#include "axon/blmc/host/board.hpp"
#include "axon/blmc/host/loop_timing.hpp"
#include "axon/blmc/host/measurements.hpp"
#include "axon/blmc/host/safety.hpp"
#include "axon/core/clock.hpp"
#include "axon/core/error.hpp"
#include "axon/core/realtime.hpp"

#include <boost/lockfree/spsc_queue.hpp>

#include <array>
#include <atomic>
#include <memory>
#include <optional>
#include <span>
#include <thread>
#include <vector>

namespace axon::blmc::host {

inline constexpr std::size_t kMaxBoards = 4;  // per loop (records have room for this many)

struct ControlInput {
  std::uint64_t cycle = 0;
  core::TimePoint now{};
  core::Duration dt{0};  // since the previous cycle (the nominal period on the first)
  std::span<const Measurements> boards;
};

// The user's control law. Runs on the real-time thread: no allocation, locks, exceptions or I/O.
class Controller {
 public:
  virtual ~Controller() = default;
  // Once, before the first update (e.g. to latch start positions).
  virtual void start(const ControlInput& /*in*/) noexcept {}
  // Writes one MotorPair per board into `currents` (pre-set to zero).
  virtual void update(const ControlInput& in, std::span<MotorPair> currents) noexcept = 0;
};

// Wraps a callable `void(const ControlInput&, std::span<MotorPair>)`.
template <class F>
class FunctionController final : public Controller {
 public:
  explicit FunctionController(F f) : f_(std::move(f)) {}
  void update(const ControlInput& in, std::span<MotorPair> currents) noexcept override { f_(in, currents); }

 private:
  F f_;
};

enum class Pacing : std::uint8_t { clock, measurements };

struct LoopOptions {
  core::Duration period = std::chrono::milliseconds(1);
  Pacing pacing = Pacing::clock;
  Quantity trigger = Quantity::velocity;  // Pacing::measurements: the frame that completes a burst
  bool realtime = true;                   // try SCHED_FIFO / mlockall / affinity
  int fifo_priority = 80;
  bool lock_memory = true;
  std::vector<int> cpus;                  // pin the loop thread to these CPUs (empty: no pinning)
  std::size_t record_capacity = 4096;     // CycleRecords queued for the consumer
  bool stop_on_fault = true;
  // After a fault the loop keeps sending zero current for up to this long, waiting for the
  // board's next status frame, so that a fault seen first as stale data (a board that disabled
  // itself stops sending data at once, its status comes once per second) is reported with the
  // board's error code. 0 ends at once.
  core::Duration fault_grace = std::chrono::milliseconds(1200);
};

// What one cycle did, for logging and monitoring (trivially copyable, fixed size).
struct CycleRecord {
  struct PerBoard {
    MotorPair current, position, velocity, adc;  // latest measurements
    MotorPair command;                           // currents sent after safety
    std::uint8_t status = 0;                     // latest status byte
    bool tripped = false;
  };
  std::uint64_t cycle = 0;
  core::TimePoint start{};
  core::Duration period{0};
  core::Duration compute{0};  // previous cycle's start to end
  std::uint64_t overruns = 0;  // overruns so far, this cycle's included (LoopStats::overruns)
  std::uint8_t boards = 0;
  std::array<PerBoard, kMaxBoards> board{};
};

struct LoopFault {
  std::size_t board = 0;
  Fault fault;
};

class ControlLoop {
 public:
  // One SafetyLimits per port (or one for all). Throws axon::Exception (HostErrc::invalid_argument)
  // for no ports, more than kMaxBoards, a limits count that fits neither, limits that fail
  // SafetyLimits::validate(), or a period that is not > 0.
  ControlLoop(std::vector<CyclicPort*> ports, Controller& controller, std::vector<SafetyLimits> limits,
              LoopOptions options = {}, const core::Clock& clock = core::SteadyClock::instance());
  ~ControlLoop();  // stops and joins
  ControlLoop(const ControlLoop&) = delete;
  ControlLoop& operator=(const ControlLoop&) = delete;

  // Starts the thread (ports must be in cyclic mode); returns once it applied its real-time
  // settings (realtime_report() says which were granted).
  Result<void> start();
  void stop() noexcept;  // requests the stop and joins
  [[nodiscard]] bool running() const noexcept { return running_.load(std::memory_order_acquire); }
  [[nodiscard]] const core::RealtimeReport& realtime_report() const noexcept { return rt_report_; }

  // Runs one cycle on the calling thread (tests, or a caller's own loop): `deadline` is when it
  // was due, `now` when it runs. Not while the thread runs.
  void step(core::TimePoint deadline, core::TimePoint now) noexcept;

  // Consumer side (one thread).
  bool pop_record(CycleRecord& out) noexcept { return records_.pop(out); }
  [[nodiscard]] std::uint64_t records_dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }

  [[nodiscard]] bool faulted() const noexcept { return faulted_.load(std::memory_order_acquire); }
  // The fault, complete once the loop thread ended (running() false); faulted() says earlier
  // that one happened.
  [[nodiscard]] std::optional<LoopFault> fault() const noexcept;
  [[nodiscard]] std::uint64_t cycles() const noexcept { return cycles_.load(std::memory_order_relaxed); }
  [[nodiscard]] std::uint64_t overruns() const noexcept { return overruns_.load(std::memory_order_relaxed); }
  // Exact after stop() (or between step() calls); while running use cycles()/overruns().
  [[nodiscard]] LoopStats stats() const noexcept { return timing_.stats(); }
  [[nodiscard]] const Safety& safety(std::size_t board) const noexcept { return safety_[board]; }
  [[nodiscard]] const LoopOptions& options() const noexcept { return options_; }

 private:
  void run() noexcept;
  bool wait_for_trigger(core::TimePoint deadline) noexcept;
  void learn_board_reason() noexcept;

  std::vector<CyclicPort*> ports_;
  Controller* controller_;
  std::vector<Safety> safety_;
  LoopOptions options_;
  const core::Clock* clock_;
  LoopTiming timing_;
  std::vector<Measurements> inputs_;
  std::vector<MotorPair> requests_;
  std::vector<std::uint64_t> trigger_seen_;
  boost::lockfree::spsc_queue<CycleRecord> records_;
  std::thread thread_;
  core::RealtimeReport rt_report_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> running_{false};
  std::atomic<bool> faulted_{false};
  std::atomic<std::uint64_t> cycles_{0};
  std::atomic<std::uint64_t> overruns_{0};
  std::atomic<std::uint64_t> dropped_{0};
  LoopFault fault_{};
  core::TimePoint prev_start_{};
  bool started_controller_ = false;
  bool halted_ = false;  // a fault zeroed everything
  std::array<bool, kMaxBoards> disable_queued_{};  // the fault's disable frames went into the link
  std::uint64_t status_at_trip_ = 0;  // status frames (any byte) seen when the fault tripped
};

}  // namespace axon::blmc::host

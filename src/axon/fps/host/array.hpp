// Array: every positioner on one or more CAN buses, with the safety lock.
//
// Each bus gets its own CommandClient; robots are found by discovery (a GET_ID broadcast per bus,
// then firmware version and status of each robot) or added by hand, and each robot is addressed
// through the client of the bus it answered on. Buses are independent: the array talks to all of
// them at once (one coroutine per robot or bus), so 24 buses and 500 robots cost no more wall time
// than the busiest bus needs.
//
// Safety. A collision report (command 18, uid 0) from any robot on any bus locks the array at
// once and sends TRAJECTORY_ABORT as a broadcast on every bus (abort, not stop: the collision flags
// stay for diagnosis). While locked, every command that moves a robot is refused with
// HostErrc::locked by the command client it would go through (motion_lock.hpp: one lock shared by
// every bus's client, one rule from the command table), whichever handle sends it; steps already
// waiting end at their next poll. More collision reports after
// the stop are expected (neighbours hit by the stop, robots noticing late): they are recorded, not
// treated as new. unlock() sends STOP_TRAJECTORY on every bus, which clears the flags, and only then
// unlocks. A robot that does not acknowledge a trajectory start makes the array stop every robot
// (TRAJECTORY_ABORT broadcast on every bus), without locking. An operator's or a program's stop
// (emergency_stop(), or request_stop() from a signal handler or a watchdog) locks and stops the same
// way, with its own reason: whatever the host was doing stops with the robots. Every stop leaves a
// StopReport (last_stop()): the reason and, per bus, whether the abort went out and to how many
// robots, of which how many this array had set moving.
//
// Threading: all buses must live on the same executor (one io_context thread); the array's
// coroutines run there. Lifetime: `co_await close()` before destroying the array; the buses must
// outlive it.
#pragma once

#include "axon/can/bus.hpp"
#include "axon/core/error.hpp"
#include "axon/fps/host/command_client.hpp"
#include "axon/fps/host/firmware_upgrade.hpp"
#include "axon/fps/host/motion_lock.hpp"
#include "axon/fps/host/positioner.hpp"
#include "axon/fps/host/status_table.hpp"
#include "axon/fps/host/trajectory_report.hpp"
#include "axon/core/wakeup.hpp"
#include "axon/fps/protocol/trajectory.hpp"

#include <boost/asio/awaitable.hpp>

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

namespace axon::fps::host {

struct ArrayOptions {
  ClientOptions client;                 // for every bus's command client
  PositionerOptions positioner;         // for every robot
  core::Duration discover_window = 500ms;  // how long GET_ID broadcasts collect (as hosts in service)
  unsigned emergency_send_attempts = 3;    // per bus, for the stop broadcast when a send fails
};

struct DiscoveryReport {
  StatusTable table;                  // every robot found, with firmware and status
  std::vector<std::string> problems;  // buses that failed, ids that answered on two buses, ...
  std::vector<std::size_t> failed_buses;  // buses whose GET_ID broadcast failed (their robots are unknown)
};

// One bus of an emergency stop: did the TRAJECTORY_ABORT broadcast go out, and to whom.
struct BusStop {
  std::size_t bus = 0;
  std::string name;
  std::size_t robots = 0;  // robots the array knows on the bus (the broadcast reaches them all)
  std::size_t moving = 0;  // of them, robots this array had set moving (a run or a move under way)
  bool sent = false;
  std::string error;       // why it was not sent
};

// What a stop of every robot did (collision, lost connection, operator, signal).
struct StopReport {
  std::string reason;
  std::vector<BusStop> buses;

  [[nodiscard]] std::size_t robots_reached() const noexcept;  // on the buses where the abort went out
  [[nodiscard]] std::size_t moving_reached() const noexcept;
  [[nodiscard]] std::size_t buses_sent() const noexcept;
  // "stopped 12 robots (12 moving) with TRAJECTORY_ABORT on 4 of 4 buses: cannet://h:p/1 3 robots, ...",
  // plus a line per bus where the abort could not be sent.
  [[nodiscard]] std::string to_text() const;
};

struct UnlockReport {
  std::vector<std::uint16_t> acknowledged;  // robots that answered STOP_TRAJECTORY
  std::vector<std::uint16_t> silent;        // known robots that did not
};

struct ArrayCounters {
  std::uint64_t collision_locks = 0;      // collisions that locked the array
  std::uint64_t expected_collisions = 0;  // collision reports while already locked
  std::uint64_t emergency_stops = 0;      // stop-everyone broadcasts (collision or start failure)
  std::uint64_t start_failures = 0;       // trajectory starts not acknowledged by every robot
  std::uint64_t unlocks = 0;
  std::uint64_t sync_starts = 0;          // start acknowledgements with uid 0 nobody collected
};

class Array final : public MotionGate {
 public:
  // Throws axon::Exception: HostErrc::invalid_argument without buses, wrong_executor when the
  // buses do not share one executor.
  explicit Array(std::vector<can::Bus*> buses, ArrayOptions options = {});
  Array(const Array&) = delete;
  Array& operator=(const Array&) = delete;
  ~Array() override;

  [[nodiscard]] const ArrayOptions& options() const noexcept { return options_; }
  [[nodiscard]] std::size_t bus_count() const noexcept { return buses_.size(); }
  // The command client of a bus; it obeys the array's lock like every other path.
  [[nodiscard]] CommandClient& client(std::size_t bus) const { return *buses_.at(bus).client; }
  [[nodiscard]] const std::string& bus_name(std::size_t bus) const { return buses_.at(bus).bus->name(); }

  // --- robots --------------------------------------------------------------------------------
  [[nodiscard]] std::vector<std::uint16_t> ids() const;
  [[nodiscard]] std::vector<std::uint16_t> ids_on(std::size_t bus) const;
  // nullptr when unknown.
  [[nodiscard]] Positioner* find(std::uint16_t id) const noexcept;
  [[nodiscard]] Result<Positioner*> positioner(std::uint16_t id) const;
  [[nodiscard]] Result<std::size_t> bus_of(std::uint16_t id) const;
  // Adds a robot known to be on `bus` (from a configuration file) without discovery.
  Result<Positioner*> add(std::uint16_t id, std::size_t bus);

  // GET_ID broadcast on every bus (collecting for discover_window, or until `expected` robots
  // answered on that bus when given), then firmware version and status of every robot found.
  // New robots are added; known robots that did not answer are kept and listed as problems. Do not
  // run it while other operations use the robots (a robot found on another bus gets a new handle).
  asio::awaitable<Result<DiscoveryReport>> discover(std::map<std::size_t, std::size_t> expected = {});
  // Firmware (if not known), status and (application robots) position of every known robot.
  asio::awaitable<StatusTable> status_table(bool positions = true);

  // --- safety --------------------------------------------------------------------------------
  // A collision flag found while polling a robot during a step: locks and stops like a collision
  // frame (which may have been lost).
  void collision_seen(std::uint16_t positioner, const protocol::PositionerStatus& status) override;
  [[nodiscard]] bool locked() const noexcept { return lock_->locked(); }
  [[nodiscard]] const LockState& lock_state() const noexcept { return lock_->state(); }
  // The lock's rule asked up front for a whole sequence, so that a refused one does nothing at all
  // (HostErrc::locked with the lock's reason when command `c` to any of `ids` would be refused).
  [[nodiscard]] Result<void> admit_all(protocol::CommandId c, const std::vector<std::uint16_t>& ids) const;
  // The lock every client of this array obeys (for a client made by hand on one of its buses).
  [[nodiscard]] std::shared_ptr<const MotionLock> motion_lock() const noexcept { return lock_; }
  // Locks the array and stops every robot (TRAJECTORY_ABORT broadcast on every bus at once), as
  // a collision does; `reason` says why in the lock and in every robot's result. For operators and
  // supervisors. When the array was already locked, the first reason stays and the abort goes out
  // again.
  asio::awaitable<StopReport> emergency_stop(std::string reason);
  // The same without waiting: for signal handlers, watchdogs and other callbacks that cannot
  // co_await. Runs on the array's executor; close() waits for it; last_stop() has its report.
  void request_stop(std::string reason);
  // The report of the latest stop of every robot (none yet: empty).
  [[nodiscard]] const std::optional<StopReport>& last_stop() const noexcept { return last_stop_; }
  // Robots this array has set moving and not yet seen finish (trajectory runs, goto moves).
  [[nodiscard]] const std::set<std::uint16_t>& moving() const noexcept { return moving_; }
  // STOP_TRAJECTORY on every bus (clears collision flags), then unlocks. Stays locked when a
  // stop could not be sent on some bus.
  asio::awaitable<Result<UnlockReport>> unlock();

  // --- motion --------------------------------------------------------------------------------
  // Moves every listed robot at once and waits for all; one result per robot (each checked
  // against its target within the position tolerance). Errors: locked, unknown_positioner.
  using MoveResults = std::map<std::uint16_t, Result<MoveResult>>;
  asio::awaitable<Result<MoveResults>> goto_absolute(std::map<std::uint16_t, ArmAngles> targets);
  asio::awaitable<Result<MoveResults>> goto_relative(std::map<std::uint16_t, ArmAngles> deltas);
  // The trajectory sequence (see docs/fps-host.md): abort (and optionally stop) each robot,
  // settle, check status, upload every trajectory checking every reply, refuse to start unless
  // every robot loaded its trajectory, start by broadcast on every bus (or the sync line),
  // stop everyone if a robot does not acknowledge, wait for the end and check positions.
  // Errors only when nothing could be done (locked, unknown robots, no trajectories); everything
  // else is in the report.
  asio::awaitable<Result<TrajectoryReport>> run_trajectories(std::map<std::uint16_t, protocol::Trajectory> trajectories,
                                                             TrajectoryOptions options = {});

  // --- bus-wide switches (broadcast on every bus; unicast-only commands go to each robot) -----
  asio::awaitable<Result<void>> set_hall(bool on);
  asio::awaitable<Result<void>> stop_all(bool clear_collision_flags);

  // --- firmware --------------------------------------------------------------------------------
  // Upgrades the listed robots, which must already run their bootloader. `image` must stay alive
  // until this completes. Errors only for an unusable image; per-robot results are in the report.
  asio::awaitable<Result<UpgradeReport>> upgrade_firmware(std::vector<std::uint16_t> ids,
                                                          std::span<const std::uint8_t> image,
                                                          UpgradeOptions options = {});

  [[nodiscard]] const ArrayCounters& counters() const noexcept { return counters_; }
  // The command clients' counters, summed over all buses.
  [[nodiscard]] ClientCounters client_totals() const;

  // Stops every command client (waiting requests fail with HostErrc::cancelled).
  asio::awaitable<void> close();

 private:
  struct BusSlot {
    can::Bus* bus = nullptr;
    std::unique_ptr<CommandClient> client;
    std::uint64_t subscription = 0;
  };
  struct Robot {
    std::unique_ptr<Positioner> positioner;
    std::size_t bus = 0;
  };

  // A broadcast on each listed bus at once, collecting until the robots known on that bus answered.
  struct BusBroadcast {
    std::size_t bus = 0;
    Result<BroadcastResult> result = Error(HostErrc::cancelled);
  };

  asio::awaitable<Result<MoveResults>> move_many(std::map<std::uint16_t, ArmAngles> values, bool relative);
  void on_unsolicited(std::size_t bus, const Unsolicited& u);
  void lock_for(std::string reason);
  void stop_in_background();
  asio::awaitable<StopReport> stop_everyone(std::string reason);
  // Marks robots moving while it lives (from the start of a run or a move to its end).
  class MovingMark {
   public:
    MovingMark(std::set<std::uint16_t>& moving, std::vector<std::uint16_t> ids) : moving_(&moving), ids_(std::move(ids)) {
      moving_->insert(ids_.begin(), ids_.end());
    }
    ~MovingMark() {
      for (auto id : ids_) moving_->erase(id);
    }
    MovingMark(const MovingMark&) = delete;
    MovingMark& operator=(const MovingMark&) = delete;

   private:
    std::set<std::uint16_t>* moving_;
    std::vector<std::uint16_t> ids_;
  };
  asio::awaitable<std::vector<BusBroadcast>> broadcast_on(std::vector<std::size_t> buses, protocol::CommandId c,
                                                          BroadcastOptions options = {});
  asio::awaitable<Result<void>> broadcast_checked(protocol::CommandId c);
  std::vector<std::size_t> all_buses() const;
  asio::awaitable<void> upgrade_one(std::uint16_t id, const std::vector<protocol::Request>& chunks,
                                    const protocol::FirmwareUpgradeHeader& header, const UpgradeOptions& options,
                                    UpgradeRobotReport& report);

  ArrayOptions options_;
  asio::any_io_executor executor_;
  std::vector<BusSlot> buses_;
  std::map<std::uint16_t, Robot> robots_;
  std::shared_ptr<MotionLock> lock_ = std::make_shared<MotionLock>();  // shared with every client
  ArrayCounters counters_;
  std::set<std::uint16_t> moving_;
  std::optional<StopReport> last_stop_;
  std::size_t background_ = 0;  // emergency stops running in the background
  std::vector<core::Wakeup*> background_waiters_;
};

}  // namespace axon::fps::host

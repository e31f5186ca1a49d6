// MotionLock: an array's collision lock, and the rule that decides which commands it stops.
//
// The rule is the command table's (protocol/commands.hpp): a command flagged `moves` (go-to moves,
// trajectory upload and start, datum searches, calibrations) is refused while the lock is held;
// everything else (reads, settings, and the stops TRAJECTORY_ABORT and STOP_TRAJECTORY) goes out.
// The rule is applied in one place, by the command client (command_client.hpp), right before a
// frame or a sync-line trigger leaves it. Every client of an Array shares the array's lock, so no
// handle on those buses (Array::client(bus), a Positioner, the firmware upgrade, a pipeline, a raw
// request or broadcast) can send a move while the array is locked. A refusal is HostErrc::locked,
// nothing goes on the bus, and it is counted: by the lock (refused(), whoever asked) and by the
// client that refused it (ClientCounters::refused).
//
// The Array locks and unlocks (a collision report, a collision flag seen while polling, a lost
// gateway, emergency_stop / request_stop; unlock() after STOP_TRAJECTORY went out on every bus). A
// program that drives a CommandClient of its own may give it a MotionLock it controls.
//
// Threading: used on the buses' executor only (no locking of its own).
#pragma once

#include "axon/core/clock.hpp"
#include "axon/core/error.hpp"
#include "axon/fps/protocol/commands.hpp"
#include "axon/fps/protocol/response.hpp"

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace axon::fps::host {

struct Collision {
  std::uint16_t positioner = 0;
  std::size_t bus = 0;
  protocol::ResponseCode code = protocol::ResponseCode::accepted;  // alpha_collision or beta_collision
  core::WallTime when{0};
  bool caused_lock = false;  // false: reported after the array was already locked (expected)
};

struct LockState {
  bool locked = false;
  std::string reason;                   // what locked the array
  std::vector<Collision> collisions;    // the first caused the lock; the rest came after the stop
  std::vector<std::string> stop_errors; // buses where the stop broadcast could not be sent
};

class MotionLock {
 public:
  [[nodiscard]] bool locked() const noexcept { return state_.locked; }
  [[nodiscard]] const LockState& state() const noexcept { return state_; }

  // The rule: HostErrc::locked when `command` moves (its table flag) and the lock is held, naming
  // the robot (0: a broadcast), the command and the reason; ok otherwise. Counts each refusal.
  [[nodiscard]] Result<void> admit(protocol::CommandId command, std::uint16_t positioner) const;
  // Refusals since this lock was made (every path, every time it was held).
  [[nodiscard]] std::uint64_t refused() const noexcept { return refused_; }
  // The error of a motion step on `positioner` that the lock ended while it was under way.
  [[nodiscard]] Error interrupted(std::uint16_t positioner) const;

  // Holds the lock for `reason`. Already locked: the first reason stays; returns false.
  bool lock(std::string reason);
  void record_collision(Collision c) { state_.collisions.push_back(std::move(c)); }
  void record_stop_error(std::string what) { state_.stop_errors.push_back(std::move(what)); }
  // Releases the lock and forgets its reason, collisions and stop errors.
  void clear() noexcept { state_ = LockState{}; }

 private:
  LockState state_;
  mutable std::uint64_t refused_ = 0;  // a statistic: admit() stays a question about the state
};

}  // namespace axon::fps::host

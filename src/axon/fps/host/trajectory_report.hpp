// What happened to each robot in a trajectory run (Array::run_trajectories): which robots were
// not ready, which refused their upload and where, which were loaded, started, stopped, finished.
#pragma once

#include "axon/fps/host/positioner.hpp"
#include "axon/fps/plan/planner.hpp"

#include <boost/asio/awaitable.hpp>

#include <cstdint>
#include <functional>
#include <optional>
#include <string_view>
#include <string>
#include <vector>

namespace axon::fps::host {

enum class RobotState : std::uint8_t {
  pending,            // nothing done yet
  not_ready,          // failed the checks before the upload (no datum, moving, collision flag, no reply)
  upload_failed,      // refused or did not answer part of its upload (see `upload`)
  loaded,             // trajectory accepted; not started (load-only runs)
  withdrawn,          // loaded fine, then aborted because another robot failed: nothing started
  still_loaded,       // loaded fine, the run was called off, but the abort did not reach it: it
                      // still holds its whole trajectory (a sync pulse would start it)
  not_started,        // did not acknowledge the start: every robot was stopped
  started,            // acknowledged the start; the run did not wait for the end
  stopped,            // started, then stopped because of another robot (start failure or collision)
  collided,           // reported a collision
  timeout,            // did not finish in time
  position_mismatch,  // finished away from its last point
  completed,          // finished at its last point
};
const char* to_string(RobotState s) noexcept;

struct RobotRun {
  std::uint16_t id = 0;
  std::size_t bus = 0;
  RobotState state = RobotState::pending;
  UploadResult upload;               // the last attempt
  unsigned upload_attempts = 0;      // uploads started (more than one: a reply was lost, see upload_retries)
  std::optional<ArmAngles> start;    // position before the upload
  std::optional<ArmAngles> target;   // the last point of each arm (the start for an arm without points)
  std::optional<ArmAngles> reached;  // position after the move (after the final approach, if any)
  bool approached = false;           // the final approach (TrajectoryOptions::final_approach) ended at the target
  std::string detail;                // why, for every state but completed / loaded
};

struct TrajectoryOptions {
  bool start = true;  // false: load and validate only
  bool wait = true;   // wait for the end and check the final positions
  // Before the upload TRAJECTORY_ABORT goes to every bus the start reaches (the robots' buses; every
  // bus for the sync line). Abort keeps collision flags (a flagged robot is not ready); with
  // clear_collision_flags STOP_TRAJECTORY follows on the robots' buses, as the host in service does.
  bool clear_collision_flags = false;
  core::Duration settle = 100ms;        // after the abort/stop, before the next command
  // A robot whose upload ended without a reply (a lost frame: HostErrc::timeout) is uploaded again
  // from the start this many times (SEND_NEW_TRAJECTORY restarts the robot's point counters), so
  // that one lost reply does not call off a whole-plane run. A refusal is never retried.
  unsigned upload_retries = 1;
  // Collecting start acknowledgements. The robots that did start keep moving while the host waits
  // for one that does not answer, so keep this short (acknowledgements take milliseconds).
  core::Duration start_window = 250ms;
  core::Duration end_margin = 10s;      // beyond the trajectory's duration
  // Starts by the sync line, not a START_TRAJECTORY broadcast, once every bus listens (uid-0 acks);
  // refused (not_ready, before any upload) when a robot outside the run does not ack the abort.
  // Hold the line high about 0.5 s.
  std::function<asio::awaitable<Result<void>>()> sync_line;
  // When given, a robot whose trajectory drives an arm faster than this (from where it stands) is
  // not ready, with the duration it would need (trajectory_speed.hpp): nothing is uploaded, instead
  // of every too-fast point being refused by the robot.
  std::optional<plan::SpeedLimits> speed_limits;
  // Called as each phase ends ("checked": robots checked, "uploaded": every upload done,
  // "started": start acknowledged, "finished": every robot done), e.g. for timings and progress.
  std::function<void(std::string_view phase)> on_phase;
  // Interface document 7.3: after the move, GO_TO_RELATIVE_POSITION (0, 0) to every robot that
  // completed. The firmware's precise approach drives each arm 0.9 deg past where it stands and
  // back in open loop, so the arms end outside the gears' backlash, within 10-30 um of the target:
  // where correction iterations start from. A robot whose approach fails (no answer, collision,
  // away from its target) leaves the run in that state, with the reason. Phase "approached".
  bool final_approach = false;
};

// Wall time of each phase of a run (zero for phases not reached).
struct TrajectoryTimings {
  core::Duration check{0};   // abort/stop broadcasts, settle, status and position of each robot
  core::Duration upload{0};  // every trajectory uploaded, every reply checked
  core::Duration start{0};   // start broadcast or sync line, acknowledgements collected
  core::Duration move{0};    // from the start until every robot was seen done
  core::Duration approach{0};  // the final approach (TrajectoryOptions::final_approach)
};

struct TrajectoryReport {
  std::vector<RobotRun> robots;  // in id order
  bool started = false;          // the start went out and every robot acknowledged it
  bool completed = false;        // every robot finished at its target
  std::string outcome;           // one line: what happened overall
  TrajectoryTimings timings;

  [[nodiscard]] bool ok(bool load_only = false) const noexcept { return load_only ? !robots.empty() && all(RobotState::loaded) : completed; }
  [[nodiscard]] bool all(RobotState s) const noexcept;
  [[nodiscard]] std::vector<std::uint16_t> in_state(RobotState s) const;
  [[nodiscard]] const RobotRun* find(std::uint16_t id) const noexcept;
  // The outcome, the count per state, and one line per robot that did not complete.
  [[nodiscard]] std::string summary() const;
};

}  // namespace axon::fps::host

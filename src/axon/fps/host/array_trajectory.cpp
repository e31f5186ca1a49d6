// Array::run_trajectories: the trajectory sequence over every bus.
#include "axon/fps/host/array.hpp"

#include "axon/fps/host/concurrent.hpp"
#include "axon/fps/host/trajectory_speed.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <set>

namespace axon::fps::host {

using protocol::CommandId;
using protocol::PositionerStatus;

namespace {

// Why a robot may not take a trajectory now ("" when it may).
std::string not_ready_reason(const PositionerStatus& st) {
  if (st.collided()) {
    return fmt::format("collision flag set ({}); inspect, then unlock (STOP_TRAJECTORY clears it)", st.to_string());
  }
  if (!st.initialized()) return fmt::format("not initialised or datum lost ({})", st.to_string());
  if (st.calibrating()) return fmt::format("a calibration or datum search runs ({})", st.to_string());
  if (!st.idle()) return fmt::format("still moving ({})", st.to_string());
  return {};
}

ArmAngles end_of(const protocol::Trajectory& t, ArmAngles start) {
  return {t.alpha().empty() ? start.alpha : t.alpha().back().position.degrees(),
          t.beta().empty() ? start.beta : t.beta().back().position.degrees()};
}

std::vector<std::size_t> buses_of(const TrajectoryReport& rep) {
  std::set<std::size_t> s;
  for (const auto& r : rep.robots) s.insert(r.bus);
  return {s.begin(), s.end()};
}

// Robots outside the run on `buses` that the pre-upload abort did not confirm: neither an
// acknowledgement nor the bootloader's refusal (a robot in its bootloader holds no trajectory).
// One line each, for the error that refuses the start.
std::vector<std::string> unconfirmed_outside(const std::vector<std::pair<std::size_t, std::vector<std::uint16_t>>>& buses,
                                             const TrajectoryReport& rep, const auto& results) {
  std::vector<std::string> out;
  for (const auto& [bus, ids] : buses) {
    for (const auto& b : results) {
      if (b.bus != bus) continue;
      for (auto id : ids) {
        if (rep.find(id) != nullptr) continue;
        const Reply* reply = b.result ? b.result.value().from(id) : nullptr;
        if (!b.result) {
          out.push_back(fmt::format("{} (the abort broadcast failed: {})", id, b.result.error().message()));
        } else if (reply == nullptr) {
          out.push_back(fmt::format("{} (no acknowledgement)", id));
        } else if (!reply->accepted() && reply->code != protocol::ResponseCode::invalid_bootloader_command) {
          out.push_back(fmt::format("{} ({})", id, reply->error().message()));
        }
      }
    }
  }
  return out;
}

// An upload that ended because a reply did not come (not a refusal, not the lock): worth another go.
bool lost_reply(const UploadResult& u) {
  return u.error && *u.error == HostErrc::timeout && u.stage != UploadResult::Stage::not_sent;
}

// Interface document 7.3: GO_TO_RELATIVE_POSITION (0, 0) to every robot that completed, all at
// once; each either ends at its target (approached) or leaves the run with the reason.
asio::awaitable<void> final_approach(Array& array, TrajectoryReport& rep) {
  std::map<std::uint16_t, ArmAngles> in_place;
  for (const auto& r : rep.robots)
    if (r.state == RobotState::completed) in_place.emplace(r.id, ArmAngles{0, 0});
  if (in_place.empty()) co_return;
  auto moved = co_await array.goto_relative(std::move(in_place));
  for (auto& r : rep.robots) {
    if (r.state != RobotState::completed) continue;
    if (!moved) {  // locked meanwhile (the whole call is refused)
      r.state = RobotState::stopped;
      r.detail = fmt::format("final approach (7.3) not sent: {}", moved.error().message());
      continue;
    }
    const auto& m = moved.value().at(r.id);
    if (m) {
      r.reached = m.value().reached;
      r.approached = true;
      continue;
    }
    const auto& e = m.error();
    r.state = e == HostErrc::collision ? RobotState::collided
              : e == HostErrc::locked  ? RobotState::stopped
              : e == HostErrc::timeout ? RobotState::timeout
                                       : RobotState::position_mismatch;  // or refused: the detail says
    r.detail = fmt::format("final approach (7.3): {}", e.message());
  }
}

}  // namespace

asio::awaitable<Result<TrajectoryReport>> Array::run_trajectories(std::map<std::uint16_t, protocol::Trajectory> trajectories,
                                                                  TrajectoryOptions o) {
  if (trajectories.empty()) co_return Error(HostErrc::invalid_argument, "no trajectories to run");
  TrajectoryReport rep;
  std::vector<const protocol::Trajectory*> traj;
  for (const auto& [id, t] : trajectories) {
    auto bus = bus_of(id);
    if (!bus) co_return bus.error();
    RobotRun run;
    run.id = id;
    run.bus = bus.value();
    rep.robots.push_back(std::move(run));
    traj.push_back(&t);
  }
  std::vector<std::uint16_t> ids;
  for (const auto& r : rep.robots) ids.push_back(r.id);
  if (auto a = admit_all(CommandId::send_new_trajectory, ids); !a) co_return a.error();
  const std::size_t n = rep.robots.size();
  const auto involved = buses_of(rep);
  auto phase_start = core::steady_now();
  auto phase_end = [&](core::Duration& slot, std::string_view name) {
    const auto t = core::steady_now();
    slot = std::chrono::duration_cast<core::Duration>(t - phase_start);
    phase_start = t;
    if (o.on_phase) o.on_phase(name);
  };
  auto traj_points = [&](const RobotRun& r) {
    const auto& t = trajectories.at(r.id);
    return t.alpha().size() + t.beta().size();
  };
  auto fail = [&](RobotRun& r, RobotState s, std::string why) {
    r.state = s;
    r.detail = std::move(why);
  };

  // 1. Stop whatever runs and drop old trajectories wherever the start will reach (a START_TRAJECTORY
  //    broadcast: the buses involved; the sync line: every bus of the array), then let the robots
  //    settle. Collision flags are cleared (STOP_TRAJECTORY) only on the buses involved.
  const bool by_sync = o.start && o.sync_line;
  const auto reached = by_sync ? all_buses() : involved;
  std::vector<CommandId> pre{CommandId::trajectory_abort};
  if (o.clear_collision_flags) pre.push_back(CommandId::stop_trajectory);
  for (auto c : pre) {
    auto results = co_await broadcast_on(c == CommandId::trajectory_abort ? reached : involved, c);
    if (c == CommandId::trajectory_abort && by_sync) {
      // Never pulse the line while a robot nobody watches may hold a trajectory.
      std::vector<std::pair<std::size_t, std::vector<std::uint16_t>>> others;
      for (auto b : reached) others.emplace_back(b, ids_on(b));
      if (auto silent = unconfirmed_outside(others, rep, results); !silent.empty()) {
        co_return Error(HostErrc::not_ready,
                        fmt::format("start by the sync line refused: it reaches every bus, and {} robot(s) outside the "
                                    "run could not be confirmed to hold no trajectory (they would move unwatched): "
                                    "{}; nothing was uploaded",
                                    silent.size(), fmt::join(silent, ", ")));
      }
    }
    for (auto& r : rep.robots) {
      if (r.state != RobotState::pending) continue;
      for (const auto& b : results) {
        if (b.bus != r.bus) continue;
        if (!b.result) {
          fail(r, RobotState::not_ready, fmt::format("{} broadcast failed: {}", protocol::command_name(c),
                                                     b.result.error().message()));
        } else if (const Reply* reply = b.result.value().from(r.id); !reply) {
          fail(r, RobotState::not_ready, fmt::format("no acknowledgement of {}", protocol::command_name(c)));
        } else if (!reply->accepted()) {
          fail(r, RobotState::not_ready, reply->error().message());
        }
      }
    }
  }
  co_await core::sleep_for(o.settle);

  // 2. Check each robot and note where it starts.
  co_await for_each_concurrently(n, [&](std::size_t i) -> asio::awaitable<void> {
    auto& r = rep.robots[i];
    if (r.state != RobotState::pending) co_return;
    Positioner* p = find(r.id);
    auto st = co_await p->read_status();
    if (!st) co_return fail(r, RobotState::not_ready, st.error().message());
    if (auto why = not_ready_reason(st.value()); !why.empty()) co_return fail(r, RobotState::not_ready, why);
    auto pos = co_await p->read_position();
    if (!pos) co_return fail(r, RobotState::not_ready, pos.error().message());
    r.start = pos.value();
    r.target = end_of(*traj[i], pos.value());
    if (o.speed_limits) {
      const auto c = check_speed(*traj[i], pos.value(), *o.speed_limits);
      if (!c.feasible()) {
        fail(r, RobotState::not_ready,
             fmt::format("too fast for its speed limit (alpha {:.1f}, beta {:.1f} deg/s): its {:.1f} s trajectory needs "
                         "at least {:.1f} s",
                         o.speed_limits->alpha_deg_s, o.speed_limits->beta_deg_s, c.duration_s,
                         feasible_duration_s(c.shortest_duration_s())));
      }
    }
  });

  phase_end(rep.timings.check, "checked");

  // 3. Upload to every robot that passed, every reply checked.
  co_await for_each_concurrently(n, [&](std::size_t i) -> asio::awaitable<void> {
    auto& r = rep.robots[i];
    if (r.state != RobotState::pending) co_return;
    std::string lost;  // the attempts that ended without a reply, for the report
    for (;;) {
      ++r.upload_attempts;
      r.upload = co_await find(r.id)->upload_trajectory(*traj[i]);
      if (r.upload.ok() || !lost_reply(r.upload) || r.upload_attempts > o.upload_retries || lock_->locked()) break;
      lost += fmt::format("{}attempt {}: {}", lost.empty() ? "" : "; ", r.upload_attempts, r.upload.describe());
      spdlog::warn("fps array: positioner {}: upload attempt {} lost a reply; uploading again", r.id, r.upload_attempts);
    }
    if (r.upload.ok()) {
      r.state = RobotState::loaded;
      if (!lost.empty()) r.detail = fmt::format("loaded on attempt {} ({})", r.upload_attempts, lost);
    } else {
      fail(r, RobotState::upload_failed,
           lost.empty() ? r.upload.describe() : fmt::format("{} (after {} attempts; {})", r.upload.describe(), r.upload_attempts, lost));
    }
  });

  phase_end(rep.timings.upload, "uploaded");

  // 4. Start only if every robot is loaded (and nothing locked the array meanwhile).
  const auto failed = [&] {
    std::vector<std::uint16_t> ids;
    for (const auto& r : rep.robots) {
      if (r.state != RobotState::loaded) ids.push_back(r.id);
    }
    return ids;
  }();
  const bool lock_now = lock_->locked();
  if (!failed.empty() || lock_now) {
    rep.outcome = lock_now ? fmt::format("not started: the array is locked ({})", lock_->state().reason)
                           : fmt::format("not started: {} of {} positioners failed the checks or the upload (each "
                                         "listed once below)",
                                         failed.size(), n);
    // Drop the trajectories that did load (and partial uploads), so that nothing (a stray sync
    // pulse) can start them; say exactly what each robot holds when the abort did not reach it.
    auto results = co_await broadcast_on(involved, CommandId::trajectory_abort);
    for (auto& r : rep.robots) {
      std::string abort_failure;
      bool acknowledged = false;
      for (const auto& b : results) {
        if (b.bus != r.bus) continue;
        if (!b.result) {
          abort_failure = fmt::format("the abort broadcast on bus {} failed: {}", bus_name(r.bus), b.result.error().message());
        } else if (const Reply* reply = b.result.value().from(r.id); reply != nullptr && reply->accepted()) {
          acknowledged = true;
        } else {
          abort_failure = "it did not acknowledge the abort";
        }
      }
      if (r.state == RobotState::loaded) {
        if (acknowledged) {
          fail(r, RobotState::withdrawn, "loaded, then withdrawn (abort acknowledged): the run was not started");
        } else {
          fail(r, RobotState::still_loaded,
               fmt::format("still holds its whole trajectory ({} points): {}; the run was not started", traj_points(r),
                           abort_failure));
        }
      } else if (r.state == RobotState::upload_failed && r.upload.stage != UploadResult::Stage::not_sent) {
        r.detail += acknowledged ? "; the partial upload was discarded (abort acknowledged)"
                                 : fmt::format("; may still hold a partial trajectory ({} of {} points accepted), not withdrawn: {}",
                                               r.upload.points_accepted, traj_points(r), abort_failure);
      }
    }
    spdlog::warn("fps array: trajectories {}", rep.outcome);
    co_return rep;
  }
  if (!o.start) {
    rep.outcome = "loaded; not started (load only)";
    co_return rep;
  }

  // 5. Start on every bus at once: a broadcast per bus, or the sync line once every bus listens.
  BroadcastOptions start;
  start.window = o.start_window;
  std::size_t listening = 0;
  if (o.sync_line) {
    start.trigger = [&]() -> asio::awaitable<Result<void>> {
      if (++listening < involved.size()) co_return ok();
      co_return co_await o.sync_line();
    };
  }
  std::vector<std::uint16_t> run_ids;
  for (const auto& r : rep.robots) run_ids.push_back(r.id);
  const MovingMark moving(moving_, std::move(run_ids));  // from the start to the end of the run
  auto acks = co_await broadcast_on(involved, CommandId::start_trajectory, start);
  std::vector<std::uint16_t> not_acked;
  for (auto& r : rep.robots) {
    for (const auto& b : acks) {
      if (b.bus != r.bus) continue;
      if (!b.result) {
        fail(r, RobotState::not_started, fmt::format("start on bus {} failed: {}", bus_name(r.bus),
                                                     b.result.error().message()));
      } else if (const Reply* reply = b.result.value().from(r.id); !reply) {
        fail(r, RobotState::not_started, "did not acknowledge START_TRAJECTORY");
      } else if (!reply->accepted()) {
        fail(r, RobotState::not_started, reply->error().message());
      } else {
        r.state = RobotState::started;
      }
    }
    if (r.state == RobotState::not_started) not_acked.push_back(r.id);
  }
  if (!not_acked.empty()) {
    ++counters_.start_failures;
    rep.outcome = fmt::format("start failed: {} of {} positioners did not acknowledge (listed below); every robot was "
                              "stopped",
                              not_acked.size(), n);
    spdlog::error("fps array: {}", rep.outcome);
    co_await stop_everyone(rep.outcome);
    for (auto& r : rep.robots) {
      if (r.state == RobotState::started) fail(r, RobotState::stopped, "stopped because another robot did not start");
    }
    co_return rep;
  }
  rep.started = true;
  phase_end(rep.timings.start, "started");
  if (!o.wait) {
    rep.outcome = "started; not waiting for the end";
    co_return rep;
  }

  // 6. Wait for every robot to finish, then check where each one ended.
  const auto started_at = core::steady_now();
  co_await for_each_concurrently(n, [&](std::size_t i) -> asio::awaitable<void> {
    auto& r = rep.robots[i];
    Positioner* p = find(r.id);
    const auto duration = std::chrono::duration_cast<core::Duration>(
        std::chrono::duration<double>(traj[i]->duration().seconds()));
    bool seen_moving = false;
    auto done = [&](const PositionerStatus& st) {
      if (!st.idle()) {
        seen_moving = true;
        return false;
      }
      return seen_moving || core::steady_now() - started_at >= duration;
    };
    auto st = co_await p->wait_for(done, duration + o.end_margin, "trajectory");
    if (!st) {
      const auto& e = st.error();
      const auto& collisions = lock_->state().collisions;
      const bool reported = std::any_of(collisions.begin(), collisions.end(),
                                        [&](const Collision& c) { return c.positioner == r.id; });
      if (e == HostErrc::collision || reported) {
        co_return fail(r, RobotState::collided, e.message());
      }
      // The lock's reason is the run's outcome, said once (not on each of 500 robot lines).
      if (e == HostErrc::locked) co_return fail(r, RobotState::stopped, "stopped with every robot (see the outcome)");
      co_return fail(r, RobotState::timeout, e.message());
    }
    auto pos = co_await p->read_position();
    if (!pos) co_return fail(r, RobotState::timeout, pos.error().message());
    r.reached = pos.value();
    const double tol = p->options().position_tolerance;
    if (std::abs(r.reached->alpha - r.target->alpha) > tol || std::abs(r.reached->beta - r.target->beta) > tol) {
      co_return fail(r, RobotState::position_mismatch,
                     fmt::format("ended at alpha {:.4f} beta {:.4f} deg, last point alpha {:.4f} beta {:.4f} "
                                 "(tolerance {} deg)",
                                 r.reached->alpha, r.reached->beta, r.target->alpha, r.target->beta, tol));
    }
    r.state = RobotState::completed;
  });
  // Robots the host stopped watching before they were seen done may still be moving: stop them.
  co_await for_each_concurrently(n, [&](std::size_t i) -> asio::awaitable<void> {
    auto& r = rep.robots[i];
    if (r.state != RobotState::timeout) co_return;
    auto aborted = co_await find(r.id)->abort();
    r.detail += aborted ? "; TRAJECTORY_ABORT sent to it" : fmt::format("; TRAJECTORY_ABORT not sent: {}", aborted.error().message());
  });
  phase_end(rep.timings.move, "finished");
  if (o.final_approach && !lock_->locked()) {
    co_await final_approach(*this, rep);
    phase_end(rep.timings.approach, "approached");
  }
  rep.completed = rep.all(RobotState::completed);
  if (rep.completed) {
    rep.outcome = fmt::format("completed: {} robots at their targets", n);
  } else if (lock_->locked()) {
    rep.outcome = fmt::format("stopped: {}", lock_->state().reason);
  } else {
    rep.outcome = "finished with problems";
  }
  co_return rep;
}

}  // namespace axon::fps::host

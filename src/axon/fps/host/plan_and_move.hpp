// Plan from where the robots are, then move: the whole-plane reconfiguration ("goto all"). Reads
// the position and status of every robot of the layout, plans collision-free trajectories from
// there to the targets (fps/plan: the planner's independent checker must verify the plan), and
// runs them on the array (Array::run_trajectories: upload, start, follow, check positions).
//
// Robots that did not answer are refused (no plan around unknown poses) unless the layout marks
// them offline (then assumed folded); robots that answered but are not ready (collision flag, no
// datum, moving) and robots the layout disables are held where they are. Nothing moves unless the
// checker verified the plan and (without allow_partial) every robot reaches its target.
#pragma once

#include "axon/core/error.hpp"
#include "axon/fps/host/array.hpp"
#include "axon/fps/host/status_table.hpp"
#include "axon/fps/host/trajectory_build.hpp"
#include "axon/fps/host/trajectory_report.hpp"
#include "axon/fps/layout/focal_plane.hpp"
#include "axon/fps/plan/collision.hpp"
#include "axon/fps/plan/planner.hpp"

#include <boost/asio/awaitable.hpp>

#include <functional>
#include <optional>
#include <vector>

namespace axon::fps::host {

struct PlanAndMoveOptions {
  plan::PlannerOptions planner;
  bool allow_partial = false;  // move the others when some robots cannot reach their targets
  // Targets that leave their robots' safe zones (Plan::safe_zone, spec section 11): refused with
  // PlanErrc::outside_safe_zone naming them before anything moves; false: only reported.
  bool refuse_outside_safe_zone = false;
  // Per robot (model order), the fibre whose point its target is (plan::point_fibres): the safe
  // zone's reach check; empty: targets are poses.
  std::vector<std::optional<std::size_t>> point_fibre;
  TrajectoryOptions trajectory;
  // Called with the plan once it is made, before anything moves (a summary, a saved plan.json),
  // also when it is then refused.
  std::function<void(const plan::Plan&)> on_plan;
  // Starts the trajectories instead of Array::run_trajectories (FocalPlaneArray, to start by the
  // PLC's sync line); empty: the array's own.
  std::function<asio::awaitable<Result<TrajectoryReport>>(Trajectories, TrajectoryOptions)> run;
};

struct PlanAndMoveReport {
  plan::Plan plan;
  std::optional<TrajectoryReport> run;  // empty: every robot already stood at its target
  [[nodiscard]] bool ok() const noexcept { return !run || run->completed; }
};

// The planner's request from a status table: current poses in model order (offline robots folded),
// the targets, and the robots that must not move (held at their current pose). Errors
// (HostErrc::unknown_positioner): robots of the layout without a position that are not offline.
[[nodiscard]] Result<plan::PlanRequest> request_from_status(const FocalPlane& plane, const plan::CollisionModel& model,
                                                            const StatusTable& table, std::vector<plan::Pose> targets);

// The whole sequence. `targets`: one pose per robot, model order (plan::target_poses). Errors:
// request_from_status's, the planner's, PlanErrc::robot_collision when the checker rejected the
// plan or robots cannot reach their targets (without allow_partial), PlanErrc::outside_safe_zone
// (with refuse_outside_safe_zone), and run_trajectories' own
// (locked, ...). What the run did per robot is in the report.
asio::awaitable<Result<PlanAndMoveReport>> plan_and_move(Array& array, const FocalPlane& plane,
                                                         const plan::CollisionModel& model, std::vector<plan::Pose> targets,
                                                         PlanAndMoveOptions options = {});

}  // namespace axon::fps::host

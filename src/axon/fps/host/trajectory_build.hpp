// Firmware trajectories built from what a program has: a straight move of both arms between two
// poses, the same for every robot of a status table, and a plan of the path planner. The planner
// (fps/plan) works in degrees and seconds with its start point included; a firmware trajectory
// (protocol::Trajectory) holds quantised points after the start, which the robot adds itself.
#pragma once

#include "axon/core/error.hpp"
#include "axon/fps/host/positioner.hpp"
#include "axon/fps/host/status_table.hpp"
#include "axon/fps/plan/collision.hpp"
#include "axon/fps/plan/planner.hpp"
#include "axon/fps/protocol/trajectory.hpp"

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace axon::fps::host {

using Trajectories = std::map<std::uint16_t, protocol::Trajectory>;

// Both arms from `from` to `to` together, `points` evenly spaced points per arm over `duration_s`
// (the last one at `to`). Errors: points < 1, duration <= 0, angles the firmware cannot take.
[[nodiscard]] Result<protocol::Trajectory> straight_trajectory(ArmAngles from, ArmAngles to, int points, double duration_s);

struct StraightMoves {
  Trajectories trajectories;
  std::map<std::uint16_t, ArmAngles> starts;  // where each of those robots stood
  std::vector<std::string> left_out;          // "positioner 7: no position (timeout)", one per robot
};
// Every robot of `table` that reported its position, straight to `to` (straight_trajectory).
// Robots without a position are left out and listed.
[[nodiscard]] Result<StraightMoves> straight_moves(const StatusTable& table, ArmAngles to, int points, double duration_s);

// The plan's trajectories as firmware trajectories, by robot id. Robots whose arms do not move are
// left out; an arm that does not move gets no points (it stays). Errors name the robot.
[[nodiscard]] Result<Trajectories> plan_trajectories(const plan::CollisionModel& model, const plan::Plan& plan);

// A trajectory file: {robot id: {alpha: [[deg, s], ...], beta: [[deg, s], ...]}} in YAML or JSON,
// one entry per robot, either arm optional. Errors (CoreErrc::invalid_argument, or the trajectory's
// own) are located by file:line and name the robot.
[[nodiscard]] Result<Trajectories> load_trajectory_file(const std::string& path);

}  // namespace axon::fps::host

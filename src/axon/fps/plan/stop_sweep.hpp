// Whether a robot can drive its arms into their hard stops without touching anything: the check
// the protocol document asks for before a datum search or a datum calibration (commands 20-25
// find the zero by running each chosen arm in the negative direction until it hits its stop, and
// a collision on the way would be taken for the stop).
//
// The firmware runs the chosen arms at once. By default both are taken to turn at the same
// angular speed (two identical motors and gears): down the diagonal of angle space until one arm
// reaches its stop, then the other alone. The document does not give the speeds; with
// `simultaneous` off any interleaving is allowed and the whole rectangle
// [stop_alpha, alpha] x [stop_beta, beta] must be clear, which in a full plane a stretched arm
// rarely is. For one arm the region is the line along it. The region is evaluated on a grid of
// `grid_deg` and the poses in between are proven: with only this robot moving, no point of its
// collision segment is farther than (grid/2) * (reach + collision length) (in radians) from where
// it is at the nearest grid pose, so the region is clear when every grid pose keeps at least that
// much. Neighbours stand at their given poses; fixed obstacles are included.
#pragma once

#include "axon/fps/plan/collision.hpp"

#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace axon::fps::plan {

struct StopSweepOptions {
  bool alpha = true;            // which arms go to their stops
  bool beta = true;
  double overtravel_deg = 10;   // the hard stops lie this far below the angle limits (at most)
  double grid_deg = 0.5;
  bool simultaneous = true;     // both arms at the same speed (false: any interleaving, the rectangle)
};

struct StopSweep {
  bool clear = true;
  double min_clearance_mm = 0;  // proven lower bound over the region (negative: a possible contact)
  // The bodies the sweep may touch, nearest first: "robot 12 (-3.214 mm)", "fiducial 7 (-0.5 mm)".
  std::vector<std::string> in_the_way;
};

// Robot `i` of `model` sweeping from poses[i] to its stops; the other robots at their poses
// (poses.size() == model.size()).
StopSweep check_sweep_to_stops(const CollisionModel& model, std::size_t i, std::span<const Pose> poses,
                               const StopSweepOptions& options = {});

// Robot `i` turning one arm ('a' or 'b') alone from poses[i] to `to_deg` and back (the test moves
// of the troubleshooting chapter, 9.4.2 and 9.4.3); the others stand at their poses. A go-to move
// ends with the firmware's precise approach, a back-and-forth of both arms (0.9 deg in the
// simulator), so the region is the rectangle of the turning arm's range widened by `approach_deg`
// at both ends and the other arm within `approach_deg` of where it is. Proven as the stop sweep is,
// on a grid of `grid_deg`; a target outside the arm's angle limits is not clear ("angle limit" in
// in_the_way).
StopSweep check_arm_sweep(const CollisionModel& model, std::size_t i, std::span<const Pose> poses, char arm,
                          double to_deg, double grid_deg = 0.5, double approach_deg = 1.0);

// ---- Backing off ---------------------------------------------------------------------------------
// After a collision the document (9.4.1) asks for the flags to be cleared and the robot moved away
// by at least 2 degrees; after a power loss mid-move, robots that stopped dead may stand inside a
// neighbour's collision buffer, and the planner holds such pairs (docs/fps-plan.md). A back-off is
// one arm of one robot turned by a few degrees (one arm at a time: its path does not depend on the
// speeds), chosen so that it is certified on a grid of `grid_deg`:
// - a body the robot is in contact with, or nearly (closer than the grid's slack), never comes
//   closer along the move than it is at the start, at any grid pose (between grid poses it may, by
//   at most the slack: 0.5 * grid * (reach + collision length) in radians, about 0.01 mm at 0.05 deg);
// - every other body stays clear by the slack (proven in between as for the stop sweep);
// - the arm stays inside its angle limits.
// Of the certified moves the smallest step that ends clear of everything wins, then the one that
// ends farthest from the nearest body; when none ends clear, the one that gains the most.

struct BackOffOptions {
  std::vector<double> steps_deg{2, 3, 4, 6, 8};  // tried in this order (the document's 2 degrees first)
  double grid_deg = 0.05;
};

struct BackOff {
  bool found = false;  // a certified move exists (to, arm, step_deg say which)
  bool clear = false;  // and it ends clear of every body at the full buffer
  Pose from;
  Pose to;
  char arm = 0;        // 'a' or 'b'
  double step_deg = 0; // signed
  double clearance_before_mm = 0;  // the smallest over every body, at the full buffer
  double clearance_after_mm = 0;
  // The bodies within the slack at the start, nearest first: "robot 12 (-0.083 mm)".
  std::vector<std::string> in_contact;
};

// Robot `i` of `model` backing off from poses[i]; the others stand at their poses.
BackOff plan_back_off(const CollisionModel& model, std::size_t i, std::span<const Pose> poses,
                      const BackOffOptions& options = {});

}  // namespace axon::fps::plan

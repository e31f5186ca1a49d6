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

}  // namespace axon::fps::plan

// Untangling after a half: robots the lock-step engine left away from their fold are planned one
// at a time on a grid of their own two angles, everyone else standing still, to a fold (beta at the
// fold angle) at any alpha: the turn to the planned fold alpha happens later, while folded, and the
// search picks the fold that makes the way out and that turn together quickest.
//
// With one robot moving and every other body still, the step certificate is exact: a point of the
// collision segment moves at most |d alpha| * reach + |d beta| * collision length over a step, so
// with clearances c0 and c1 at a step's ends the clearance inside it is at least (c0 + c1 - S) / 2.
// A grid edge is used only where that is positive (and every cell but the start keeps the engine's
// margin). Breadth-first search over the 8-connected grid (one engine step per edge) finds the
// quickest way out if there is one at this resolution.
//
// The stuck robots are grouped in zones (a stuck robot and two rings of neighbours around it, zones
// that overlap merged): no robot one zone's untangle moves is a neighbour of one another's moves,
// so each zone keeps a clock of its own. The engine keeps stuck robots wandering until its stall
// limit (a certified but useless 20 s): a cluster of stuck robots that touch each other has its
// paths cut as soon as every robot next to one of them has stopped for good, and starts from there.
// Turning folded neighbours out of the way waits until everything within two rings has stopped.
// Within a zone robots move in waves: stuck robots that are not neighbours of each other move at
// once (neighbours of a moving robot wait for the next wave, so every plan sees still
// neighbours); waves repeat while they make progress.
#pragma once

#include "axon/fps/plan/collision.hpp"
#include "axon/fps/plan/stepper.hpp"

#include <span>
#include <string>
#include <vector>

namespace axon::fps::plan {

// `robots` and `result` as from drive_to_goals (goals are folds at `fold_beta_deg`). Robots not
// reached whose goal beta is the fold beta are untangled where possible: their paths (cut once their
// neighbours have stopped, the untangle appended), `end`, `reached` and the result's duration
// (the last point of any path) are updated. Returns how many were untangled.
std::size_t untangle_to_fold(const CollisionModel& model, std::span<const StepperRobot> robots, StepperResult& result,
                             const StepperOptions& options, std::size_t max_cells_per_robot = 200'000);

// Whether robot i is boxed in by fixed obstacles: with only the fiducials and other obstacles
// present (every other robot out of the way), a flood fill of its own angle space from `from`
// (the untangle's grids, coarse to fine) finds no fold (beta at `fold_beta`, any alpha). Returns
// the names of the obstacles around it when every grid ran out of cells to visit (a closed pocket
// between obstacles and its angle stops, at the finest resolution); empty when a fold is
// reachable, or when the search hit `max_cells` before deciding (then the engine gets to try).
std::vector<std::string> fold_blocked_by_obstacles(const CollisionModel& model, std::size_t i, Pose from, double fold_beta,
                                                   const StepperOptions& options, std::size_t max_cells = 200'000);

}  // namespace axon::fps::plan

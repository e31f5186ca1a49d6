// The planner's motion engine: drives every robot from a start pose towards a goal pose in
// lock-step time steps, each step certified collision-free over its whole interval.
//
// Every step lasts dt; each arm moves by -step, 0, +step or the rest of the way to its goal (a
// partial step), so each arm's speed is piecewise constant and at most the speed limit. Robots
// take their step one after the other within a time step (in a random order drawn from the seed),
// and each checks its move against every neighbour's move of the same step (neighbours that have
// not moved yet stand still for this check; they check against this robot when their turn comes),
// so every pair is checked once, with both robots moving, by whichever moves later. Standing
// still is therefore always allowed, and the configuration stays clear.
//
// Certificate for one pair over one step: a point of a robot's collision segment moves at most
// |d alpha| * reach + |d beta| * collision length (radians, mm), so the pair's clearance changes
// by at most S (the sum of both robots' bounds) over the step. With clearances c0 and c1 at the
// ends, the clearance anywhere in between is at least (c0 + c1 - S) / 2. Where that is negative,
// the step is halved and both halves are certified the same way, down to a few micrometres. A
// step the certificate rejects is not taken.
//
// Choice of move: greedy, the move that lowers the weighted angle distance to the goal the most
// (beta weighs more than alpha, so arms fold before they turn), preferring the previous move on
// ties so that trajectories keep few corners. A robot that makes no progress for a while is stuck:
// the neighbours blocking its best move that rank lower (a random priority per run) are made to
// escape; if none does, it escapes itself. Escaping robots, for a random number of steps, take the
// move that opens the most clearance (with a random nudge), then go back to greedy. Robots still away from their goal when the time limit is
// reached are reported as stuck, with the neighbours that blocked them.
#pragma once

#include "axon/fps/plan/collision.hpp"
#include "axon/fps/plan/trajectory.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace axon::fps::plan {

// The step certificate's constants, shared by the engine and the untangle (untangle.hpp):
inline constexpr double kCertifyTinyMm = 1e-4;        // the certificate keeps this much above zero
inline constexpr double kCertifyResolutionMm = 0.01;  // a sub-step this short counts as resolved

struct StepperRobot {
  Pose start;
  Pose goal;
  bool frozen = false;  // never moves (held, disabled): an obstacle for the others
  // Optional: the robot follows this trajectory (times from 0) instead of being planned, a moving
  // obstacle for the others (a local re-plan inside a half already planned). Its moves are not
  // checked against each other; every planned robot checks against them, and a planned robot that
  // a scripted one would run into must dodge (see StepperResult::violations).
  const RobotTrajectory* script = nullptr;
};

struct StepperOptions {
  double dt_s = 1.0 / 12.0;      // one step
  double alpha_step_deg = 1.0;   // per step at full speed
  double beta_step_deg = 1.0;
  double margin_mm = 0.05;       // clearance every step's end keeps (or its start value if less)
  double max_duration_s = 90.0;  // give up after this much simulated time
  double stall_s = 20.0;         // or after this long without any robot arriving (0: never)
  std::uint64_t seed = 1;
  double alpha_weight = 1.0;     // cost = weight * |angle to go|, per arm
  double beta_weight = 2.0;
  int stuck_steps = 6;           // steps without progress before a robot escapes
  int escape_min_steps = 3;
  int escape_max_steps = 15;
  double stop_avoid_deg = 0;     // escapes keep this far from the alpha stops while unfolded (0: off)
  // A robot that started this many escapes of its own without ever getting closer to its goal
  // gives up: it stands still for the rest of the run (and no longer yields), stuck (0: never).
  int give_up_after = 0;
  // A robot stuck next to fixed obstacles (fiducials, robots that never move) switches to a
  // navigation field: the grid cost to its goal around them (Dijkstra), followed downhill.
  bool fields = false;
  // Robots (model indices) that rank above every other robot: they step first in every time step
  // (so the others make way) and lower-ranked blockers yield to them. Used to retry a half with
  // the robots that got stuck the last time in front.
  std::vector<std::uint32_t> first;
};

struct StepperResult {
  std::vector<RobotTrajectory> paths;   // per robot, times from 0, few points (lossless)
  std::vector<Pose> end;                // where each robot ended
  std::vector<bool> reached;            // at its goal
  std::vector<std::vector<std::uint32_t>> blockers;  // for robots that did not reach: who blocked
  double duration_s = 0;                // until the last robot stopped
  std::size_t steps = 0;
  std::size_t escapes = 0;              // escape episodes started
  std::size_t pair_checks = 0;          // exact pair certificates evaluated
  // Steps in which a planned robot could neither stand still nor move clear of a scripted robot:
  // the result is then not collision-free and must not be used (only possible with scripts).
  std::size_t violations = 0;
};

// Robots in model order. A pair that starts in contact cannot be certified, so both robots of it
// stay where they are: callers pass a clear start.
StepperResult drive_to_goals(const CollisionModel& model, std::span<const StepperRobot> robots,
                             const StepperOptions& options);

}  // namespace axon::fps::plan

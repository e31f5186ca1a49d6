// The focal-plane path planner: collision-free trajectories for every robot from the current
// poses to the targets, within the firmware's limits (docs/fps-plan.md has the algorithm).
//
// In brief: the move goes through a folded configuration (beta folded back over the robot's own
// centre, where no two robots can touch). Two halves are planned at once, on two threads, by the
// certified lock-step engine (stepper.hpp): from the current poses to the fold, and from the
// targets to the fold (then played backwards). The fold's alpha is chosen per robot so that alpha
// turns during both halves and neither half waits for it. Robots that cannot leave their target
// region are parked folded instead and reported; robots that cannot leave their current pose are
// held there and reported; the rest is re-planned around them. Trajectories keep only the corners
// of the piecewise-constant speed profile; jagged arms are shortened by certified shortcuts
// (smooth.hpp), everything is simplified where that stays clear, and the result is verified by the
// independent checker (checker.hpp: a proof, not a sampling result) at the full buffer (flagged robots fall back to their
// shortcut, then to their exact trajectories: verify_with_fallbacks).
#pragma once

#include "axon/fps/plan/checker.hpp"
#include "axon/fps/plan/collision.hpp"
#include "axon/fps/plan/safe_zone.hpp"
#include "axon/fps/plan/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace axon::fps::plan {

// Arm speeds in degrees per second at the arm.
struct SpeedLimits {
  double alpha_deg_s = 12.0;
  double beta_deg_s = 12.0;

  // From the firmware's motor speed (rpm at the motor) and the motor-to-arm gear ratio:
  // 2000 rpm at 1000:1 is 2 rpm at the arm, 12 deg/s.
  static SpeedLimits from_motor(double motor_rpm, double gear_ratio) noexcept {
    const double deg_s = motor_rpm / gear_ratio * 360.0 / 60.0;
    return {deg_s, deg_s};
  }
};

// The time of the straight move from `a` to `b`, each arm at full speed (the slower arm sets it):
// no plan brings a robot in earlier.
inline double straight_move_s(const Pose& a, const Pose& b, const SpeedLimits& v) noexcept {
  return std::max(std::abs(b.alpha_deg - a.alpha_deg) / v.alpha_deg_s, std::abs(b.beta_deg - a.beta_deg) / v.beta_deg_s);
}

struct PlannerOptions {
  SpeedLimits speed{};
  double step_deg = 1.0;          // engine step of the faster arm (sets the engine's dt)
  double fold_beta_deg = 180.0;   // beta of the folded configuration
  double margin_mm = 0.05;        // clearance the engine keeps at step ends
  double simplify_deg = 0.2;      // per-arm simplification tolerance (0: none); kept only where clear
  double max_half_s = 90.0;       // time limit of each half
  std::uint64_t seed = 1;
  int retries = 3;                // re-planning rounds after parking or holding robots
  int half_retries = 8;           // re-runs of a half that left robots stuck, those robots first
  int relax_after = 8;            // from this retry on, stuck robots fold without turning alpha (8: never)
  int local_retries = 24;         // then re-plans of only the stuck robots' neighbourhood (new seeds)
  int local_rings = 2;            // neighbour rings around the stuck robots re-planned with them
  int tail_retries = 32;          // then re-plans of the last robots' neighbourhood (new seeds), kept when they arrive earlier
  int tail_tries_per_cluster = 12; // tries in a row that bring nothing end them
  double tail_quantile = 0.9;     // late: arriving more than tail_slack_s after this quantile of the arrivals
  double tail_slack_s = 3.0;
  int tail_rings = 1;             // neighbour rings around the late robots re-planned with them
  double fold_spread_deg = 90;    // local re-plans: a stuck robot's fold alpha drawn within this of its start
  double stop_avoid_deg = 0;      // engine escapes keep away from the alpha stops while unfolded (0: off)
  double fold_stop_gap_deg = 0;   // fold alphas kept this far from the alpha stops (0: off)
  double stall_s = 20.0;          // a half ends when no robot has arrived for this long (engine time)
  int give_up_after = 0;          // engine: a robot gives up after this many fruitless escapes (0: never)
  bool untangle = true;           // then robots still stuck are planned one at a time to any fold (untangle.hpp)
  std::size_t smooth_points = 40; // arms with more points are shortened by certified shortcuts (smooth.hpp; 0: off)
  double smooth_clearance_mm = 0.02;  // clearance the shortcuts keep (room for the simplification around them)
  std::size_t max_points = 1023;  // per arm, after the start point (firmware limit)
  bool verify = true;             // run the checker on the result
  CheckOptions check{};           // the checker's settings (full buffer)
  bool parallel = true;           // plan both halves on two threads
  // B starts before A has ended, as early as every robot's own A and B allow, where the checker
  // proves the overlap clear at the full buffer (phases::overlap_shift).
  bool overlap_halves = true;
  // The targets' check against the robots' safe zones (spec section 11, safe_zone.hpp), reported
  // in Plan::safe_zone; it changes nothing in the plan (nullopt: not checked).
  std::optional<SafeZoneOptions> safe_zone = SafeZoneOptions{};
};

struct PlanRequest {
  std::vector<Pose> current;  // one per robot, model order
  std::vector<Pose> target;   // one per robot, model order
  std::vector<bool> frozen;   // optional: robots that must not move (disabled, offline)
  // optional: per robot, the fibre whose focal-plane point its target is (point_fibres(), for the
  // safe zone's reach check); empty or nullopt: an explicit pose.
  std::vector<std::optional<std::size_t>> point_fibre;
};

struct RobotPlan {
  enum class Status : std::uint8_t {
    reached,  // ends at its target
    frozen,   // asked not to move
    parked,   // its target could not be reached: ends folded (see reason, blockers)
    held,     // could not leave its current pose safely: stays there (see reason, blockers)
  };
  Status status = Status::reached;
  Pose end;                             // where it ends
  std::string reason;                   // for parked and held
  std::vector<std::int32_t> blockers;   // robot ids in its way
};
std::string_view to_string(RobotPlan::Status s) noexcept;

struct PlanStats {
  double plan_s = 0;             // wall time of plan_moves
  double setup_s = 0;            // of which the checks before the engine (contacts, boxed-in robots, targets)
  double search_s = 0;           // of which the engine
  double check_s = 0;            // of which the checker
  double smooth_s = 0;           // of which the shortcuts (smooth.hpp)
  std::size_t checks = 0;        // checker runs (1 + fallback passes)
  double duration_s = 0;         // the move
  double middle_s = 0;           // of which the middle phase (folded robots turning alpha)
  double overlap_s = 0;          // B started this much before A and the middle ended (overlap_halves)
  std::size_t rounds = 0;        // engine rounds (1 + re-plans)
  std::size_t escapes = 0;       // escape episodes (deadlock nudges)
  std::size_t simplified = 0;    // robots whose simplified trajectories were kept
  std::size_t smoothed = 0;      // robots whose shortcut (smoothed) trajectories were kept
  std::size_t median_points = 0; // per arm, after the start point, over moving arms
  std::size_t max_points = 0;
  double max_alpha_speed = 0;    // deg/s
  double max_beta_speed = 0;
};

struct Plan {
  std::vector<RobotTrajectory> trajectories;  // one per robot: times from 0, first point = current pose
  std::vector<RobotPlan> robots;              // one per robot
  std::size_t not_reached = 0;                // parked + held
  bool verified = false;                      // the checker ran and found no contact
  CheckReport check;                          // the checker's report (if verify)
  SafeZoneReport safe_zone;                   // targets outside their robots' safe zones (if checked)
  PlanStats stats;

  [[nodiscard]] bool ok() const noexcept { return not_reached == 0 && (verified || check.samples == 0); }
  // Robot by robot: every parked or held robot and why.
  [[nodiscard]] std::string summary(const CollisionModel& model) const;
};

// Errors: PlanErrc::bad_trajectory when the request's sizes do not match the model or an angle is
// not finite; robot_collision / obstacle_collision naming the pairs when the current poses
// already collide (the planner cannot certify any move out of a contact). Targets that collide
// with each other or with fixed obstacles are not errors: the later robot is parked (reported).
Result<Plan> plan_moves(const CollisionModel& model, const PlanRequest& request, const PlannerOptions& options = {});

// Ramer-Douglas-Peucker on one arm's (time, angle) points: drops points while the angle stays
// within `tolerance_deg` of the original at every dropped point's time. Speeds never increase.
std::vector<TimedAngle> simplify_arm(std::span<const TimedAngle> points, double tolerance_deg);

// Verification with fallbacks: `layers` are whole plans (one trajectory per robot each), from the
// most processed (layers[0]) to the one certified by construction (the last). Every robot starts
// on layer 0; the checker checks the plan, and every robot of a pair it flags moves on to its next
// layer that differs from its current trajectory; then the plan is checked again, until the
// checker is satisfied, nothing is left to fall back to, or `max_passes` checks ran. `out` gets
// the trajectories, `level[i]` the layer robot i ends on, `report` the last check. Returns the
// number of checks run.
Result<std::size_t> verify_with_fallbacks(const CollisionModel& model, std::span<const std::vector<RobotTrajectory>> layers,
                                   const CheckOptions& options, std::vector<RobotTrajectory>& out,
                                   std::vector<std::size_t>& level, CheckReport& report, int max_passes = 8);

}  // namespace axon::fps::plan

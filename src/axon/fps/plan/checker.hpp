// Collision check of a whole move, independent of any planner: dense samples, and a proof between them.
//
// Every robot follows its alpha and beta trajectories (linear between points). The checker picks
// one time step for the move such that no point of any collision segment travels more than
// `max_step_mm` between two samples: a point at distance r from an axis turning at w rad/s moves
// at most w * r, so with alpha speed wa and beta speed wb (the fastest segment of each robot)
// a step dt moves any point of the segment at most (wa * reach + wb * collision length) * dt.
// At every sample it evaluates the exact segment distances of the neighbour pairs and the
// robot-obstacle pairs, and keeps per pair the first sample in collision and the smallest
// clearance. Between samples nothing is left to chance: a pair's clearance changes no faster than
// the sum of its two bodies' fastest point speeds (rate), so over an interval of dt it stays at or
// above (c0 + c1 - rate * dt) / 2, c0 and c1 being the clearances at its ends. Where that bound is
// negative while both ends are clear, the interval is halved (exact clearance at the midpoint)
// until it is proven clear or a contact shows; after 12 halvings the negative bound itself counts
// as a contact. A clean report is therefore a proof, not a sampling result (docs/fps-plan.md).
//
// The sample range is split over threads in contiguous blocks. A checker keeps its scratch
// storage between calls and fills a caller-owned report, so repeated checks allocate nothing
// once warmed up (with threads = 1; more threads start std::threads per call).
#pragma once

#include "axon/fps/plan/collision.hpp"
#include "axon/fps/plan/trajectory.hpp"

#include <cstddef>
#include <limits>
#include <span>
#include <vector>

namespace axon::fps::plan {

struct CheckOptions {
  double max_step_mm = 0.05;  // largest travel of any arm point between samples
  unsigned threads = 0;       // 0: std::thread::hardware_concurrency()
  bool obstacles = true;      // also check robot-obstacle pairs
  // A pair whose bodies never move (two robots standing still throughout, or a standing robot and
  // an obstacle) keeps the clearance it started with: a contact there is the start's, not the
  // move's (the planner holds robots that start in contact). true: such contacts are counted in
  // standing_contacts, not in collided_pairs, and left out of min_clearance_mm; false (a check of
  // poses: every contact counts): collisions. The planner's verification sets it.
  bool allow_standing_contacts = false;
};

struct PairOutcome {
  bool collided = false;
  double first_collision_s = std::numeric_limits<double>::quiet_NaN();
  double min_clearance_mm = std::numeric_limits<double>::infinity();
  double min_clearance_s = std::numeric_limits<double>::quiet_NaN();
  bool standing = false;  // neither body moves during the whole move

  // A contact the move made: not a standing one that `o` allows.
  [[nodiscard]] bool move_collided(const CheckOptions& o) const noexcept {
    return collided && !(standing && o.allow_standing_contacts);
  }
};

struct CheckReport {
  // Parallel to CollisionModel::robot_pairs() and obstacle_pairs().
  std::vector<PairOutcome> robot_pairs;
  std::vector<PairOutcome> obstacle_pairs;
  double start_s = 0;
  double end_s = 0;
  double step_s = 0;
  std::size_t samples = 0;
  std::size_t collided_pairs = 0;  // robot and obstacle pairs that collided at least once
  std::size_t standing_contacts = 0;  // pairs in contact that never move (allow_standing_contacts)
  std::size_t halvings = 0;           // sample intervals halved to prove a close pair clear
  double min_clearance_mm = std::numeric_limits<double>::infinity();  // over the pairs that count

  [[nodiscard]] bool ok() const noexcept { return collided_pairs == 0; }
  // Pair evaluations done (samples x pairs checked).
  [[nodiscard]] std::size_t evaluations() const noexcept {
    return samples * (robot_pairs.size() + obstacle_pairs.size());
  }
};

class TrajectoryChecker {
 public:
  explicit TrajectoryChecker(const CollisionModel& model) : model_(&model) {}

  // trajectories: one per robot in model order. Errors: PlanErrc::bad_trajectory (wrong count, or
  // a trajectory that fails validate()).
  Result<void> check(std::span<const RobotTrajectory> trajectories, const CheckOptions& options, CheckReport& out);

 private:
  struct Worker {
    std::vector<Pose> poses;
    std::vector<Segment> segs;
    std::vector<Vec2> mid;      // segment midpoints
    std::vector<double> half;   // half the segment lengths
    std::vector<double> prev_robot, prev_obstacle;  // per pair: clearance (or a lower bound) at the last sample
    std::size_t halvings = 0;
    std::vector<AngleCursor> alpha, beta;
    std::vector<PairOutcome> robot_pairs, obstacle_pairs;
  };
  void run(Worker& w, std::span<const RobotTrajectory> trajectories, std::size_t first, std::size_t last,
           const CheckReport& shape, bool obstacles) const;

  const CollisionModel* model_;
  std::vector<double> speed_;  // per robot: fastest point speed of its segment in this move, mm/s
  std::vector<Worker> workers_;
};

}  // namespace axon::fps::plan

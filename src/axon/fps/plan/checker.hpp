// Collision check of a whole move, independent of any planner, that cannot miss a contact.
//
// Every robot follows its alpha and beta trajectories (linear between points). A point at distance
// r from an axis turning at w rad/s moves at most w * r, so a robot's collision segment moves no
// point faster than wa * reach + wb * collision length (wa, wb: its arms' speeds), and a pair's
// clearance (distance minus both buffers) changes no faster than the sum of its two bodies' bounds.
// Two methods use that bound:
//
// - advancing (the default): each pair walks its own time line. From the clearance c at t, with
//   V the pair's bound over the stretch where all four arms keep their speeds (trajectory points
//   end stretches), the clearance cannot reach 0 before t + c / V: the next evaluation is there
//   (closer when the reported minimum must be precise, see CheckOptions), or at the end of the
//   stretch. Pairs that stand still are evaluated once per stretch, far pairs rarely, close pairs
//   often. A step that would have to be shorter than `min_step_s` is taken with its bound, which
//   then counts as a contact (a pair touching within about V x 1 us, 1e-5 mm, is reported as one).
// - dense: one time step for the whole move, such that no point of any collision segment travels
//   more than `max_step_mm` between two samples, every pair evaluated at every sample; between
//   samples the interval is proven with the two-ended bound (c0 + c1 - rate * dt) / 2 and halved
//   where that is negative, up to 12 halvings (then the bound counts as a contact).
//
// Both give a proof at the full buffer, not a sampling result (docs/fps-plan.md). Pairs (advancing)
// or samples (dense) are split over threads in contiguous blocks; the report does not depend on
// the thread count. A checker keeps its scratch storage between calls and fills a caller-owned
// report, so repeated checks allocate nothing once warmed up (with threads = 1; more threads start
// std::threads per call).
#pragma once

#include "axon/fps/plan/collision.hpp"
#include "axon/fps/plan/trajectory.hpp"

#include <cstddef>
#include <limits>
#include <span>
#include <vector>

namespace axon::fps::plan {

enum class CheckMethod { advancing, dense };

struct CheckOptions {
  CheckMethod method = CheckMethod::advancing;
  double max_step_mm = 0.05;  // dense: largest travel of any arm point between samples
  // advancing: a pair's true smallest clearance is at least min(its reported one,
  // precise_below_mm) - precision_mm (steps are shortened to keep that), and never below 0 for a
  // pair reported clear.
  double precision_mm = 0.05;
  double precise_below_mm = 1.0;
  double min_step_s = 1e-6;  // advancing: a shorter step is not proven, its bound is noted
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
  double step_s = 0;        // dense: the time step (advancing: 0)
  std::size_t samples = 0;  // dense: sample instants; advancing: the evaluations of the busiest pair
  std::size_t pair_evaluations = 0;  // exact clearances computed (both methods)
  std::size_t collided_pairs = 0;  // robot and obstacle pairs that collided at least once
  std::size_t standing_contacts = 0;  // pairs in contact that never move (allow_standing_contacts)
  std::size_t halvings = 0;           // dense: sample intervals halved to prove a close pair clear
  std::size_t forced_steps = 0;       // advancing: steps shorter than min_step_s, noted as bounds
  double min_clearance_mm = std::numeric_limits<double>::infinity();  // over the pairs that count

  [[nodiscard]] bool ok() const noexcept { return collided_pairs == 0; }
  // Pair evaluations done.
  [[nodiscard]] std::size_t evaluations() const noexcept { return pair_evaluations; }
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
    std::size_t evaluations = 0, busiest = 0, forced = 0;  // advancing
    std::vector<AngleCursor> alpha, beta;
    std::vector<PairOutcome> robot_pairs, obstacle_pairs;
  };
  void run(Worker& w, std::span<const RobotTrajectory> trajectories, std::size_t first, std::size_t last,
           const CheckReport& shape, bool obstacles) const;
  void check_dense(std::span<const RobotTrajectory> trajectories, const CheckOptions& options, double point_speed,
                   unsigned threads, CheckReport& out);
  void check_advancing(std::span<const RobotTrajectory> trajectories, const CheckOptions& options, unsigned threads,
                       CheckReport& out);
  void summarize(const CheckOptions& options, CheckReport& out) const;
  template <class Work>
  void split(std::size_t count, unsigned threads, const Work& work);
  // Advancing: pairs [first, last) of robot pairs followed by obstacle pairs, written into `out`.
  void advance(Worker& w, std::span<const RobotTrajectory> trajectories, std::size_t first, std::size_t last,
               const CheckOptions& options, CheckReport& out) const;

  const CollisionModel* model_;
  std::vector<double> speed_;  // per robot: fastest point speed of its segment in this move, mm/s
  std::vector<Worker> workers_;
};

}  // namespace axon::fps::plan

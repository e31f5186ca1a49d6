// One half of a plan (A: from the current poses to the folds; B: from the targets to the folds) as
// engine runs: the first run, re-runs while robots get stuck, local repairs of the stuck robots'
// neighbourhood, the untangle, and the tail (the neighbourhood of the robots that arrive last
// planned again until they arrive earlier). Every step keeps a run only when no scripted robot was
// run into, so what drive_half returns is as certified as a single engine run.
#pragma once

#include "axon/fps/plan/collision.hpp"
#include "axon/fps/plan/planner.hpp"
#include "axon/fps/plan/stepper.hpp"

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace axon::fps::plan::half {

// Cores a half may borrow to run the second engine run of a pair (a local repair's or the tail's)
// beside the first: the halves run on a thread each, and one that has finished lends its core to
// the other (more on a machine with more cores). Thread-safe. Plans never depend on it: a pair's
// runs are the same runs whether they go side by side or one after the other.
class SpareCores {
 public:
  explicit SpareCores(int spare = 0) noexcept : spare_(spare) {}
  [[nodiscard]] bool take() noexcept;  // one core, when one is spare
  void give() noexcept;                // a core back, or lent by a half that has finished
 private:
  std::atomic<int> spare_;
};

// The local repairs and the tail draw from seeds of their own: the half's seed with these mixed in.
inline constexpr std::uint64_t kLocalRepairSeedSalt = 0x9e3779b97f4a7c15ULL;
inline constexpr std::uint64_t kTailSeedSalt = 0x7f4a7c159e3779b9ULL;

// The half: re-run while robots get stuck (options.half_retries; those stuck so far step first,
// from relax_after on they keep their start alpha), the run with the fewest stuck (then the
// shortest) kept and `robots` given its goals; then repair_locally, the untangle (options.untangle)
// and shorten_tail, whose pairs of runs may borrow from `cores`. `runs` counts the engine runs.
// The result does not depend on `cores` (nullptr: none to borrow).
StepperResult drive_half(const CollisionModel& model, std::vector<StepperRobot>& robots, StepperOptions so,
                         const PlannerOptions& o, std::size_t& runs, SpareCores* cores = nullptr);

// The stuck robots and options.local_rings rings of neighbours planned again with new seeds (the
// ring around them follows its paths of `best`, scripted), two tries at a time on the same patch
// (side by side on a core borrowed from `cores`); the clean try that leaves the fewest of the
// patch stuck, fewer than `best`, replaces the patch's paths in `best`. options.local_retries runs
// at most. The result does not depend on `cores`.
void repair_locally(const CollisionModel& model, std::vector<StepperRobot>& robots, StepperResult& best,
                    StepperOptions so, const PlannerOptions& o, std::size_t& runs, SpareCores* cores = nullptr);

// The robots that arrive late in `best`: more than options.tail_slack_s after the
// options.tail_quantile of the moving robots' arrivals, and more than tail_slack_s after their own
// straight move would (a re-plan cannot bring them in before that). Robots left short are not late.
std::vector<bool> late_robots(const std::vector<StepperRobot>& robots, const StepperResult& best,
                              const PlannerOptions& o);

// The tail: the late robots around the last one and options.tail_rings rings of neighbours planned
// again (late robots first, a new seed per try), two tries at a time on the same patch (side by
// side on a core borrowed from `cores`); in the second the late robots turn less alpha here,
// leaving the rest to the middle phase, and must then win more than the middle can lose. A try
// wins when it is clean, leaves no more of the patch short and the patch's last arrival comes at
// least half a step earlier; the earlier of two winners is kept. Ends when nobody is late, after
// options.tail_tries_per_cluster fruitless tries in a row, or after options.tail_retries runs.
// The result does not depend on `cores`.
void shorten_tail(const CollisionModel& model, std::vector<StepperRobot>& robots, StepperResult& best,
                  StepperOptions so, const PlannerOptions& o, std::size_t& runs, SpareCores* cores = nullptr);

}  // namespace axon::fps::plan::half

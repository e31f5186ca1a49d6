// The phases of plan_moves (planner.hpp), one function each, in the order the driver runs them:
//
//   check_request        sizes, finite angles, positive speeds
//   prepare              frozen robots, robots starting in contact, the safe zone report, targets
//                        outside the limits, robots boxed in by fixed obstacles
//   settle_targets       targets that touch each other or an obstacle: park or hold until none do
//   search_rounds        rounds of choose_folds -> run_halves -> take_stuck_robots -> run_middle,
//                        re-settling the targets after each round that parked or held a robot
//   finish_parked        robots parked because half B got stuck try forwards from their fold
//   join_halves          A, the middle phase, reversed B and the finish joined per robot
//   smooth_and_simplify  the fallback layers: simplified, smoothed (if any), exact
//   verify_layers        the checker, robots of a flagged pair falling back one layer at a time
//   collect_stats        points, speeds and the move's duration
//
// Internal to the planner and its tests: installed with the other headers, but not part of the
// documented interface (it follows the algorithm). Every phase reads one Context (the request and
// the PlannerOptions it was given) and changes the Work it is handed.
#pragma once

#include "axon/fps/plan/planner.hpp"
#include "axon/fps/plan/stepper.hpp"

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace axon::fps::plan::phases {

// Seeds of the engine runs, all derived from PlannerOptions::seed (s): changing one changes plans.
inline constexpr std::uint64_t kHalfASeed = 1;           // half A runs on 2s+1
inline constexpr std::uint64_t kHalfBSeed = 2;           // half B runs on 2s+2 (never A's seed)
inline constexpr std::uint64_t kMiddleSeed = 77;         // the middle phase runs on 2s+77
inline constexpr std::uint64_t kFinishSeed = 99;         // finish pass k runs on 2s+99+k
inline constexpr std::uint64_t kRoundSeedStride = 7919;  // each search round adds this prime to A, B and middle seeds
inline constexpr std::uint64_t kExtraASeedStep = 104729; // the extra A run (folds B gave up) adds this prime to A's seed
// (within a half, the local repairs and the tail mix half::kLocalRepairSeedSalt and kTailSeedSalt in)

// Guards of the loops.
inline constexpr std::size_t kSettleChangesPerRobot = 4;  // settle_targets: at most 4n+4 contacts resolved (a robot ...
inline constexpr std::size_t kSettleChangesExtra = 4;     // ... changes at most twice, parked then held: room to spare)
inline constexpr int kExtraRounds = 8;                    // search rounds allowed beyond 1 + PlannerOptions::retries
inline constexpr int kFinishPasses = 4;                   // finish_parked: engine runs at most
inline constexpr double kSimplifyMinToleranceDeg = 1e-3;  // simplification starts at least this coarse
inline constexpr double kSimplifyMaxToleranceDeg = 10;    // and doubles until it fits, giving up past this
inline constexpr double kSameInstantS = 1e-9;             // joined points closer in time than this are one point
inline constexpr int kMiddleStartRounds = 4;              // middle_starts: checker runs at most

// The reason of a robot parked because half B could not bring it from its target to the fold
// (finish_parked looks for it).
inline constexpr const char* kReverseStuck = "its target cannot be reached from the fold without a collision";

// What every phase reads. Holds references: the model, request and options outlive it.
struct Context {
  const CollisionModel& model;
  const PlanRequest& request;
  const PlannerOptions& options;
  StepperOptions engine;                          // every engine run starts from these (its seed set per run)
  std::chrono::steady_clock::time_point started;  // when plan_moves began (the timing stats)

  [[nodiscard]] std::size_t size() const noexcept { return model.size(); }
  // The fold beta of robot i (the option, within its limits), and its parking pose: its current
  // alpha, folded.
  [[nodiscard]] double fold_beta(std::size_t i) const;
  [[nodiscard]] Pose park_pose(std::size_t i) const;
  // Robot ids of model indices.
  [[nodiscard]] std::vector<std::int32_t> ids_of(const std::vector<std::uint32_t>& indices) const;
};

// The engine settings from the options (dt from the faster arm's step).
Context make_context(const CollisionModel& model, const PlanRequest& request, const PlannerOptions& options,
                     std::chrono::steady_clock::time_point started = std::chrono::steady_clock::now());

// What the phases decide on the way, robot by robot.
struct Work {
  Plan plan;                // statuses and reasons so far; trajectories and stats as phases fill them
  std::vector<Pose> target; // where each robot aims now (parked: its fold; still: its current pose)
  std::vector<bool> still;  // frozen or held: stays at its current pose throughout
};

// Errors (PlanErrc::bad_trajectory) for a request whose sizes do not match the model, with an
// angle that is not finite, or options with a speed or step that is not positive.
Result<void> check_request(const CollisionModel& model, const PlanRequest& request, const PlannerOptions& options);

// Every robot reached (frozen as asked), then: robots starting in contact held, the targets' safe
// zone report, targets outside the angle limits parked, robots boxed in by obstacles held (at the
// start) or parked (at the target).
Work prepare(const Context& ctx);

// Until no target touches another robot's target or an obstacle (robots that stay are left
// alone): one contact at a time, the robot that moves (of two that move, the later) is parked at
// its fold; a robot already folded makes the other give way, or, if that one stays, is held.
void settle_targets(const Context& ctx, Work& w);

// The folds of both halves (StepperRobot: start and goal per robot) and the folds a half gave up.
struct Folds {
  std::vector<StepperRobot> a;  // half A: current pose -> fold
  std::vector<StepperRobot> b;  // half B: target -> fold (played backwards by join_halves)
  std::vector<bool> relax_a;    // A gave up turning alpha: A's fold is at the current alpha
  std::vector<bool> relax_b;    // B gave up turning alpha: B's fold is at the target alpha
};
Folds no_folds(std::size_t n);

// The fold of every robot that moves: beta folded, alpha turned towards the target by as much as
// half B's beta work leaves time for (the rest happens in A), kept off the alpha stops when
// fold_stop_gap_deg asks; a relaxed half keeps its own alpha. Robots that stay stand still.
void choose_folds(const Context& ctx, const Work& w, Folds& f);

// The engine results of the last round, and the engine's wall time over all of them.
struct Search {
  StepperResult a;       // half A
  StepperResult b;       // half B (forwards: from the targets)
  StepperResult middle;  // the middle phase (empty when no robot turned while folded)
  double search_s = 0;
};

// Both halves of round `round` (two threads if options.parallel), each re-run while robots get
// stuck; then robots whose B fold was given up get A to turn them to the target alpha instead
// (one more A run). `f` gets the goals the runs ended up with and the relax flags.
void run_halves(const Context& ctx, const Work& w, Folds& f, int round, Search& s);

// Robots a half left stuck: stuck in A, held at the current pose; stuck in B, parked. Returns
// whether any was.
bool take_stuck_robots(const Context& ctx, Work& w, const Search& s);

// The middle phase: robots whose A and B folds differ turn alpha from one to the other while
// folded (the engine, everyone else standing still). Robots that cannot are parked (their relax
// flags cleared). Returns whether any was.
bool run_middle(const Context& ctx, Work& w, Folds& f, int round, Search& s);

// The rounds: until a round parks or holds nobody, then the targets are settled again (error
// PlanErrc::robot_collision after 1 + retries + kExtraRounds rounds).
Result<void> search_rounds(const Context& ctx, Work& w, Search& s);

// Robots parked with kReverseStuck whose target is within limits, driven forwards from where B
// starts (everyone else at rest at their ends) to their targets; a pass that leaves some short
// drops them and runs again with the rest (kFinishPasses at most).
struct Finish {
  StepperResult run;    // the last pass (empty unless `any`)
  std::vector<bool> in; // robots that reach their targets this way
  bool any = false;
};
Finish finish_parked(const Context& ctx, Work& w, Search& s);

// When each robot's middle-phase turn starts: as soon as it has arrived in A, where the checker
// proves the turns clear of the robots still in A (at the full buffer, from the first turn to the
// end of A and the turns). The robots of a pair in contact turn at A's end instead and the check
// repeats (kMiddleStartRounds runs at most, then every turn at A's end). At A's end (the engine's
// certified middle run) also for robots that arrive within a step of it, and for all when
// options.overlap_halves is off. Folded robots cannot touch each other: only robots still in A
// are in question.
std::vector<double> middle_starts(const Context& ctx, const Search& s, std::size_t& checks, double& check_s);

// How much earlier than at `ta` (the end of A and the middle, appended to s.a) reversed B (tb
// long) can start. The most any robot allows: B may not move it before it has arrived in A, so
// the smallest over the robots of the time from its A arrival to ta plus its B departure. Whether
// robots still in A and robots already in B pass each other clear is proven by the checker on the
// overlap window (the full buffer; before and after it the engine's certificates hold): the first
// of that shift, 3/4, 1/2 and 1/4 of it that checks clear is taken, else 0 (and 0 when
// options.overlap_halves is off). `checks` counts the checker runs, `check_s` their time.
double overlap_shift(const Context& ctx, const Search& s, double ta, double tb, std::size_t& checks, double& check_s);

// Per robot: A, the middle phase appended to it (from middle_starts on), B reversed (from the end
// of both minus overlap_shift on), then the finish; still points dropped. Fills the plan's trajectories, every robot's end, not_reached,
// middle_s, overlap_s and search_s.
void join_halves(const Context& ctx, Work& w, Search& s, const Finish& fin);

// The layers verify_layers falls back through, most processed first: simplified, smoothed (only
// when a shortcut was taken), exact (the joined trajectories, certified by the engine).
struct Layers {
  std::vector<std::vector<RobotTrajectory>> plans;
  std::vector<bool> smoothed;    // per robot: a shortcut was taken (then: and kept)
  std::vector<bool> simplified;  // per robot: simplified (then: and kept)
  std::vector<std::size_t> level;  // per robot, after verify_layers: the layer it ends on
};

// Shortcuts on the jagged arms (smooth_points), then each robot simplified from the smoothed (or
// exact) layer within simplify_deg, coarser when over max_points. Sets smooth_s.
Layers smooth_and_simplify(const Context& ctx, Work& w);

// The checker with fallbacks (verify_with_fallbacks) when options.verify, else layer 0 as it is;
// the plan gets the trajectories, the report, checks and check_s; the layers' flags keep only the
// robots still on their simplified / a smoothed layer.
Result<void> verify_layers(const Context& ctx, Work& w, Layers& layers);

// The statistics of the final trajectories (points, speeds, duration; simplified, smoothed).
void collect_stats(Work& w, const Layers& layers);

}  // namespace axon::fps::plan::phases

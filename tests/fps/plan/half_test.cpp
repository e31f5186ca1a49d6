// One half's engine runs (half.hpp): which robots count as late, and the tail re-plans that bring
// them in earlier without running into anyone.
#include "axon/fps/plan/half.hpp"
#include "axon/fps/plan/checker.hpp"
#include "axon/fps/plan/phases.hpp"
#include "axon/fps/plan/problems.hpp"
#include "model_util.hpp"
#include "support/short_run.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

// A named namespace: in the unity build this file shares a translation unit with other tests.
namespace axon::fps::plan::half_test {

using test::build;
using test::hex_patch;
using test::pts;
using test::robot_at;

double arrival(const RobotTrajectory& t) { return std::max(t.alpha.back().t_s, t.beta.back().t_s); }


// Robots 100 mm apart in a row (nobody can touch anybody), each turning alpha by `turn[i]`.
struct Row {
  CollisionModel model;
  std::vector<StepperRobot> robots;
  explicit Row(const std::vector<double>& turn) : model(make(turn.size())) {
    for (const double d : turn) robots.push_back({Pose{90, 180}, Pose{90 + d, 180}, false});
  }
  static CollisionModel make(std::size_t n) {
    std::vector<RobotSpec> specs;
    for (std::size_t i = 0; i < n; ++i) specs.push_back(robot_at(static_cast<std::int32_t>(i + 1), 100.0 * i, 0));
    return build(specs);
  }
};

// An engine result where robot i moves straight from start to goal, arriving at arrive[i].
StepperResult arriving(const std::vector<StepperRobot>& robots, const std::vector<double>& arrive) {
  StepperResult r;
  for (std::size_t i = 0; i < robots.size(); ++i) {
    r.paths.push_back(RobotTrajectory::linear(robots[i].start, robots[i].goal, 0, arrive[i]));
    r.end.push_back(robots[i].goal);
    r.reached.push_back(true);
    r.blockers.emplace_back();
    r.duration_s = std::max(r.duration_s, arrive[i]);
  }
  return r;
}

// Half A (current poses to the folds) of `request` as the planner sets it up, with its engine
// options and `seed`.
struct HalfA {
  std::vector<StepperRobot> robots;
  StepperOptions engine;
};
HalfA half_a(const CollisionModel& model, const PlanRequest& request, const PlannerOptions& o, std::uint64_t seed) {
  const phases::Context ctx = phases::make_context(model, request, o);
  phases::Work w = phases::prepare(ctx);
  phases::settle_targets(ctx, w);
  phases::Folds f = phases::no_folds(model.size());
  phases::choose_folds(ctx, w, f);
  HalfA out{f.a, ctx.engine};
  out.engine.seed = seed;
  return out;
}

TEST(PlanHalf, LateRobotsArriveWellAfterTheOthersAndCouldArriveEarlier) {
  // 26 robots turn 10 degrees and arrive at 1 s; robot 10 turns 10 degrees but arrives at 20 s
  // (late); robot 11 turns 240 degrees (20 s at 1 degree per 1/12 s) and arrives at 21 s (no
  // re-plan brings it in much earlier: not late); robot 12 arrives at 20 s but stopped short (a
  // repair's business, not the tail's); robot 13 is frozen.
  std::vector<double> turn(30, 10.0);
  turn[11] = 240;
  Row row(turn);
  row.robots[13].frozen = true;
  std::vector<double> arrive(30, 1.0);
  arrive[10] = 20;
  arrive[11] = 21;
  arrive[12] = 20;
  arrive[13] = 0;
  StepperResult best = arriving(row.robots, arrive);
  best.reached[12] = false;
  const PlannerOptions o;
  const std::vector<bool> late = half::late_robots(row.robots, best, o);
  for (std::size_t i = 0; i < late.size(); ++i) EXPECT_EQ(late[i], i == 10) << "robot " << i;

  // Nobody is late when everyone arrives together, and when nobody moves.
  const std::vector<bool> together = half::late_robots(row.robots, arriving(row.robots, std::vector<double>(30, 5.0)), o);
  EXPECT_EQ(std::count(together.begin(), together.end(), true), 0);
  const Row still(std::vector<double>(3, 0.0));
  const std::vector<bool> nobody = half::late_robots(still.robots, arriving(still.robots, {0, 0, 0}), o);
  EXPECT_EQ(std::count(nobody.begin(), nobody.end(), true), 0);
}

TEST(PlanHalf, ShortenTailBringsADelayedRobotInAtItsOwnPaceAndLeavesTheOthers) {
  // Everyone turns 30 degrees (2.5 s); robot 4's path waits 20 s before it moves.
  Row row(std::vector<double>(10, 30.0));
  StepperOptions so;
  StepperResult best = drive_to_goals(row.model, row.robots, so);
  ASSERT_EQ(std::count(best.reached.begin(), best.reached.end(), false), 0);
  const std::vector<RobotTrajectory> before = best.paths;
  best.paths[4] = RobotTrajectory::linear(row.robots[4].start, row.robots[4].goal, 20, 22.5);
  best.paths[4].alpha.insert(best.paths[4].alpha.begin(), {0, row.robots[4].start.alpha_deg});
  best.paths[4].beta.insert(best.paths[4].beta.begin(), {0, row.robots[4].start.beta_deg});
  best.duration_s = 22.5;

  std::size_t runs = 0;
  half::shorten_tail(row.model, row.robots, best, so, PlannerOptions{}, runs);
  EXPECT_GE(runs, 1u);
  EXPECT_TRUE(best.reached[4]);
  EXPECT_EQ(best.end[4], row.robots[4].goal);
  EXPECT_LE(arrival(best.paths[4]), 30 * so.dt_s + so.dt_s);  // its straight move, 2.5 s
  EXPECT_LT(best.duration_s, 3.0);
  for (std::size_t i = 0; i < 10; ++i) {
    if (i == 4) continue;
    EXPECT_EQ(best.paths[i].alpha.size(), before[i].alpha.size()) << "robot " << i;
    EXPECT_EQ(arrival(best.paths[i]), arrival(before[i])) << "robot " << i;
  }
}

TEST(PlanHalf, TheTailNeverLengthensAHalfNorLeavesMoreShortAndStaysContactFree) {
  // Half A of small crowded problems (37 robots, folded lattice to random targets), without and
  // with the tail re-plans. Where robots were late, the half with the tail ends no later, leaves
  // no more robots short, and the checker proves its paths contact-free; on some it ends earlier.
  const CollisionModel model = build(hex_patch(3));
  int late_seen = 0, shortened = 0;
  const auto seeds = static_cast<std::uint64_t>(test_support::cases(12));
  for (std::uint64_t seed = 1; seed <= seeds; ++seed) {
    PlanRequest request;
    request.current = random_poses(model, 100 + seed);
    request.target = random_poses(model, 200 + seed);
    PlannerOptions off;
    off.tail_retries = 0;
    const PlannerOptions on;
    const HalfA half = half_a(model, request, off, seed);
    const StepperOptions& so = half.engine;
    std::vector<StepperRobot> robots_off = half.robots, robots_on = half.robots;
    std::size_t runs = 0;
    const StepperResult a = half::drive_half(model, robots_off, so, off, runs);
    const std::vector<bool> late = half::late_robots(robots_off, a, on);
    if (std::count(late.begin(), late.end(), true) == 0) continue;
    ++late_seen;
    const StepperResult b = half::drive_half(model, robots_on, so, on, runs);
    EXPECT_LE(b.duration_s, a.duration_s) << "seed " << seed;
    EXPECT_LE(std::count(b.reached.begin(), b.reached.end(), false),
              std::count(a.reached.begin(), a.reached.end(), false))
        << "seed " << seed;
    EXPECT_EQ(b.violations, 0u);
    TrajectoryChecker checker(model);
    CheckReport report;
    ASSERT_TRUE(checker.check(b.paths, CheckOptions{}, report));
    EXPECT_TRUE(report.ok()) << "seed " << seed << ": " << report.collided_pairs << " pairs in contact";
    shortened += b.duration_s < a.duration_s - so.dt_s / 2 ? 1 : 0;
  }
  EXPECT_GT(late_seen, 0);
  EXPECT_GT(shortened, 0);
}

TEST(PlanHalf, PairedRunsGiveTheSamePlanWithOrWithoutASpareCore) {
  // Half A of crowded problems from random starts (61 robots), where the first run leaves robots
  // stuck: the half repairs them and shortens its tail in pairs of runs. With a spare core a pair
  // runs side by side, without one after the other; the paths, the robots' goals and the runs are
  // the same either way, with the local repairs alone and with every stage.
  const CollisionModel model = build(hex_patch(4));
  PlannerOptions repairs;
  repairs.half_retries = 0;
  repairs.tail_retries = 0;
  repairs.untangle = false;
  int repaired = 0, more = 0;
  const auto seeds = static_cast<std::uint64_t>(test_support::cases(8));
  for (const PlannerOptions& o : {repairs, PlannerOptions{}}) {
    for (std::uint64_t seed = 1; seed <= seeds; ++seed) {
      PlanRequest request;
      request.current = random_poses(model, 300 + seed);
      request.target = random_poses(model, 400 + seed);
      const HalfA half = half_a(model, request, o, seed);
      std::vector<StepperRobot> alone = half.robots, beside = half.robots;
      std::size_t runs_alone = 0, runs_beside = 0;
      const StepperResult a = half::drive_half(model, alone, half.engine, o, runs_alone);
      half::SpareCores one(1);
      const StepperResult b = half::drive_half(model, beside, half.engine, o, runs_beside, &one);
      EXPECT_TRUE(one.take()) << "the core was given back";
      EXPECT_EQ(runs_alone, runs_beside) << "seed " << seed;
      (o.tail_retries == 0 ? repaired : more) += runs_alone > 1 ? 1 : 0;
      for (std::size_t i = 0; i < model.size(); ++i) {
        EXPECT_EQ(alone[i].goal, beside[i].goal) << "seed " << seed << " robot " << i;
        EXPECT_EQ(pts(a.paths[i].alpha), pts(b.paths[i].alpha)) << "seed " << seed << " robot " << i;
        EXPECT_EQ(pts(a.paths[i].beta), pts(b.paths[i].beta)) << "seed " << seed << " robot " << i;
      }
    }
  }
  EXPECT_GT(repaired, 0) << "no problem needed a local repair: the test checked nothing";
  EXPECT_GT(more, 0);
}

}  // namespace axon::fps::plan::half_test

// Shortcuts on jagged arms (smooth_arms) and the planner's verification with fallback layers:
// dithering goes where nothing is near, an excursion that keeps an arm out of a neighbour's way
// stays, and a flattened arm the checker flags falls back to the certified one.
#include "axon/fps/plan/planner.hpp"
#include "axon/fps/plan/smooth.hpp"
#include "model_util.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace axon::fps::plan {
namespace {

using test::two_robots;

// Robot 1 (at the origin, stretched out) turns from alpha 90 (pointing up) to 150 and back,
// dithering by a degree while it waits at 150; robot 2 (22.4 mm to the right, stretched out)
// swings to alpha 150 (towards where robot 1's arm points at 90) in the middle of the wait.
RobotTrajectory excursion_with_dither() {
  RobotTrajectory t;
  t.alpha.push_back({0, 90});
  t.alpha.push_back({5, 150});
  for (int k = 1; k < 40; ++k) t.alpha.push_back({5 + 0.25 * k, k % 2 ? 149.0 : 150.0});
  t.alpha.push_back({15, 150});
  t.alpha.push_back({20, 90});
  t.beta = {{0, 0}};
  return t;
}

RobotTrajectory neighbour_swing() {
  return {{{0, 90}, {6, 90}, {11, 150}, {16, 90}}, {{0, 0}}};
}

TEST(PlanSmooth, DitherAwayFromEveryoneBecomesOneSegment) {
  const auto m = two_robots();
  // Robot 1 dithers by a degree around alpha 90 (pointing away from robot 2) for five seconds,
  // then turns to 120; robot 2 stays folded.
  RobotTrajectory jagged;
  jagged.alpha.push_back({0, 90});
  for (int k = 1; k <= 60; ++k) jagged.alpha.push_back({k / 12.0, k % 2 ? 91.0 : 90.0});
  jagged.alpha.push_back({7.5, 120});
  jagged.beta = {{0, 0}};
  std::vector<RobotTrajectory> plan{jagged, RobotTrajectory::hold({0, 180})};
  std::vector<bool> changed;
  SmoothOptions o;
  o.min_points = 10;
  const SmoothStats stats = smooth_arms(m, plan, o, changed);

  EXPECT_EQ(stats.arms, 1u);
  EXPECT_TRUE(changed[0]);
  EXPECT_FALSE(changed[1]);
  const auto& a = plan[0].alpha;
  EXPECT_LE(a.size(), 3u) << "the dither should be gone";
  EXPECT_EQ(a.front().t_s, 0.0);
  EXPECT_EQ(a.front().deg, 90.0);
  EXPECT_EQ(a.back().t_s, 7.5);
  EXPECT_EQ(a.back().deg, 120.0);
  EXPECT_LE(max_speed(a), max_speed(jagged.alpha) + 1e-9);
  for (std::size_t k = 1; k < a.size(); ++k) EXPECT_GT(a[k].t_s, a[k - 1].t_s);
  // The folded neighbour and the untouched beta arm.
  EXPECT_EQ(plan[1].alpha.size(), 1u);
  EXPECT_EQ(plan[0].beta.size(), 1u);

  TrajectoryChecker checker(m);
  CheckReport report;
  ASSERT_TRUE(checker.check(plan, {}, report));
  EXPECT_TRUE(report.ok());
}

TEST(PlanSmooth, ExcursionThatKeepsClearOfANeighbourStays) {
  const auto m = two_robots();
  const std::vector<RobotTrajectory> original{excursion_with_dither(), neighbour_swing()};
  TrajectoryChecker checker(m);
  CheckReport report;
  ASSERT_TRUE(checker.check(original, {}, report));
  ASSERT_TRUE(report.ok()) << "the test's own plan must be clear";
  // Flattened to a hold at 90, robot 1 would be in robot 2's way.
  std::vector<RobotTrajectory> flat = original;
  flat[0].alpha = {{0, 90}, {20, 90}};
  ASSERT_TRUE(checker.check(flat, {}, report));
  ASSERT_FALSE(report.ok());

  std::vector<RobotTrajectory> plan = original;
  std::vector<bool> changed;
  SmoothOptions o;
  o.min_points = 10;
  smooth_arms(m, plan, o, changed);
  EXPECT_TRUE(changed[0]);
  EXPECT_LT(plan[0].alpha.size(), original[0].alpha.size() / 4) << "the dither at 150 should be gone";
  // The arm is still out of the way while robot 2 swings over.
  for (double t = 8; t <= 14; t += 0.5) EXPECT_GE(angle_at(plan[0].alpha, t), 140.0) << "at " << t << " s";
  EXPECT_EQ(plan[1].alpha.size(), original[1].alpha.size());
  ASSERT_TRUE(checker.check(plan, {}, report));
  EXPECT_TRUE(report.ok()) << "min clearance " << report.min_clearance_mm;
}

TEST(PlanSmooth, FlattenedArmThatCollidesFallsBackToTheCertifiedOne) {
  const auto m = two_robots();
  const std::vector<RobotTrajectory> exact{excursion_with_dither(), neighbour_swing()};
  std::vector<RobotTrajectory> flat = exact;
  flat[0].alpha = {{0, 90}, {20, 90}};
  const std::vector<std::vector<RobotTrajectory>> layers{flat, exact};
  std::vector<RobotTrajectory> out;
  std::vector<std::size_t> level;
  CheckReport report;
  auto checks = verify_with_fallbacks(m, layers, {}, out, level, report);
  ASSERT_TRUE(checks) << checks.error().message();
  EXPECT_EQ(checks.value(), 2u) << "one check flags the pair, the second passes";
  EXPECT_TRUE(report.ok());
  ASSERT_EQ(level.size(), 2u);
  EXPECT_EQ(level[0], 1u) << "robot 1 is back on its certified trajectory";
  EXPECT_EQ(level[1], 0u) << "robot 2 has nothing different to fall back to";
  EXPECT_EQ(out[0].alpha.size(), exact[0].alpha.size());

  // A clear first layer is kept as it is, after one check.
  const std::vector<std::vector<RobotTrajectory>> clear_layers{exact, exact};
  checks = verify_with_fallbacks(m, clear_layers, {}, out, level, report);
  ASSERT_TRUE(checks);
  EXPECT_EQ(checks.value(), 1u);
  EXPECT_EQ(level[0], 0u);

  // Layers of the wrong size are an error.
  const std::vector<std::vector<RobotTrajectory>> short_layers{{exact[0]}};
  EXPECT_FALSE(verify_with_fallbacks(m, short_layers, {}, out, level, report));
}

}  // namespace
}  // namespace axon::fps::plan

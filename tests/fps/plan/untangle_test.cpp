// The untangle phase: a robot left away from its fold is planned alone on its angle grid, and the
// move it gets is clear (independent checker) and ends folded.
#include "fps/plan/checker.hpp"
#include "fps/plan/untangle.hpp"
#include "model_util.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace axon::fps::plan {
namespace {

using test::two_robots;

StepperResult stuck_result(const std::vector<StepperRobot>& robots, std::vector<bool> reached) {
  StepperResult r;
  for (const auto& rb : robots) {
    r.paths.push_back(RobotTrajectory{{{0.0, rb.start.alpha_deg}}, {{0.0, rb.start.beta_deg}}});
    r.end.push_back(rb.start);
  }
  r.reached = std::move(reached);
  r.blockers.resize(robots.size());
  return r;
}

TEST(Untangle, StuckRobotReachesAFoldWithoutContact) {
  const auto m = two_robots();
  // Robot 2 folded with its capsule towards robot 1; robot 1 half unfolded towards robot 2.
  std::vector<StepperRobot> robots{{{10, 40}, {10, 180}, false, nullptr}, {{180, 180}, {180, 180}, false, nullptr}};
  StepperResult r = stuck_result(robots, {false, true});
  EXPECT_EQ(untangle_to_fold(m, robots, r, StepperOptions{}), 1u);
  EXPECT_TRUE(r.reached[0]);
  EXPECT_DOUBLE_EQ(r.end[0].beta_deg, 180.0);
  EXPECT_DOUBLE_EQ(r.paths[0].beta.back().deg, 180.0);
  TrajectoryChecker checker(m);
  CheckReport report;
  ASSERT_TRUE(checker.check(r.paths, CheckOptions{}, report));
  EXPECT_TRUE(report.ok());
  EXPECT_GT(r.duration_s, 0.0);
}

TEST(Untangle, RobotsAlreadyReachedAreLeftAlone) {
  const auto m = two_robots();
  std::vector<StepperRobot> robots{{{10, 40}, {10, 40}, false, nullptr}, {{180, 180}, {180, 180}, false, nullptr}};
  StepperResult r = stuck_result(robots, {true, true});
  EXPECT_EQ(untangle_to_fold(m, robots, r, StepperOptions{}), 0u);
  EXPECT_EQ(r.paths[0].beta.size(), 1u);
}

}  // namespace
}  // namespace axon::fps::plan

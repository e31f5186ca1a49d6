// The motion engine with scripted robots (the planner's local re-plans): planned robots certify
// their moves against the scripted ones, and a planned robot that a scripted one would run into
// is reported (a violation), so that the planner discards that run.
#include "axon/fps/plan/checker.hpp"
#include "axon/fps/plan/stepper.hpp"
#include "model_util.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace axon::fps::plan {
namespace {

using test::two_robots;

TEST(StepperScript, ARobotThatCannotGetAwayIsReportedAsAViolation) {
  // The same swing as fast as a robot can go: robot 1 cannot fold away in time. The engine must
  // say so (the planner then throws the run away), and the played move indeed touches.
  const auto m = two_robots();
  const RobotTrajectory script = RobotTrajectory::linear({0, 0}, {180, 300}, 0, 25);
  std::vector<StepperRobot> robots{{{0, 60}, {0, 60}, false, nullptr}, {{0, 0}, {180, 300}, false, &script}};
  const StepperResult r = drive_to_goals(m, robots, StepperOptions{});
  EXPECT_GT(r.violations, 0u);
  std::vector<RobotTrajectory> played{r.paths[0], script};
  TrajectoryChecker checker(m);
  CheckReport report;
  ASSERT_TRUE(checker.check(played, CheckOptions{}, report));
  EXPECT_FALSE(report.ok());
}

TEST(StepperScript, WithoutScriptsTheSameRobotsNeverMove) {
  // Control: robot 2 frozen at its start, robot 1 at its goal: nothing to do, nobody moves.
  const auto m = two_robots();
  std::vector<StepperRobot> robots{{{0, 60}, {0, 60}, false, nullptr}, {{0, 0}, {0, 0}, true, nullptr}};
  const StepperResult r = drive_to_goals(m, robots, StepperOptions{});
  EXPECT_EQ(r.paths[0].alpha.size(), 1u);
  EXPECT_EQ(r.paths[0].beta.size(), 1u);
  EXPECT_TRUE(r.reached[0]);
  EXPECT_EQ(r.violations, 0u);
}

TEST(StepperGiveUp, ARobotThatNeverGetsCloserStopsTrying) {
  // Robot 1's goal overlaps robot 2, which never moves: it can only get so close, then escapes
  // and comes back again and again. With give_up_after it stops after a few fruitless escapes:
  // still not at its goal, but with fewer corners and an earlier end of motion.
  const auto m = two_robots();
  std::vector<StepperRobot> robots{{{180, 0}, {0, 0}, false, nullptr}, {{180, 0}, {180, 0}, true, nullptr}};
  const StepperResult keep_trying = drive_to_goals(m, robots, StepperOptions{});
  StepperOptions o;
  o.give_up_after = 3;
  const StepperResult given_up = drive_to_goals(m, robots, o);
  EXPECT_FALSE(keep_trying.reached[0]);
  EXPECT_FALSE(given_up.reached[0]);
  const auto points = [](const StepperResult& r) { return r.paths[0].alpha.size() + r.paths[0].beta.size(); };
  EXPECT_LT(points(given_up), points(keep_trying));
  EXPECT_LT(given_up.duration_s, keep_trying.duration_s);
  std::vector<RobotTrajectory> played{given_up.paths[0], given_up.paths[1]};
  TrajectoryChecker checker(m);
  CheckReport report;
  ASSERT_TRUE(checker.check(played, CheckOptions{}, report));
  EXPECT_TRUE(report.ok());
}

}  // namespace
}  // namespace axon::fps::plan

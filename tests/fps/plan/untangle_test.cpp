// The untangle phase: a robot left away from its fold is planned alone on its angle grid, and the
// move it gets is clear (independent checker) and ends folded.
#include "axon/fps/plan/checker.hpp"
#include "axon/fps/plan/untangle.hpp"
#include "model_util.hpp"

#include <gtest/gtest.h>

#include <cmath>
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

// The independent checker finds no contact in the paths (at the full buffer).
void expect_clear(const CollisionModel& m, const std::vector<RobotTrajectory>& paths) {
  TrajectoryChecker checker(m);
  CheckReport report;
  ASSERT_TRUE(checker.check(paths, CheckOptions{}, report));
  EXPECT_TRUE(report.ok()) << report.min_clearance_mm;
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
  expect_clear(m, r.paths);
  EXPECT_GT(r.duration_s, 0.0);
}

// A robot alone, half unfolded at alpha 10, planned to fold at alpha 100. Folding straight takes
// 140 steps and leaves a 90-step turn for later; turning alpha on the way folds it at alpha 100 in
// the same 140 steps.
TEST(Untangle, TheWayOutEndsAtThePlannedAlphaWhenThatIsQuickestWithTheTurnAfter) {
  const std::vector<RobotSpec> specs{RobotSpec{1, {0, 0}, {}, {}, 2.0}};
  auto built = CollisionModel::build(specs, ArmDesign{}, std::vector<FiducialSpec>{});
  ASSERT_TRUE(built) << built.error().message();
  const CollisionModel& m = built.value();
  const StepperOptions o;
  std::vector<StepperRobot> robots{{{10, 40}, {100, 180}, false, nullptr}};
  StepperResult r = stuck_result(robots, {false});
  ASSERT_EQ(untangle_to_fold(m, robots, r, o), 1u);
  EXPECT_DOUBLE_EQ(r.end[0].beta_deg, 180.0);
  EXPECT_NEAR(r.end[0].alpha_deg, 100.0, 1e-9);
  const double turn_after = std::abs(r.end[0].alpha_deg - 100.0) / o.alpha_step_deg * o.dt_s;
  EXPECT_LE(end_time(r.paths[0]) + turn_after, 140 * o.dt_s + 1e-9);
  EXPECT_LE(max_speed(r.paths[0].alpha), 12.0 + 1e-6);
  expect_clear(m, r.paths);
}

TEST(Untangle, RobotsAlreadyReachedAreLeftAlone) {
  const auto m = two_robots();
  std::vector<StepperRobot> robots{{{10, 40}, {10, 40}, false, nullptr}, {{180, 180}, {180, 180}, false, nullptr}};
  StepperResult r = stuck_result(robots, {true, true});
  EXPECT_EQ(untangle_to_fold(m, robots, r, StepperOptions{}), 0u);
  EXPECT_EQ(r.paths[0].beta.size(), 1u);
}

// A robot against its alpha-0 stop, half unfolded, with a fiducial on the neighbouring site at 60
// deg (the geometry of the bench's default layout): its straight fold touches the fiducial and
// turning alpha up sweeps into it, so the only way out is a narrow passage along the stop. The
// engine's grid (1 deg, 0.05 mm margin) does not get through; the finer grids do.
TEST(Untangle, RobotAgainstTheAlphaStopNextToAFiducialGetsOut) {
  const std::vector<RobotSpec> specs{RobotSpec{1, {0, 0}, {}, {}, 2.0}};
  const std::vector<FiducialSpec> fiducials{FiducialSpec{7, {11.2, 19.399}, 3.0}};
  auto built = CollisionModel::build(specs, ArmDesign{}, fiducials);
  ASSERT_TRUE(built) << built.error().message();
  const CollisionModel& m = built.value();
  for (const Pose start : {Pose{0.18, 77.30}, Pose{0.93, 67.95}}) {
    std::vector<StepperRobot> robots{{start, {82.67, 180}, false, nullptr}};
    StepperResult r = stuck_result(robots, {false});
    ASSERT_EQ(untangle_to_fold(m, robots, r, StepperOptions{}), 1u) << start.alpha_deg << ", " << start.beta_deg;
    EXPECT_TRUE(r.reached[0]);
    EXPECT_DOUBLE_EQ(r.end[0].beta_deg, 180.0);
    EXPECT_GE(r.end[0].alpha_deg, 0.0);
    expect_clear(m, r.paths);
    // Never faster than the engine's speed (1 deg per step of 1/12 s on each arm).
    EXPECT_LE(max_speed(r.paths[0].alpha), 12.0 + 1e-6);
    EXPECT_LE(max_speed(r.paths[0].beta), 12.0 + 1e-6);
  }
}

// A robot against its alpha-0 stop, 0.3 mm from a folded neighbour on the site at 60 deg (problem
// 1009 of the bench, robots 85, 86 and 44). The neighbour's best alpha lies beyond where the stuck
// robot lets it turn; turned the other way, within the range it can reach, it clears the way.
TEST(Untangle, FoldedNeighbourTurnsWithinTheRangeItCanReach) {
  const std::vector<RobotSpec> specs{RobotSpec{85, {0, 0}, {}, {}, 2.0}, RobotSpec{86, {11.2, 19.399}, {}, {}, 2.0},
                                     RobotSpec{44, {22.4, 0}, {}, {}, 2.0}};
  const std::vector<FiducialSpec> fiducials{FiducialSpec{2, {33.6, 19.399}, 3.0}};
  auto built = CollisionModel::build(specs, ArmDesign{}, fiducials);
  ASSERT_TRUE(built) << built.error().message();
  const CollisionModel& m = built.value();
  std::vector<StepperRobot> robots{{{0.05, 52.41}, {60.16, 180}, false, nullptr},
                                   {{90.64, 180}, {90.64, 180}, false, nullptr},
                                   {{251.17, 180}, {251.17, 180}, false, nullptr}};
  StepperResult r = stuck_result(robots, {false, true, true});
  ASSERT_EQ(untangle_to_fold(m, robots, r, StepperOptions{}), 1u);
  EXPECT_DOUBLE_EQ(r.end[0].beta_deg, 180.0);
  EXPECT_NE(r.end[1].alpha_deg, 90.64);  // the neighbour turned
  EXPECT_DOUBLE_EQ(r.end[1].beta_deg, 180.0);
  expect_clear(m, r.paths);
}

// The engine keeps a stuck robot wandering until its stall limit, long after everyone else has
// stopped: the untangle starts where the others came to rest (robot 2 at 2 s), from the stuck
// robot's pose then, not after the wander (which ends at 20 s).
TEST(Untangle, StartsWhenTheOthersHaveStoppedNotAfterTheWander) {
  const auto m = two_robots();
  std::vector<StepperRobot> robots{{{10, 40}, {10, 180}, false, nullptr}, {{170, 180}, {180, 180}, false, nullptr}};
  StepperResult r = stuck_result(robots, {false, true});
  r.paths[0].alpha = {{0, 10}, {2, 10}, {6, 12}, {10, 10}, {20, 11}};
  r.paths[0].beta = {{0, 40}, {20, 40}};
  r.end[0] = {11, 40};
  r.paths[1] = RobotTrajectory::linear({170, 180}, {180, 180}, 0, 2);
  r.end[1] = {180, 180};
  r.duration_s = 20;
  ASSERT_EQ(untangle_to_fold(m, robots, r, StepperOptions{}), 1u);
  EXPECT_DOUBLE_EQ(angle_at(r.paths[0].alpha, 2.0), 10.0);
  for (const TimedAngle& p : r.paths[0].alpha) EXPECT_NE(p.deg, 12.0) << "the wander after 2 s is dropped";
  EXPECT_DOUBLE_EQ(r.end[0].beta_deg, 180.0);
  EXPECT_LT(end_time(r.paths[0]), 20.0);
  EXPECT_DOUBLE_EQ(r.duration_s, end_time(r.paths[0]));
  expect_clear(m, r.paths);
}

// Two stuck robots far apart (sites 0 and 12 of a row of 16; robots two sites apart are still
// neighbours): each starts when its own surroundings have stopped (robot 2 at 1 s, robot 14 at
// 20 s), not when the last of the plane has.
TEST(Untangle, FarApartStuckRobotsEachStartWhenTheirSurroundingsStop) {
  std::vector<RobotSpec> row;
  for (int k = 0; k < 16; ++k) row.push_back(test::robot_at(k + 1, 22.4 * k, 0));
  const CollisionModel m = test::build(row);
  std::vector<StepperRobot> robots(16, StepperRobot{{180, 180}, {180, 180}, false, nullptr});
  robots[0] = robots[12] = {{10, 40}, {10, 180}, false, nullptr};
  robots[13].start = {160, 180};
  std::vector<bool> reached(16, true);
  reached[0] = reached[12] = false;
  StepperResult r = stuck_result(robots, reached);
  r.paths[1] = RobotTrajectory::linear({180, 180}, {180, 180}, 0, 1);
  r.paths[13] = RobotTrajectory::linear({160, 180}, {180, 180}, 0, 20);
  r.end[13] = {180, 180};
  r.duration_s = 20;
  ASSERT_EQ(untangle_to_fold(m, robots, r, StepperOptions{}), 2u);
  EXPECT_LT(end_time(r.paths[0]), 20.0);                    // started at 1 s
  EXPECT_DOUBLE_EQ(angle_at(r.paths[12].beta, 20.0), 40.0);  // still until its neighbour stopped
  EXPECT_GT(end_time(r.paths[12]), 20.0);
  EXPECT_DOUBLE_EQ(r.duration_s, end_time(r.paths[12]));
  expect_clear(m, r.paths);
}

// A stuck robot needs only its neighbours still to move on its own: it starts when they have
// stopped (robot 2 at 1 s), not when their neighbours have (robot 4, three sites away, at 20 s).
TEST(Untangle, AStuckRobotStartsWhenItsNeighboursStopNotTheirs) {
  std::vector<RobotSpec> row;
  for (int k = 0; k < 6; ++k) row.push_back(test::robot_at(k + 1, 22.4 * k, 0));
  const CollisionModel m = test::build(row);
  std::vector<StepperRobot> robots(6, StepperRobot{{180, 180}, {180, 180}, false, nullptr});
  robots[0] = {{10, 40}, {10, 180}, false, nullptr};
  robots[3].start = {160, 180};
  std::vector<bool> reached(6, true);
  reached[0] = false;
  StepperResult r = stuck_result(robots, reached);
  r.paths[1] = RobotTrajectory::linear({180, 180}, {180, 180}, 0, 1);
  r.paths[3] = RobotTrajectory::linear({160, 180}, {180, 180}, 0, 20);
  r.end[3] = {180, 180};
  ASSERT_EQ(untangle_to_fold(m, robots, r, StepperOptions{}), 1u);
  EXPECT_LT(angle_at(r.paths[0].beta, 2.0), angle_at(r.paths[0].beta, 5.0));  // on its way by then
  EXPECT_LT(end_time(r.paths[0]), 20.0);
  EXPECT_DOUBLE_EQ(r.end[0].beta_deg, 180.0);
  expect_clear(m, r.paths);
}

}  // namespace
}  // namespace axon::fps::plan

// The check before a datum search or calibration (protocol document 5.3.11-5.3.16: the arms run to
// their hard stops and a collision on the way would be taken for the stop).
#include "axon/fps/plan/stop_sweep.hpp"
#include "model_util.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include <string>
#include <vector>

namespace axon::fps::plan::stop_sweep_test {
namespace {

// Robot 1 at the origin with its alpha arm pointing away from robot 2 (22.4 mm along x), both folded.
struct Pair {
  CollisionModel model = test::build({RobotSpec{1, {0, 0}, {}, {}, 2.0}, RobotSpec{2, {22.4, 0}, {}, {}, 2.0}});
  std::vector<Pose> poses{{180, 180}, {180, 180}};
};

TEST(StopSweep, BetaAloneSwingsAwayFromTheNeighbourAndIsClear) {
  Pair p;
  ASSERT_GT(test::static_clearance(p.model, p.poses), 0.0);
  StopSweepOptions o;
  o.alpha = false;
  const auto s = check_sweep_to_stops(p.model, 0, p.poses, o);
  EXPECT_TRUE(s.clear) << (s.in_the_way.empty() ? "" : s.in_the_way.front());
  EXPECT_GT(s.min_clearance_mm, 0.0);
}

// Both arms: alpha runs down through 0, where the stretched arm points at robot 2.
TEST(StopSweep, BothArmsWouldSweepOverTheNeighbourAndAreRefusedNamingIt) {
  Pair p;
  const auto s = check_sweep_to_stops(p.model, 0, p.poses);
  EXPECT_FALSE(s.clear);
  EXPECT_LT(s.min_clearance_mm, 0.0);
  ASSERT_EQ(s.in_the_way.size(), 1u);
  EXPECT_EQ(s.in_the_way[0].rfind("robot 2 (", 0), 0u) << s.in_the_way[0];
}

// The path of two arms at the same speed lies inside the rectangle of any interleaving: wherever
// the path is blocked the rectangle is too, and from some poses only the rectangle is (a stretched
// arm somewhere in it passes over robot 2).
TEST(StopSweep, TheSimultaneousPathIsCheckedAndTheRectangleOnRequest) {
  Pair p;  // robot 2 moved to 150 deg, away from where the arm ends stretched (alpha at its stop)
  p.model = test::build({RobotSpec{1, {0, 0}, {}, {}, 2.0}, RobotSpec{2, {-19.399, 11.2}, {}, {}, 2.0}});
  StopSweepOptions together, any;
  any.simultaneous = false;
  int only_rectangle = 0, both = 0;
  for (double a = 0; a < 360; a += 15) {
    p.poses[0] = {a, 180};
    const bool path_clear = check_sweep_to_stops(p.model, 0, p.poses, together).clear;
    const bool rect_clear = check_sweep_to_stops(p.model, 0, p.poses, any).clear;
    if (!path_clear) {
      EXPECT_FALSE(rect_clear) << "alpha " << a;
      ++both;
    } else if (!rect_clear) {
      ++only_rectangle;
    }
  }
  EXPECT_GT(only_rectangle, 0);
  EXPECT_GT(both, 0);
}

// A fiducial next to the robot is in the way of the stretched arm as well.
TEST(StopSweep, AFiducialInTheSweptRegionIsNamed) {
  const auto m = test::build({RobotSpec{1, {0, 0}, {}, {}, 2.0}}, {{7, {20, -5}, 3.0}});
  const std::vector<Pose> poses{{90, 180}};
  ASSERT_GT(test::static_clearance(m, poses), 0.0);
  const auto s = check_sweep_to_stops(m, 0, poses);
  EXPECT_FALSE(s.clear);
  ASSERT_FALSE(s.in_the_way.empty());
  EXPECT_NE(s.in_the_way[0].find("fiducial 7"), std::string::npos) << s.in_the_way[0];
  // Alpha alone from 90 down to the stop keeps the folded arm near the centre: clear.
  StopSweepOptions alpha_only;
  alpha_only.beta = false;
  EXPECT_TRUE(check_sweep_to_stops(m, 0, poses, alpha_only).clear);
}

// The bound is a proof: a finer grid never finds less room than the coarse one promised.
TEST(StopSweep, TheBoundHoldsOnAFinerGrid) {
  Pair p;
  StopSweepOptions coarse, fine;
  coarse.alpha = fine.alpha = false;
  coarse.grid_deg = 2.0;
  fine.grid_deg = 0.1;
  const auto c = check_sweep_to_stops(p.model, 0, p.poses, coarse);
  const auto f = check_sweep_to_stops(p.model, 0, p.poses, fine);
  EXPECT_LE(c.min_clearance_mm, f.min_clearance_mm + 1e-9);
}

// ---- backing off ----

// Robot 1 stretched towards robot 2 until its arm is `inside` mm within their buffers: where two
// robots stop when the power goes mid-move.
std::vector<Pose> in_contact(const CollisionModel& m, double inside) {
  std::vector<Pose> poses{{0, 180}, {180, 180}};
  for (double b = 180; b > 0; b -= 0.001) {
    poses[0].beta_deg = b;
    if (test::static_clearance(m, poses) < -inside) return poses;
  }
  ADD_FAILURE() << "no contact found";
  return poses;
}

// The clearance of robot 1 to robot 2 along its move, on a grid finer than the planner's.
double worst_on_the_way(const CollisionModel& m, const std::vector<Pose>& poses, const BackOff& b) {
  double worst = 1e9;
  for (int k = 0; k <= 4000; ++k) {
    auto p = poses;
    const double t = k / 4000.0;
    p[0] = {b.from.alpha_deg + t * (b.to.alpha_deg - b.from.alpha_deg), b.from.beta_deg + t * (b.to.beta_deg - b.from.beta_deg)};
    worst = std::min(worst, test::static_clearance(m, p));
  }
  return worst;
}

TEST(BackOff, APairLeftInContactIsSeparatedByTwoDegreesThatNeverMakeItWorse) {
  const auto m = test::two_robots();
  const auto poses = in_contact(m, 0.083);
  const auto b = plan_back_off(m, 0, poses);
  ASSERT_TRUE(b.found);
  EXPECT_TRUE(b.clear);
  EXPECT_EQ(std::abs(b.step_deg), 2.0);  // the document's 2 degrees are enough here
  EXPECT_LT(b.clearance_before_mm, -0.08);
  EXPECT_GE(b.clearance_after_mm, 0.0);
  ASSERT_EQ(b.in_contact.size(), 1u);
  EXPECT_EQ(b.in_contact[0].rfind("robot 2 (-0.08", 0), 0u) << b.in_contact[0];
  // Never closer than at the start by more than the slack of the 0.05 deg grid.
  const double slack = 0.5 * 0.05 * kRad * (m.robot(0).reach_mm() + m.robot(0).collision_length_mm());
  EXPECT_GE(worst_on_the_way(m, poses, b), b.clearance_before_mm - slack);
  auto after = poses;
  after[0] = b.to;
  EXPECT_GE(test::static_clearance(m, after), 0.0);
}

TEST(BackOff, ARobotThatCollidedWithNothingNearStillMovesTheDocumentsTwoDegrees) {
  const auto m = test::two_robots();
  const std::vector<Pose> poses{{180, 180}, {180, 180}};
  const auto b = plan_back_off(m, 0, poses);
  ASSERT_TRUE(b.found);
  EXPECT_TRUE(b.clear);
  EXPECT_EQ(std::abs(b.step_deg), 2.0);
  EXPECT_TRUE(b.in_contact.empty());
}

TEST(BackOff, NoMoveInsideTheAngleLimitsIsNotFoundAndTheContactIsNamed) {
  auto specs = std::vector<RobotSpec>{RobotSpec{1, {0, 0}, {}, {}, 2.0}, RobotSpec{2, {22.4, 0}, {}, {}, 2.0}};
  const auto free_model = test::build(specs);
  const auto poses = in_contact(free_model, 0.083);
  specs[0].limits = {poses[0].alpha_deg - 1, poses[0].alpha_deg + 1, poses[0].beta_deg - 1, poses[0].beta_deg + 1};
  const auto boxed = test::build(specs);
  const auto b = plan_back_off(boxed, 0, poses);
  EXPECT_FALSE(b.found);
  ASSERT_EQ(b.in_contact.size(), 1u);
  EXPECT_EQ(b.in_contact[0].rfind("robot 2", 0), 0u);
}

}  // namespace
}  // namespace axon::fps::plan::stop_sweep_test

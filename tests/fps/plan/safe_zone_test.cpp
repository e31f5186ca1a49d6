// Safe zones (spec section 11): the figures of the document's tables from the error budget, and
// the check of targets against them (reach of point targets, clearance to neighbours and obstacles)
// on its own and inside the planner.
#include "axon/fps/plan/safe_zone.hpp"
#include "axon/fps/plan/planner.hpp"

#include "model_util.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace axon::fps::plan {
namespace {

// Micrometres, rounded as the document's tables are.
long um(double mm) { return std::lround(mm * 1000.0); }

TEST(SafeZone, TheDesignsBudgetGivesTheDocumentsFigures) {
  const PositionerErrors e;
  // 11.1.1: total length errors per arm.
  EXPECT_EQ(um(e.alpha.length_min_mm()), -121);
  EXPECT_EQ(um(e.alpha.length_max_mm()), 118);
  EXPECT_EQ(um(e.beta.length_min_mm()), -128);
  EXPECT_EQ(um(e.beta.length_max_mm()), 121);
  // 11.1.2: total angle errors.
  EXPECT_NEAR(e.alpha.angle_deg(), 1.50, 1e-9);
  EXPECT_NEAR(e.beta.angle_deg(), 1.48, 1e-9);
  // 11.1.2 and 11.1.3 with the design's arms (7.4 mm, 16.2 mm to the end).
  const SafeZone z = safe_zone(ArmLengths{});
  EXPECT_EQ(um(z.alpha_lateral_mm), 197);
  EXPECT_EQ(um(z.beta_lateral_mm), 849);
  EXPECT_EQ(um(z.lateral_mm()), 1046);
  EXPECT_EQ(um(z.length_min_mm()), -249);
  EXPECT_EQ(um(z.length_max_mm()), 239);
  EXPECT_NEAR(z.radius_mm(), std::hypot(0.249, z.lateral_mm()), 1e-9);
}

TEST(SafeZone, ARobotsOwnArmsChangeItsZone) {
  ArmLengths longer;
  longer.beta_tip_mm = 17.2;
  EXPECT_GT(safe_zone(longer).beta_lateral_mm, safe_zone(ArmLengths{}).beta_lateral_mm + 0.05);
  PositionerErrors none{ArmErrorBudget{0, 0, 0, 0, 0, 0, 0, 0, 0}, ArmErrorBudget{0, 0, 0, 0, 0, 0, 0, 0, 0}};
  EXPECT_EQ(safe_zone(ArmLengths{}, none).radius_mm(), 0.0);
}

CollisionModel one_robot(std::vector<FiducialSpec> fids = {}) { return test::build({RobotSpec{5, {0, 0}, {}, {}, 2.0}}, fids); }
std::size_t boss_of(const CollisionModel& m) { return *m.design().fibre_index("boss"); }

// The check of robot 5 with its boss fibre aimed at the point `d` mm from its centre along x.
SafeZoneReport check_point(const CollisionModel& m, double d) {
  Target t;
  t.robot = 5;
  t.position = Vec2{d, 0};
  const std::vector<Pose> poses{m.robot(0).inverse({d, 0}, boss_of(m), Elbow::ccw).value()};
  const std::vector<Target> targets{t};
  return check_safe_zone(m, poses, {{}, point_fibres(m, targets, poses)});
}

TEST(SafeZone, APointNearTheOuterEdgeIsBeyondTheReachOfARobotWithShortArms) {
  const CollisionModel m = one_robot();
  const double outer = m.robot(0).max_reach_mm(boss_of(m));
  const auto r = check_point(m, outer - 0.100);
  ASSERT_EQ(r.issues.size(), 1u) << r.summary();
  EXPECT_EQ(r.issues[0].robot, 5);
  EXPECT_EQ(r.issues[0].kind, SafeZoneIssue::Kind::beyond_reach);
  EXPECT_NEAR(r.issues[0].by_mm, 0.249 - 0.100, 1e-6);
  EXPECT_EQ(r.robots(), std::vector<std::int32_t>{5});
  EXPECT_NE(r.summary().find("robot 5: target 0.149 mm beyond"), std::string::npos) << r.summary();
  EXPECT_TRUE(check_point(m, outer - 0.300).ok()) << check_point(m, outer - 0.300).summary();
}

TEST(SafeZone, APointNearTheInnerEdgeIsInsideTheFoldOfARobotWithALongBetaArm) {
  const CollisionModel m = one_robot();
  const auto r = check_point(m, m.robot(0).min_reach_mm(boss_of(m)) + 0.100);
  ASSERT_EQ(r.issues.size(), 1u) << r.summary();
  EXPECT_EQ(r.issues[0].kind, SafeZoneIssue::Kind::inside_reach);
  // The fold grows by the beta arm's longest (+0.121) and the alpha arm's shortest (-0.121).
  EXPECT_NEAR(r.issues[0].by_mm, 0.242 - 0.100, 1e-6);
}

TEST(SafeZone, AnExplicitPoseGetsNoReachCheck) {
  const CollisionModel m = test::build({RobotSpec{5, {0, 0}, {}, {}, 2.0}});
  const std::vector<Pose> stretched{{0, 0}};
  EXPECT_TRUE(check_safe_zone(m, stretched).ok());
}

// Robot 1 swings towards robot 2 (beta arm along +y, one pitch to the right) until their clearance
// is below `c` mm; returns the poses.
std::vector<Pose> poses_with_clearance_below(const CollisionModel& m, double c) {
  std::vector<Pose> poses{{0, 90}, {90, 0}};
  for (double a = 0; a < 90; a += 0.05) {
    poses[0] = {a, 0};
    if (test::static_clearance(m, poses) < c) return poses;
  }
  ADD_FAILURE() << "no pose found";
  return poses;
}

TEST(SafeZone, TwoTargetsCloserThanBothZonesAreReportedOnceWithTheShortfall) {
  const CollisionModel m = test::two_robots();
  const auto poses = poses_with_clearance_below(m, 1.0);
  const double c = test::static_clearance(m, poses);
  ASSERT_GT(c, 0.5);  // clear for the collision check, not for the safe zones
  const double need = 2 * safe_zone(ArmLengths{}).radius_mm();
  auto r = check_safe_zone(m, poses);
  ASSERT_EQ(r.issues.size(), 1u) << r.summary();
  EXPECT_EQ(r.issues[0].robot, 1);
  EXPECT_EQ(r.issues[0].other, 2);
  EXPECT_EQ(r.issues[0].kind, SafeZoneIssue::Kind::robot_clearance);
  EXPECT_NEAR(r.issues[0].by_mm, need - c, 1e-9);
  // Robot 1 held (skipped): the pair is robot 2's.
  r = check_safe_zone(m, poses, {{true, false}, {}});
  ASSERT_EQ(r.issues.size(), 1u) << r.summary();
  EXPECT_EQ(r.issues[0].robot, 2);
  EXPECT_EQ(r.issues[0].other, 1);
  // Farther apart than both zones: nothing.
  EXPECT_TRUE(check_safe_zone(m, poses_with_clearance_below(m, 3.0)).ok());
  SafeZoneOptions no_clearance;
  no_clearance.clearance = false;
  EXPECT_TRUE(check_safe_zone(m, poses, {}, no_clearance).ok());
}

TEST(SafeZone, ATargetNearAFiducialIsReportedWithItsName) {
  // The stretched arm swings away from a fiducial 26 mm out on x until it just clears it.
  const CollisionModel m = one_robot({FiducialSpec{7, {26.0, 0}, 3.0}});
  std::vector<Pose> pose{{0, 0}};
  for (double a = 0; a < 90 && test::static_clearance(m, pose) < 0.5; a += 0.05) pose[0] = {a, 0};
  const double c = test::static_clearance(m, pose);
  ASSERT_GT(c, 0.5);
  ASSERT_LT(c, 0.7);
  const auto r = check_safe_zone(m, pose);
  ASSERT_EQ(r.issues.size(), 1u) << r.summary();
  EXPECT_EQ(r.issues[0].kind, SafeZoneIssue::Kind::obstacle_clearance);
  EXPECT_EQ(r.issues[0].obstacle, "fiducial 7");
  EXPECT_NEAR(r.issues[0].by_mm, safe_zone(ArmLengths{}).radius_mm() - c, 1e-9);
}

TEST(SafeZone, ThePlannerReportsTargetsOutsideTheZonesAndPlansThemAnyway) {
  const CollisionModel m = test::two_robots();
  PlanRequest req;
  req.current = {{0, 180}, {180, 180}};
  req.target = poses_with_clearance_below(m, 1.0);
  const auto p = plan_moves(m, req);
  ASSERT_TRUE(p) << p.error().message();
  EXPECT_EQ(p.value().not_reached, 0u);
  EXPECT_EQ(p.value().safe_zone.robots(), std::vector<std::int32_t>{1});
  PlannerOptions off;
  off.safe_zone.reset();
  EXPECT_TRUE(plan_moves(m, req, off).value().safe_zone.ok());
}

}  // namespace
}  // namespace axon::fps::plan

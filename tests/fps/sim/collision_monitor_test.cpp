// Geometry and the collision monitor: segment distances, beta capsules, and which contacts count.
#include "axon/fps/sim/collision_monitor.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include <vector>

using namespace axon::fps::sim;
using Pose = CollisionMonitor::Pose;

TEST(FpsSimGeometry, SegmentDistance) {
  EXPECT_DOUBLE_EQ(segment_distance({{0, 0}, {10, 0}}, {{0, 3}, {10, 3}}), 3);
  EXPECT_DOUBLE_EQ(segment_distance({{0, 0}, {10, 0}}, {{5, -1}, {5, 1}}), 0);  // crossing
  EXPECT_DOUBLE_EQ(segment_distance({{0, 0}, {10, 0}}, {{13, 4}, {13, 4}}), 5);  // point
  EXPECT_DOUBLE_EQ(segment_distance({{0, 0}, {0, 0}}, {{3, 4}, {3, 4}}), 5);
}

TEST(FpsSimGeometry, SurelyApartNeverHidesAContact) {
  const Segment s{{0, 0}, {10, 0}};
  EXPECT_TRUE(surely_apart(s, {{30, 0}, {40, 0}}, 4));
  EXPECT_FALSE(surely_apart(s, {{13, 0}, {23, 0}}, 4));  // 3 mm apart: must not be skipped
  // Whenever the exact distance is below the limit, the quick test says "maybe".
  for (int i = 0; i < 200; ++i) {
    const double a = i * 0.1, x = 5 + (i % 17);
    const Segment t{{x, 0.5 * (i % 9)}, {x + 10 * std::cos(a), 0.5 * (i % 9) + 10 * std::sin(a)}};
    if (segment_distance(s, t) < 4) {
      EXPECT_FALSE(surely_apart(s, t, 4)) << i;
    }
  }
}

TEST(FpsSimGeometry, BetaSegmentFollowsTheArms) {
  const RobotGeometry g{{100, 0}, 90};  // alpha = 0 points along +y
  const auto folded = beta_segment(g, 0, 180);
  EXPECT_NEAR(folded.a.x, 100, 1e-9);
  EXPECT_NEAR(folded.a.y, 7.4, 1e-9);
  EXPECT_NEAR(folded.b.y, 7.4 - 14.7, 1e-9);
  const auto out = beta_segment(g, 90, 0);  // alpha towards -x, beta stretched
  EXPECT_NEAR(out.b.x, 100 - 22.1, 1e-9);
  EXPECT_NEAR(out.b.y, 0, 1e-9);
}

TEST(FpsSimMonitor, ReportsOnlyTheRobotThatMovedIntoContact) {
  CollisionMonitor m({RobotGeometry{{0, 0}}, RobotGeometry{{22.4, 0}}});
  EXPECT_EQ(m.neighbour_pairs(), 1u);
  std::vector<Pose> p{{0, 180}, {0, 180}};
  EXPECT_TRUE(m.update(p).empty());  // first call records
  p[0].beta_deg = 60;                // A turns towards B: still 6.7 mm off B's arm
  EXPECT_TRUE(m.update(p).empty());
  p[0].beta_deg = 0;  // A's tip reaches 22.1: overlaps B's folded arm (15.1..29.8)
  const auto c = m.update(p);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].robot, 0u);
  ASSERT_TRUE(c[0].other);
  EXPECT_EQ(*c[0].other, 1u);
  EXPECT_TRUE(c[0].beta_moved);
  EXPECT_FALSE(c[0].alpha_moved);
  EXPECT_LT(c[0].distance_mm, 4.0);
}

TEST(FpsSimMonitor, BackingAwayFromAContactIsAllowed) {
  CollisionMonitor m({RobotGeometry{{0, 0}}, RobotGeometry{{22.4, 0}}});
  std::vector<Pose> p{{0, 0}, {0, 180}};  // already in contact
  (void)m.update(p);
  p[0].beta_deg = 20;  // moving apart
  EXPECT_TRUE(m.update(p).empty());
}

TEST(FpsSimMonitor, FarRobotsAreNotNeighbours) {
  CollisionMonitor m({RobotGeometry{{0, 0}}, RobotGeometry{{60, 0}}});
  EXPECT_EQ(m.neighbour_pairs(), 0u);
  CollisionMonitor off({RobotGeometry{{0, 0}}, RobotGeometry{{22.4, 0}}}, false);
  EXPECT_EQ(off.neighbour_pairs(), 0u);
}

TEST(FpsSimMonitor, ObstaclesUseTheirOwnRadius) {
  CollisionMonitor m({RobotGeometry{{0, 0}}});
  m.set_obstacles({Obstacle{{{7.4, 19}, {7.4, 19}}, 3.0, "fid"}});
  std::vector<Pose> p{{0, 80}};  // beta arm pointing up from (7.4, 0): tip at about (9.95, 14.5)
  (void)m.update(p);
  p[0].beta_deg = 90;  // tip at (7.4, 14.7): 4.3 mm from the point < 2 + 3
  const auto c = m.update(p);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_FALSE(c[0].other);
  EXPECT_EQ(c[0].obstacle, 0u);
}

// The collision model: neighbour pairs and clearances in configurations worked out by hand.
#include "axon/fps/plan/collision.hpp"
#include "model_util.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace axon::fps::plan {
namespace {

using test::build;

RobotSpec robot(std::int32_t id, Vec2 c) { return RobotSpec{id, c, {}, {}, 2.0}; }

std::vector<Segment> segs_of(const CollisionModel& m, const std::vector<Pose>& poses) {
  std::vector<Segment> s(m.size());
  m.segments(poses, s);
  return s;
}

TEST(PlanCollision, NeighbourThresholdIsTwoReachesPlusTwoBuffers) {
  // 2 * (7.4 + 14.7) + 2 * 2.0 = 48.2 mm.
  const auto m = build({robot(1, {0, 0}), robot(2, {48.1, 0}), robot(3, {0, 48.3})});
  ASSERT_EQ(m.robot_pairs().size(), 1u);
  EXPECT_EQ(m.robot_pairs()[0].a, 0u);
  EXPECT_EQ(m.robot_pairs()[0].b, 1u);
  EXPECT_DOUBLE_EQ(m.robot_pairs()[0].limit_mm, 4.0);
  ASSERT_EQ(m.neighbours(0).size(), 1u);
  EXPECT_EQ(m.neighbours(0)[0], 1u);
  EXPECT_TRUE(m.neighbours(2).empty());
}

TEST(PlanCollision, HexRingIsAllNeighbours) {
  // A centre and its six hex neighbours at 22.4 mm: the ring's farthest pairs are 44.8 mm apart,
  // inside 48.2, so all 7 * 6 / 2 = 21 pairs count.
  std::vector<RobotSpec> r{robot(1, {0, 0})};
  for (int k = 0; k < 6; ++k)
    r.push_back(robot(2 + k, {22.4 * std::cos(k * std::numbers::pi / 3), 22.4 * std::sin(k * std::numbers::pi / 3)}));
  const auto m = build(r);
  EXPECT_EQ(m.robot_pairs().size(), 21u);
  for (std::size_t i = 0; i < m.size(); ++i) EXPECT_EQ(m.neighbours(i).size(), 6u);
}

TEST(PlanCollision, DuplicateIdsAreRejected) {
  std::vector<RobotSpec> r{robot(4, {0, 0}), robot(4, {30, 0})};
  auto m = CollisionModel::build(r);
  ASSERT_FALSE(m);
  EXPECT_NE(m.error().detail.find("duplicate robot id 4"), std::string::npos);
}

TEST(PlanCollision, HeadOnArms) {
  // Robot 1 at the origin stretched along +x: segment x in [7.4, 22.1] on y = 0.
  // Robot 2 at (48, 0) with alpha 180 stretched along -x: segment x in [48 - 22.1, 48 - 7.4] =
  // [25.9, 40.6]. Gap 25.9 - 22.1 = 3.8 mm; limit 2 + 2 = 4: clearance -0.2 (collision).
  const auto m = build({robot(1, {0, 0}), robot(2, {48, 0})});
  auto s = segs_of(m, {{0, 0}, {180, 0}});
  EXPECT_NEAR(m.clearance(m.robot_pairs()[0], s), -0.2, 1e-9);
  std::vector<Contact> contacts;
  EXPECT_NEAR(m.find_contacts(s, contacts), -0.2, 1e-9);
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_EQ(contacts[0].kind, Contact::Kind::robot);
  // Robot 2 bends its beta arm by 90 deg: its segment goes from (40.6, 0) to (40.6, -14.7);
  // the gap to robot 1's end (22.1, 0) is 18.5, clearance 14.5.
  s = segs_of(m, {{0, 0}, {180, 90}});
  EXPECT_NEAR(m.clearance(m.robot_pairs()[0], s), 14.5, 1e-9);
  EXPECT_NEAR(m.find_contacts(s, contacts), 14.5, 1e-9);
  EXPECT_TRUE(contacts.empty());
}

TEST(PlanCollision, PerpendicularArms) {
  // Robot 2 at (15, 25) pointing down (alpha 270, beta 0): beta axis (15, 17.6), segment down to
  // (15, 2.9). Robot 1's segment runs along y = 0 under it: gap 2.9, clearance 2.9 - 4 = -1.1.
  const auto m = build({robot(1, {0, 0}), robot(2, {15, 25})});
  const auto s = segs_of(m, {{0, 0}, {270, 0}});
  EXPECT_NEAR(m.clearance(m.robot_pairs()[0], s), -1.1, 1e-9);
  // robot_clearance with robot 1 swung up by 180 (segment x in [-22.1, -7.4]): far from robot 2;
  // closest points (-7.4, 0) and (15, 2.9): sqrt(22.4^2 + 2.9^2) = 22.587, minus 4.
  const Segment away = m.robot(0).collision_segment({180, 0});
  EXPECT_NEAR(m.robot_clearance(0, away, s), std::hypot(22.4, 2.9) - 4, 1e-9);
}

TEST(PlanCollision, FiducialBufferAddsToRobotBuffer) {
  // A fiducial 4.5 mm above robot 1's stretched segment: 4.5 - (2 + 3) = -0.5 (collision);
  // at 5.5 mm: +0.5 (clear).
  const auto m = build({robot(1, {0, 0})}, {{7, {15, 4.5}, 3.0}, {8, {15, -5.5}, 3.0}});
  ASSERT_EQ(m.obstacle_pairs().size(), 2u);
  const auto s = segs_of(m, {{0, 0}});
  EXPECT_NEAR(m.clearance(m.obstacle_pairs()[0], s), -0.5, 1e-9);
  EXPECT_NEAR(m.clearance(m.obstacle_pairs()[1], s), 0.5, 1e-9);
  std::vector<Contact> contacts;
  m.find_contacts(s, contacts);
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_EQ(contacts[0].kind, Contact::Kind::obstacle);
  EXPECT_EQ(m.obstacles()[contacts[0].b].name, "fiducial 7");
  EXPECT_NEAR(m.robot_clearance(0, s[0], s), -0.5, 1e-9);
}

TEST(PlanCollision, FarObstaclesArePairedWithNoOne) {
  // Reach 22.1 + buffers 2 + 3 = 27.1: a fiducial at 27 pairs, one at 27.2 does not; a segment
  // obstacle (a guide camera edge) counts by its closest point.
  const auto m = build({robot(1, {0, 0})}, {{1, {27, 0}, 3.0}, {2, {0, 27.2}, 3.0}},
                       {{"gfa", {{-27, -50}, {-27, 50}}, 3.0}});
  ASSERT_EQ(m.obstacle_pairs().size(), 2u);
  EXPECT_EQ(m.obstacle_pairs()[0].obstacle, 0u);
  EXPECT_EQ(m.obstacle_pairs()[1].obstacle, 2u);
  // Robot pointing at the camera edge (alpha 180): segment x in [-22.1, -7.4]; gap 4.9 - 5 = -0.1.
  const auto s = segs_of(m, {{180, 0}});
  EXPECT_NEAR(m.clearance(m.obstacle_pairs()[1], s), -0.1, 1e-9);
}

}  // namespace
}  // namespace axon::fps::plan

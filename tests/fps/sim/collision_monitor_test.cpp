// The collision monitor on the planner's model: which contacts count (moving into one, not standing
// still or backing away), obstacles with their own buffer, and robots' config geometry reaching
// the simulator's model.
#include "axon/fps/sim/collision_monitor.hpp"
#include "axon/fps/sim/simulator.hpp"

#include "axon/can/virtual_bus.hpp"

#include <boost/asio/io_context.hpp>
#include <gtest/gtest.h>

#include <vector>

using namespace axon::fps;
using namespace axon::fps::sim;
using Pose = CollisionMonitor::Pose;

namespace {

// Nominal robots at the given centres (ids 1, 2, ...).
plan::CollisionModel robots_at(const std::vector<Vec2>& centres, const std::vector<Obstacle>& obstacles = {}) {
  std::vector<plan::RobotSpec> specs;
  for (const Vec2& c : centres) {
    plan::RobotSpec s;
    s.id = static_cast<std::int32_t>(specs.size() + 1);
    s.centre = c;
    specs.push_back(s);
  }
  return plan::CollisionModel::build(specs, {}, {}, obstacles).value();
}

}  // namespace

TEST(FpsSimMonitor, ReportsOnlyTheRobotThatMovedIntoContact) {
  CollisionMonitor m(robots_at({{0, 0}, {22.4, 0}}));
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
  EXPECT_LT(c[0].clearance_mm, 0.0);
}

TEST(FpsSimMonitor, BackingAwayFromAContactIsAllowed) {
  CollisionMonitor m(robots_at({{0, 0}, {22.4, 0}}));
  std::vector<Pose> p{{0, 0}, {0, 180}};  // already in contact
  (void)m.update(p);
  p[0].beta_deg = 20;  // moving apart
  EXPECT_TRUE(m.update(p).empty());
}

TEST(FpsSimMonitor, FarRobotsAreNotNeighbours) {
  CollisionMonitor m(robots_at({{0, 0}, {60, 0}}));
  EXPECT_EQ(m.neighbour_pairs(), 0u);
  CollisionMonitor off(robots_at({{0, 0}, {22.4, 0}}), false);
  EXPECT_EQ(off.neighbour_pairs(), 0u);
  std::vector<Pose> p{{0, 180}, {0, 180}};
  (void)off.update(p);
  p[0].beta_deg = 0;
  EXPECT_TRUE(off.update(p).empty());
}

TEST(FpsSimMonitor, ObstaclesUseTheirOwnBuffer) {
  CollisionMonitor m(robots_at({{0, 0}}, {Obstacle{"fid", {{7.4, 19}, {7.4, 19}}, 3.0}}));
  std::vector<Pose> p{{0, 80}};  // beta arm pointing up from (7.4, 0): tip at about (9.95, 14.5)
  (void)m.update(p);
  p[0].beta_deg = 90;  // tip at (7.4, 14.7): 4.3 mm from the point < 2 + 3
  const auto c = m.update(p);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_FALSE(c[0].other);
  EXPECT_EQ(c[0].obstacle, 0u);
  EXPECT_NEAR(c[0].clearance_mm, 4.3 - 5.0, 1e-9);
}

TEST(FpsSimMonitor, TheSimulatorsModelTakesEachRobotsConfigGeometry) {
  boost::asio::io_context io;
  auto medium = axon::can::VirtualBus::create(io.get_executor(), "fps0");
  Simulator sim(io.get_executor());
  PositionerConfig c;
  c.id = 7;
  c.x_mm = 100;
  c.orientation_deg = 90;  // alpha = 0 points along +y
  c.arms.alpha_length_mm = 7.5;
  c.arms.beta_collision_mm = 15.0;
  c.collision_buffer_mm = 1.5;
  ASSERT_TRUE(sim.add(c, *medium).has_value());
  sim.add_obstacle(Obstacle{"fid", {{0, 0}, {0, 0}}, 1.0});
  const auto& model = sim.collision_model();
  ASSERT_EQ(model.size(), 1u);
  EXPECT_EQ(model.obstacles().size(), 1u);
  const auto& r = model.robot(0);
  EXPECT_EQ(r.id(), 7);
  EXPECT_EQ(r.buffer_mm(), 1.5);
  const Segment folded = r.collision_segment({0, 180});
  EXPECT_NEAR(folded.a.x, 100, 1e-9);
  EXPECT_NEAR(folded.a.y, 7.5, 1e-9);
  EXPECT_NEAR(folded.b.y, 7.5 - 15.0, 1e-9);
  const Segment out = r.collision_segment({90, 0});  // alpha towards -x, beta stretched
  EXPECT_NEAR(out.b.x, 100 - 22.5, 1e-9);
  EXPECT_NEAR(out.b.y, 0, 1e-9);
  sim.clear_obstacles();
  EXPECT_TRUE(sim.collision_model().obstacles().empty());
}

// Firmware trajectories from straight moves, from a plan and from a trajectory file.
#include "axon/fps/host/trajectory_build.hpp"
#include "axon/fps/layout/layout_name.hpp"
#include "axon/fps/plan/layout_model.hpp"

#include "temp_file.hpp"

#include <gtest/gtest.h>

#include <string>

namespace axon::fps::host {
namespace {

// Wire points of one arm as (steps, ticks) pairs, for comparisons.
std::vector<std::pair<std::int32_t, std::uint32_t>> wire(const std::vector<protocol::TrajectoryPoint>& points) {
  std::vector<std::pair<std::int32_t, std::uint32_t>> out;
  for (const auto& p : points) out.emplace_back(p.position.steps(), p.time.ticks());
  return out;
}

TEST(StraightTrajectory, EndsAtTheTargetWithEvenlySpacedPoints) {
  const auto t = straight_trajectory({10, 170}, {30, 150}, 4, 8.0).value();
  const std::vector<protocol::ArmPoint> alpha{{15, 2}, {20, 4}, {25, 6}, {30, 8}};
  const std::vector<protocol::ArmPoint> beta{{165, 2}, {160, 4}, {155, 6}, {150, 8}};
  const auto expected = protocol::Trajectory::from_physical(alpha, beta).value();
  EXPECT_EQ(wire(t.alpha()), wire(expected.alpha()));
  EXPECT_EQ(wire(t.beta()), wire(expected.beta()));
}

TEST(StraightTrajectory, RefusesNoPointsOrNoTime) {
  EXPECT_EQ(straight_trajectory({0, 180}, {10, 170}, 0, 5.0).error().code, HostErrc::invalid_argument);
  EXPECT_EQ(straight_trajectory({0, 180}, {10, 170}, 5, 0.0).error().code, HostErrc::invalid_argument);
}

TEST(StraightMoves, LeavesOutRobotsWithoutAPosition) {
  StatusTable table;
  table.rows.push_back(StatusRow{1, 0, "bus", {}, {}, {}, ArmAngles{0, 180}, {}});
  table.rows.push_back(StatusRow{2, 0, "bus", {}, {}, {}, std::nullopt, "timeout"});
  const auto moves = straight_moves(table, {20, 160}, 5, 10.0).value();
  ASSERT_EQ(moves.trajectories.size(), 1u);
  EXPECT_TRUE(moves.trajectories.contains(1));
  EXPECT_EQ(moves.starts.at(1), (ArmAngles{0, 180}));
  ASSERT_EQ(moves.left_out.size(), 1u);
  EXPECT_NE(moves.left_out[0].find("positioner 2"), std::string::npos);
}

TEST(PlanTrajectories, DropsTheStartPointAndRobotsThatStay) {
  const auto plane = resolve_layout("benchtop").value();
  const auto model = plan::model_from_layout(plane).value();
  plan::Plan p;
  for (std::size_t i = 0; i < model.size(); ++i) p.trajectories.push_back(plan::RobotTrajectory::hold({0, 180}));
  p.trajectories[2] = plan::RobotTrajectory::linear({0, 180}, {40, 150}, 0, 5);
  p.trajectories[4].alpha = {{0, 0}, {2, 15}, {4, 30}};  // beta stays: no beta points
  const auto t = plan_trajectories(model, p).value();
  ASSERT_EQ(t.size(), 2u);
  const auto id3 = static_cast<std::uint16_t>(model.robot(2).id());
  const auto id5 = static_cast<std::uint16_t>(model.robot(4).id());
  const std::vector<protocol::ArmPoint> a3{{40, 5}}, b3{{150, 5}}, a5{{15, 2}, {30, 4}}, none;
  EXPECT_EQ(wire(t.at(id3).alpha()), wire(protocol::Trajectory::from_physical(a3, b3).value().alpha()));
  EXPECT_EQ(wire(t.at(id3).beta()), wire(protocol::Trajectory::from_physical(a3, b3).value().beta()));
  EXPECT_EQ(wire(t.at(id5).alpha()), wire(protocol::Trajectory::from_physical(a5, none).value().alpha()));
  EXPECT_TRUE(t.at(id5).beta().empty());
}

using TrajectoryFile = testing::TempFileTest;

TEST_F(TrajectoryFile, LoadsEveryRobotWithEitherArm) {
  const auto t = load_trajectory_file(write("1: {alpha: [[10, 1], [20, 2]], beta: [[170, 2]]}\n7: {beta: [[160, 3]]}\n")).value();
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t.at(1).alpha().size(), 2u);
  EXPECT_TRUE(t.at(7).alpha().empty());
  EXPECT_EQ(t.at(7).beta().size(), 1u);
}

TEST_F(TrajectoryFile, ARobotTwiceIsLocated) {
  const auto r = load_trajectory_file(write("1: {alpha: [[10, 1]]}\n2: {alpha: [[10, 1]]}\n1: {alpha: [[20, 1]]}\n"));
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().detail.find(":3: robot 1 listed twice (first at line 1)"), std::string::npos) << r.error().detail;
}

TEST_F(TrajectoryFile, BadPointsAndKeysAreErrors) {
  EXPECT_FALSE(load_trajectory_file(write("1: {alpha: [[10]]}\n")).has_value());
  EXPECT_FALSE(load_trajectory_file(write("1-3: {alpha: [[10, 1]]}\n")).has_value());
  EXPECT_FALSE(load_trajectory_file(write("[1, 2]\n")).has_value());
  EXPECT_FALSE(load_trajectory_file(write("1: {alpha: [[10, 2], [20, 1]]}\n")).has_value());  // time runs back
}

}  // namespace
}  // namespace axon::fps::host

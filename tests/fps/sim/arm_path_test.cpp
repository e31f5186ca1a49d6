// ArmPath: interpolation, stop crossings, and arms that cannot pass their stops.
#include "axon/fps/sim/arm_path.hpp"

#include <gtest/gtest.h>

using namespace axon::fps::sim;
using namespace std::chrono_literals;

TEST(FpsSimArmPath, InterpolatesBetweenCornersAndHoldsOutside) {
  ArmPath p(10s, 0.0);
  p.line_to(10, 5).hold(1s).point(15s, 0);
  EXPECT_EQ(p.end(), 15s);
  EXPECT_DOUBLE_EQ(p.at(0s), 0);
  EXPECT_DOUBLE_EQ(p.at(11s), 5);
  EXPECT_DOUBLE_EQ(p.at(12s), 10);
  EXPECT_DOUBLE_EQ(p.at(13s), 10);
  EXPECT_DOUBLE_EQ(p.at(14s), 5);
  EXPECT_DOUBLE_EQ(p.at(99s), 0);
  EXPECT_DOUBLE_EQ(p.speed_at(11s), 5);
  EXPECT_DOUBLE_EQ(p.speed_at(12500ms), 0);
  EXPECT_DOUBLE_EQ(p.speed_at(14s), -5);
  EXPECT_DOUBLE_EQ(p.speed_at(20s), 0);
  EXPECT_DOUBLE_EQ(p.shifted(2).at(12s), 12);
}

TEST(FpsSimArmPath, FirstOutsideFindsTheCrossing) {
  ArmPath p(0s, 0.0);
  p.line_to(-10, 1);  // reaches -5 after 5 s
  const auto t = p.first_outside(-5, 365);
  ASSERT_TRUE(t);
  EXPECT_NEAR(std::chrono::duration<double>(*t).count(), 5.0, 1e-6);
  EXPECT_FALSE(p.first_outside(-20, 365));
  EXPECT_FALSE(ArmPath(0s, -5).first_outside(-5, 365));  // touching is not leaving
}

TEST(FpsSimArmPath, ClosedLoopWaitsAtTheStopUntilTheCommandReturns) {
  ArmPath cmd(0s, 0.0);
  cmd.line_to(-10, 1).line_to(0, 1);  // down for 10 s, back up for 10 s
  const ArmPath arm = cmd.clamped(-5, 365, /*slip=*/false);
  EXPECT_DOUBLE_EQ(arm.at(5s), -5);
  EXPECT_DOUBLE_EQ(arm.at(10s), -5);
  EXPECT_DOUBLE_EQ(arm.at(15s), -5);  // the command passes the stop again at 15 s
  EXPECT_NEAR(arm.at(17s), -3, 1e-9);
  EXPECT_DOUBLE_EQ(arm.at(20s), 0);
}

TEST(FpsSimArmPath, OpenLoopSlipsAndComesBackAtOnceOffsetByTheLoss) {
  ArmPath cmd(0s, 0.0);
  cmd.line_to(-10, 1).line_to(0, 1);
  const ArmPath arm = cmd.clamped(-5, 365, /*slip=*/true);
  EXPECT_DOUBLE_EQ(arm.at(10s), -5);
  EXPECT_NEAR(arm.at(12s), -3, 1e-9);  // follows from the turn-back
  EXPECT_DOUBLE_EQ(arm.at(20s), 5);    // 5 deg of steps lost
}

TEST(FpsSimArmPath, ClampLeavesPathsInsideAlone) {
  ArmPath cmd(0s, 10.0);
  cmd.line_to(20, 1).line_to(15, 1);
  const ArmPath arm = cmd.clamped(-5, 365, true);
  for (auto t : {0s, 3s, 10s, 12s, 15s}) EXPECT_DOUBLE_EQ(arm.at(t), cmd.at(t));
}

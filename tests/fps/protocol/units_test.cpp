#include "axon/fps/protocol/units.hpp"

#include "axon/fps/protocol/error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace axon::fps::protocol;

TEST(FpsUnits, AnglesFromTheSpecExamples) {
  EXPECT_EQ(Angle::from_degrees(90).value().steps(), 268435456);
  EXPECT_EQ(Angle::from_degrees(45).value().steps(), 134217728);
  EXPECT_EQ(Angle::from_degrees(360).value().steps(), 1 << 30);
  EXPECT_EQ(Angle::from_degrees(-90).value().steps(), -268435456);
  EXPECT_DOUBLE_EQ(Angle::from_steps(268435456).degrees(), 90.0);
  EXPECT_DOUBLE_EQ(Angle::from_steps(-134217728).degrees(), -45.0);
}

TEST(FpsUnits, AnglesRoundToTheNearestStep) {
  const double step = 360.0 / (1 << 30);
  EXPECT_EQ(Angle::from_degrees(0.4 * step).value().steps(), 0);
  EXPECT_EQ(Angle::from_degrees(0.6 * step).value().steps(), 1);
  EXPECT_EQ(Angle::from_degrees(-0.6 * step).value().steps(), -1);
  EXPECT_EQ(Angle::from_degrees(10.0).value().steps(), 29826162);  // 10/360*2^30 = 29826161.78
}

TEST(FpsUnits, AnglesOutOfRangeAreErrors) {
  // int32 covers just under +-720 degrees.
  EXPECT_TRUE(Angle::from_degrees(719.99));
  EXPECT_EQ(Angle::from_degrees(720).error(), ProtocolErrc::value_out_of_range);
  EXPECT_TRUE(Angle::from_degrees(-720));  // exactly INT32_MIN steps
  EXPECT_EQ(Angle::from_degrees(-720.001).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(Angle::from_degrees(std::nan("")).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(Angle::from_degrees(std::numeric_limits<double>::infinity()).error(), ProtocolErrc::value_out_of_range);
}

TEST(FpsUnits, TimesFromTheSpecExamples) {
  EXPECT_EQ(Time::from_seconds(10).value().ticks(), 20000u);
  EXPECT_EQ(Time::from_seconds(5).value().ticks(), 10000u);
  EXPECT_EQ(Time::from_seconds(0.0005).value().ticks(), 1u);
  EXPECT_EQ(Time::from_seconds(0.00074).value().ticks(), 1u);
  EXPECT_EQ(Time::from_seconds(0.00076).value().ticks(), 2u);
  EXPECT_DOUBLE_EQ(Time::from_ticks(20000).seconds(), 10.0);
}

TEST(FpsUnits, TimesOutOfRangeAreErrors) {
  EXPECT_EQ(Time::from_seconds(-0.001).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(Time::from_seconds(2.2e6).error(), ProtocolErrc::value_out_of_range);  // beyond 2^32 ticks
  EXPECT_EQ(Time::from_seconds(std::nan("")).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(Time::from_seconds(-0.0002).value().ticks(), 0u);  // rounds to 0, which is in range
}

TEST(FpsUnits, MotorSpeeds) {
  EXPECT_EQ(MotorSpeed::from_rpm(3000).value().rpm(), 3000u);
  EXPECT_EQ(MotorSpeed::from_rpm(-1).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(MotorSpeed::from_rpm(std::int64_t{1} << 32).error(), ProtocolErrc::value_out_of_range);
  // About 12 deg/s at the arm with a 1000:1 gearbox is 2000 rpm at the motor.
  EXPECT_EQ(MotorSpeed::from_arm_speed(12.0, 1000.0).value().rpm(), 2000u);
  EXPECT_DOUBLE_EQ(MotorSpeed::from_wire(2000).arm_speed(1000.0), 12.0);
  EXPECT_EQ(MotorSpeed::from_arm_speed(12.0, 0).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(MotorSpeed::from_arm_speed(-1.0, 1000).error(), ProtocolErrc::value_out_of_range);
}

TEST(FpsUnits, CurrentsAndMargins) {
  EXPECT_EQ(CurrentPercent::from_percent(45).value().percent(), 45u);
  EXPECT_TRUE(CurrentPercent::from_percent(0));
  EXPECT_TRUE(CurrentPercent::from_percent(100));
  EXPECT_EQ(CurrentPercent::from_percent(101).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(CurrentPercent::from_percent(-1).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(kDefaultHoldingCurrentAlpha, 0u);
  EXPECT_EQ(kDefaultHoldingCurrentBeta, 30u);

  EXPECT_EQ(CollisionMargin::from_value(-30).value().value(), -30);
  EXPECT_EQ(CollisionMargin::from_value(30).value().value(), 30);
  EXPECT_EQ(CollisionMargin::from_value(31).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(CollisionMargin::from_value(-31).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(kDefaultCollisionMarginAlpha, -5);
  EXPECT_EQ(kDefaultCollisionMarginBeta, 20);
}

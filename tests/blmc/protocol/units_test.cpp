#include "axon/blmc/protocol/units.hpp"

#include "axon/blmc/protocol/error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace axon::blmc::protocol;

TEST(BlmcUnits, MotorSideConversions) {
  EXPECT_DOUBLE_EQ(revolutions_to_rad(0.5), std::numbers::pi);
  EXPECT_DOUBLE_EQ(rad_to_revolutions(2 * std::numbers::pi), 1.0);
  // 1 krpm = 1000 rev/min = 16.67 rev/s = 104.72 rad/s.
  EXPECT_NEAR(krpm_to_rad_per_s(1.0), 104.7197551, 1e-6);
  EXPECT_NEAR(rad_per_s_to_krpm(krpm_to_rad_per_s(2.5)), 2.5, 1e-12);
}

TEST(BlmcUnits, JointUnitsThroughTheGearbox) {
  const auto j = JointScaling::make(9.0, 0.025).value();
  // 9 motor turns = one joint turn.
  EXPECT_NEAR(j.joint_rad(9.0), 2 * std::numbers::pi, 1e-12);
  EXPECT_NEAR(j.motor_rev(std::numbers::pi), 4.5, 1e-12);
  // 9 krpm at the motor = 1 krpm at the joint.
  EXPECT_NEAR(j.joint_rad_per_s(9.0), krpm_to_rad_per_s(1.0), 1e-9);
  EXPECT_NEAR(j.motor_krpm(krpm_to_rad_per_s(1.0)), 9.0, 1e-12);
  // 2 A * 0.025 N m/A * 9 = 0.45 N m at the joint.
  EXPECT_NEAR(j.joint_torque_nm(2.0), 0.45, 1e-12);
  EXPECT_NEAR(j.motor_current_a(0.45), 2.0, 1e-12);
}

TEST(BlmcUnits, ScalingConstantsMustBePositiveAndFinite) {
  for (auto [g, kt] : {std::pair{0.0, 0.025}, {-9.0, 0.025}, {9.0, 0.0}, {9.0, -1.0}, {NAN, 0.025}, {9.0, INFINITY}}) {
    auto r = JointScaling::make(g, kt);
    ASSERT_FALSE(r) << g << " " << kt;
    EXPECT_EQ(r.error(), ProtocolErrc::value_out_of_range);
  }
}

// MotorModel: the physics a host driver relies on (acceleration, friction, limits, encoder).
#include "axon/blmc/protocol/units.hpp"
#include "axon/blmc/sim/motor_model.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace axon::blmc::sim;
using axon::blmc::protocol::kTwoPi;

namespace {

MotorConfig frictionless() {
  MotorConfig c;
  c.viscous_friction_nms = 0;
  c.coulomb_friction_nm = 0;
  c.supply_voltage_v = 0;
  c.encoder_counts_per_rev = 0;
  return c;
}

}  // namespace

TEST(BlmcMotorModel, ConstantCurrentGivesKtTimesIOverJ) {
  const MotorConfig c = frictionless();
  MotorModel m(c);
  m.advance(1.5, 0.02);
  const double a = c.torque_constant_nm_per_a * 1.5 / c.rotor_inertia_kgm2;  // rad/s^2
  EXPECT_NEAR(m.velocity_rev_s() * kTwoPi, a * 0.02, a * 0.02 * 1e-9);
  // Semi-implicit Euler over 200 substeps: position within one substep's worth of 1/2 a t^2.
  EXPECT_NEAR(m.continuous_position_rev() * kTwoPi, 0.5 * a * 0.02 * 0.02, a * 0.02 * kSubstepS);
  EXPECT_DOUBLE_EQ(m.current_a(), 1.5);
}

TEST(BlmcMotorModel, LoadInertiaSlowsTheAcceleration) {
  MotorConfig c = frictionless();
  c.load.inertia_kgm2 = c.rotor_inertia_kgm2;  // doubles J
  MotorModel m(c);
  m.advance(1.0, 0.01);
  const double a = c.torque_constant_nm_per_a / (2 * c.rotor_inertia_kgm2);
  EXPECT_NEAR(m.velocity_rev_s() * kTwoPi, a * 0.01, a * 0.01 * 1e-9);
}

TEST(BlmcMotorModel, DefaultFrictionSubtractsFromTheDrive) {
  const MotorConfig c;  // the ODRI-type defaults
  MotorModel m(c);
  m.advance(1.0, 0.001);
  // Over 1 ms the viscous term is tiny: the acceleration is (kt i - tau_c) / J within 1 %.
  const double a = (c.torque_constant_nm_per_a - c.coulomb_friction_nm) / c.rotor_inertia_kgm2;
  EXPECT_NEAR(m.velocity_rev_s() * kTwoPi, a * 0.001, a * 0.001 * 0.01);
}

TEST(BlmcMotorModel, FrictionStopsASpinningRotorAndKeepsItStill) {
  MotorModel m(MotorConfig{});
  m.set_state(0, 20.0);
  m.advance(0.0, 1.0);
  EXPECT_EQ(m.velocity_rev_s(), 0.0);
  const double p = m.continuous_position_rev();
  EXPECT_GT(p, 0.0);
  m.advance(0.0, 0.5);
  EXPECT_EQ(m.continuous_position_rev(), p);
}

TEST(BlmcMotorModel, CurrentBelowBreakawayDoesNotMoveAStandingRotor) {
  const MotorConfig c;
  MotorModel m(c);
  const double breakaway = c.coulomb_friction_nm / c.torque_constant_nm_per_a;
  m.advance(0.9 * breakaway, 0.5);
  EXPECT_EQ(m.velocity_rev_s(), 0.0);
  EXPECT_EQ(m.continuous_position_rev(), 0.0);
  m.advance(1.5 * breakaway, 0.05);
  EXPECT_GT(m.velocity_rev_s(), 0.0);
}

TEST(BlmcMotorModel, CurrentLimitAndBackEmfCapTheDrive) {
  MotorConfig c;
  MotorModel m(c);
  m.advance(50.0, 0.0001);
  EXPECT_DOUBLE_EQ(m.current_a(), c.current_limit_a);
  m.advance(50.0, 2.0);
  // No faster than the supply allows: kt w < V.
  const double w_max = c.supply_voltage_v / c.torque_constant_nm_per_a;
  EXPECT_LT(m.velocity_rev_s() * kTwoPi, w_max);
  EXPECT_GT(m.velocity_rev_s() * kTwoPi, 0.5 * w_max);
  EXPECT_LT(m.current_a(), c.current_limit_a);
}

TEST(BlmcMotorModel, SpringLoadPullsTowardsItsCenter) {
  MotorConfig c;
  c.load.spring_nm_per_rad = 0.01;
  c.load.spring_center_rev = 0.5;
  c.viscous_friction_nms = 1e-4;
  MotorModel m(c);
  m.advance(0.0, 3.0);
  EXPECT_NEAR(m.continuous_position_rev(), 0.5, 0.05);
}

TEST(BlmcMotorModel, PositionRollsOverAtPlusMinus100Revolutions) {
  MotorModel m(frictionless());
  m.set_state(99.95, 10.0);
  m.advance(0.0, 0.01);  // +0.1 rev
  EXPECT_NEAR(m.continuous_position_rev(), 100.05, 1e-9);
  EXPECT_NEAR(m.position_rev(), -99.95, 1e-9);
  EXPECT_EQ(m.rollovers(), 1u);
  m.set_state(-99.95, -10.0);
  m.advance(0.0, 0.01);
  EXPECT_NEAR(m.position_rev(), 99.95, 1e-9);
  EXPECT_EQ(m.rollovers(), 2u);
}

TEST(BlmcMotorModel, EncoderIsQuantisedToItsCounts) {
  MotorConfig c;
  c.encoder_counts_per_rev = 4;
  c.initial_position_rev = 0.3;
  MotorModel m(c);
  EXPECT_DOUBLE_EQ(m.position_rev(), 0.25);
}

TEST(BlmcMotorModel, IndexMarkOncePerRevolutionAtItsOffset) {
  MotorConfig c = frictionless();
  c.index_offset_rev = 0.25;
  MotorModel m(c);
  m.set_state(0, 5.0);
  m.advance(0.0, 1.0);  // 0 -> 5 rev
  ASSERT_EQ(m.index_events().size(), 5u);
  for (std::size_t k = 0; k < 5; ++k) EXPECT_NEAR(m.index_events()[k], static_cast<double>(k) + 0.25, 1e-9);
  EXPECT_EQ(m.index_count(), 5u);
  m.clear_index_events();
  // Backwards through 4.25 and 3.25.
  m.set_state(4.5, -2.0);
  m.advance(0.0, 0.75);  // 4.5 -> 3.0
  ASSERT_EQ(m.index_events().size(), 2u);
  EXPECT_NEAR(m.index_events()[0], 4.25, 1e-9);
  EXPECT_NEAR(m.index_events()[1], 3.25, 1e-9);
}

TEST(BlmcMotorConfig, ValidateNamesTheBadField) {
  MotorConfig c;
  c.rotor_inertia_kgm2 = 0;
  auto r = c.validate();
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().detail.find("rotor_inertia_kgm2"), std::string::npos);
  c = MotorConfig{};
  c.index_offset_rev = 1.0;
  EXPECT_FALSE(c.validate());
}

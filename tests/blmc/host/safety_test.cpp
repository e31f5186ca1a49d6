#include "axon/blmc/host/safety.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace axon::blmc::host {
namespace {

using protocol::ErrorCode;
using protocol::Status;

core::TimePoint at(int ms) { return core::TimePoint(std::chrono::milliseconds(ms)); }

// Measurements as a healthy, enabled board gives them at `t`.
can::Frame status_byte_frame(std::uint8_t byte) {
  return can::Frame::standard(0x010, std::vector<std::uint8_t>{byte}).value();
}

Measurements healthy(core::TimePoint t) {
  Measurements m;
  m.status = {Status{true, true, true, true, true, ErrorCode::none}, t, 1};
  m.current = {{0, 0}, t, 1};
  m.position = {{0, 0}, t, 1};
  m.velocity = {{0, 0}, t, 1};
  m.adc = {{0.5, 0.5}, t, 1};
  return m;
}

TEST(BlmcSafety, ClampsCurrentToTheLimit) {
  SafetyLimits l;
  l.max_current_a = 1.5;
  Safety s(l);
  s.arm(at(0));
  const auto out = s.apply(healthy(at(1)), {3.0, -4.0}, at(1));
  EXPECT_DOUBLE_EQ(out.motor1, 1.5);
  EXPECT_DOUBLE_EQ(out.motor2, -1.5);
  EXPECT_FALSE(s.tripped());
  EXPECT_EQ(s.counters().clamped, 2u);
  const auto in = s.apply(healthy(at(2)), {0.5, -0.25}, at(2));
  EXPECT_DOUBLE_EQ(in.motor1, 0.5);
  EXPECT_DOUBLE_EQ(in.motor2, -0.25);
}

TEST(BlmcSafety, ZeroCurrentAboveTheVelocityLimitWithoutFault) {
  SafetyLimits l;
  l.max_velocity_krpm = 1.0;
  Safety s(l);
  s.arm(at(0));
  auto m = healthy(at(1));
  m.velocity.value = {1.5, -0.5};
  auto out = s.apply(m, {1.0, 1.0}, at(1));
  EXPECT_EQ(out.motor1, 0.0);
  EXPECT_EQ(out.motor2, 1.0);
  EXPECT_FALSE(s.tripped());
  EXPECT_EQ(s.counters().velocity_limited, 1u);
  m.velocity.value = {-1.01, 0};
  out = s.apply(m, {1.0, 1.0}, at(1));
  EXPECT_EQ(out.motor1, 0.0);
  m.velocity.value = {0.5, 0};
  out = s.apply(m, {1.0, 1.0}, at(1));
  EXPECT_EQ(out.motor1, 1.0);
}

TEST(BlmcSafety, BoardErrorTripsAndNamesTheCode) {
  Safety s;
  s.arm(at(0));
  auto m = healthy(at(1));
  m.status.value.error = ErrorCode::can_recv_timeout;
  const auto out = s.apply(m, {1.0, 1.0}, at(1));
  EXPECT_EQ(out, (MotorPair{0, 0}));
  ASSERT_TRUE(s.tripped());
  EXPECT_TRUE(s.newly_tripped());
  EXPECT_EQ(s.fault().kind, FaultKind::board_error);
  EXPECT_EQ(s.fault().board_error, ErrorCode::can_recv_timeout);
  EXPECT_NE(s.fault().describe().find("CAN_RECV_TIMEOUT"), std::string::npos) << s.fault().describe();
}

// Error code 6 is not in the spec's table, but a board that sends it says something is wrong: the
// host must stop in that cycle, not carry on until the data or the status go stale.
TEST(BlmcSafety, AnUndocumentedBoardErrorCodeTripsAtOnceAndIsNamed) {
  Safety s;
  s.arm(at(0));
  auto m = healthy(at(1));
  EXPECT_EQ(apply_frame(m, status_byte_frame(0xDF), at(1)), FrameOutcome::undocumented_error);  // flags on, code 6
  EXPECT_EQ(m.undocumented_errors, 1u);
  const auto out = s.apply(m, {1.0, 1.0}, at(1));
  EXPECT_EQ(out, (MotorPair{0, 0}));
  ASSERT_TRUE(s.newly_tripped());
  EXPECT_EQ(s.fault().kind, FaultKind::undocumented_error);
  EXPECT_EQ(s.fault().describe(), "board sent undocumented error code 6");
  // A later healthy status does not clear it: faults latch until reset.
  m = healthy(at(2));
  apply_frame(m, status_byte_frame(0x1F), at(2));
  EXPECT_EQ(s.apply(m, {1.0, 1.0}, at(2)), (MotorPair{0, 0}));
  s.reset(at(2));
  EXPECT_EQ(s.apply(m, {1.0, 1.0}, at(2)), (MotorPair{1.0, 1.0}));
}

TEST(BlmcSafety, FaultIsLatchedUntilReset) {
  Safety s;
  s.arm(at(0));
  auto m = healthy(at(1));
  m.status.value.error = ErrorCode::encoder;
  (void)s.apply(m, {1, 1}, at(1));
  ASSERT_TRUE(s.tripped());
  const auto out = s.apply(healthy(at(2)), {1, 1}, at(2));
  EXPECT_EQ(out, (MotorPair{0, 0}));
  EXPECT_FALSE(s.newly_tripped());
  EXPECT_EQ(s.fault().board_error, ErrorCode::encoder);
  s.reset(at(3));
  EXPECT_FALSE(s.tripped());
  EXPECT_EQ(s.apply(healthy(at(3)), {1, 1}, at(3)), (MotorPair{1, 1}));
}

TEST(BlmcSafety, BoardDisabledMotorTrips) {
  Safety s;
  s.arm(at(0));
  auto m = healthy(at(1));
  m.status.value.motor2_enabled = false;
  (void)s.apply(m, {0, 0}, at(1));
  ASSERT_TRUE(s.tripped());
  EXPECT_EQ(s.fault().kind, FaultKind::board_disabled);
  EXPECT_EQ(s.fault().motor, 1);
}

TEST(BlmcSafety, UnusedMotorIsNotCheckedAndGetsZero) {
  SafetyLimits l;
  l.motors = {true, false};
  Safety s(l);
  s.arm(at(0));
  auto m = healthy(at(1));
  m.status.value.motor2_enabled = false;
  const auto out = s.apply(m, {1, 1}, at(1));
  EXPECT_FALSE(s.tripped());
  EXPECT_EQ(out, (MotorPair{1, 0}));
}

TEST(BlmcSafety, StaleVelocityTripsEvenIfTheBoardSaysNothing) {
  SafetyLimits l;
  l.stale_after = std::chrono::milliseconds(10);
  Safety s(l);
  s.arm(at(0));
  auto m = healthy(at(5));
  (void)s.apply(m, {0, 0}, at(14));
  EXPECT_FALSE(s.tripped());
  m.current.at = m.position.at = at(20);  // velocity stops arriving at 5 ms
  (void)s.apply(m, {0, 0}, at(16));
  ASSERT_TRUE(s.tripped());
  EXPECT_EQ(s.fault().kind, FaultKind::stale_data);
  EXPECT_EQ(s.fault().quantity, Quantity::velocity);
  EXPECT_NE(s.fault().describe().find("velocity"), std::string::npos);
}

TEST(BlmcSafety, NeverReceivedCountsFromArm) {
  SafetyLimits l;
  l.stale_after = std::chrono::milliseconds(10);
  Safety s(l);
  s.arm(at(100));
  Measurements nothing;
  (void)s.apply(nothing, {0, 0}, at(105));
  EXPECT_FALSE(s.tripped());
  (void)s.apply(nothing, {0, 0}, at(111));
  ASSERT_TRUE(s.tripped());
  EXPECT_EQ(s.fault().kind, FaultKind::stale_data);
  EXPECT_EQ(s.fault().quantity, Quantity::current);
}

TEST(BlmcSafety, StaleStatusUsesItsOwnLimit) {
  SafetyLimits l;
  l.status_stale_after = std::chrono::milliseconds(2500);
  Safety s(l);
  s.arm(at(0));
  auto m = healthy(at(0));
  m.current.at = m.position.at = m.velocity.at = at(2400);
  (void)s.apply(m, {0, 0}, at(2400));
  EXPECT_FALSE(s.tripped());
  m.current.at = m.position.at = m.velocity.at = at(2600);
  (void)s.apply(m, {0, 0}, at(2600));
  ASSERT_TRUE(s.tripped());
  EXPECT_EQ(s.fault().quantity, Quantity::status);
}

TEST(BlmcSafety, AdcOnlyCheckedWhenAsked) {
  SafetyLimits l;
  l.check_adc = true;
  Safety s(l);
  s.arm(at(0));
  auto m = healthy(at(20));
  m.adc.at = at(0);
  (void)s.apply(m, {0, 0}, at(20));
  ASSERT_TRUE(s.tripped());
  EXPECT_EQ(s.fault().quantity, Quantity::adc);
  Safety lax;
  lax.arm(at(0));
  (void)lax.apply(m, {0, 0}, at(20));
  EXPECT_FALSE(lax.tripped());
}

TEST(BlmcSafety, PositionLimitTrips) {
  SafetyLimits l;
  l.position[0] = {true, -1.0, 1.0};
  Safety s(l);
  s.arm(at(0));
  auto m = healthy(at(1));
  m.position.value = {0.9, 50.0};  // motor 2 has no limit
  (void)s.apply(m, {0, 0}, at(1));
  EXPECT_FALSE(s.tripped());
  m.position.value = {-1.2, 0};
  (void)s.apply(m, {0, 0}, at(1));
  ASSERT_TRUE(s.tripped());
  EXPECT_EQ(s.fault().kind, FaultKind::position_limit);
  EXPECT_EQ(s.fault().motor, 0);
  EXPECT_DOUBLE_EQ(s.fault().limit, -1.0);
}

TEST(BlmcSafety, NonFiniteCommandTrips) {
  Safety s;
  s.arm(at(0));
  const auto out = s.apply(healthy(at(1)), {0.1, std::numeric_limits<double>::quiet_NaN()}, at(1));
  EXPECT_EQ(out, (MotorPair{0, 0}));
  ASSERT_TRUE(s.tripped());
  EXPECT_EQ(s.fault().kind, FaultKind::bad_command);
  EXPECT_EQ(s.fault().motor, 1);
}

TEST(BlmcSafety, BoardErrorTakesPrecedenceOverStaleData) {
  Safety s;
  s.arm(at(0));
  auto m = healthy(at(0));
  m.status.value.error = ErrorCode::pos_rollover;
  (void)s.apply(m, {0, 0}, at(1000));
  EXPECT_EQ(s.fault().kind, FaultKind::board_error);
  EXPECT_EQ(s.fault().board_error, ErrorCode::pos_rollover);
}

}  // namespace
}  // namespace axon::blmc::host

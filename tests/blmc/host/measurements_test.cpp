// Decoding board frames into Measurements: the position counter's rollover at +-100 rev is unwrapped
// for everything the host hands on (blmc spec: position in motor revolutions, rolling over at
// +-100).
#include "axon/blmc/host/measurements.hpp"
#include "axon/blmc/protocol/frames.hpp"

#include <gtest/gtest.h>

namespace axon::blmc::host::measurements_test {
namespace {

can::Frame position_frame(double m1, double m2) {
  return protocol::encode(protocol::PairMessage{protocol::MessageId::position, {m1, m2}}).value();
}

can::Frame index_frame(double rev, std::uint8_t motor) {
  return protocol::encode(protocol::EncoderIndex{rev, motor}).value();
}

// Feeds one position frame and returns what the host now holds.
MotorPair feed(Measurements& m, double m1, double m2) {
  EXPECT_EQ(apply_frame(m, position_frame(m1, m2), core::TimePoint{}), FrameOutcome::measurement);
  return m.position.value;
}

}  // namespace

TEST(BlmcMeasurements, PositionsAcrossTheRolloverAreContinuousInBothDirections) {
  Measurements m;
  EXPECT_NEAR(feed(m, 99.9, -99.9).motor1, 99.9, 1e-6);
  // Motor 1 turns forward past +100 (reads -99.95), motor 2 backward past -100 (reads 99.95).
  auto p = feed(m, -99.95, 99.95);
  EXPECT_NEAR(p.motor1, 100.05, 1e-6);
  EXPECT_NEAR(p.motor2, -100.05, 1e-6);
  EXPECT_EQ(m.unwrap.wraps[0], 1);
  EXPECT_EQ(m.unwrap.wraps[1], -1);
  // Another turn forward (frames 100 rev or less apart are motion), then back over the same wrap.
  p = feed(m, 0.0, 50.0);
  EXPECT_NEAR(p.motor1, 200.0, 1e-6);
  EXPECT_NEAR(p.motor2, -150.0, 1e-6);
  EXPECT_NEAR(feed(m, 99.99, 0.0).motor1, 299.99, 1e-6);
  EXPECT_NEAR(feed(m, -99.99, 0.0).motor1, 300.01, 1e-6);
  EXPECT_EQ(m.unwrap.wraps[0], 2);
  EXPECT_NEAR(feed(m, 99.99, 0.0).motor1, 299.99, 1e-6);
  EXPECT_EQ(m.unwrap.wraps[0], 1);
  EXPECT_NEAR(m.position.value.motor2, -200.0, 1e-6);
}

TEST(BlmcMeasurements, TheFirstPositionIsTakenAsItIsAndSmallMovesNeverWrap) {
  Measurements m;
  EXPECT_NEAR(feed(m, -99.99, 99.99).motor1, -99.99, 1e-6);
  for (double x = -99.0; x < 99.0; x += 7.0) EXPECT_NEAR(feed(m, x, -x).motor1, x, 1e-6);
  EXPECT_EQ(m.unwrap.wraps[0], 0);
  EXPECT_EQ(m.unwrap.wraps[1], 0);
}

TEST(BlmcMeasurements, AnIndexTickGoesOnTheTurnNearestTheMotorsPosition) {
  Measurements m;
  feed(m, 99.9, 0.0);
  feed(m, -99.9, 0.0);  // motor 1 at 100.1 rev
  // A tick recorded just before the wrap (99.95) and one just after (-99.98).
  ASSERT_EQ(apply_frame(m, index_frame(99.95, 0), core::TimePoint{}), FrameOutcome::index);
  EXPECT_NEAR(m.index[0].value, 99.95, 1e-6);
  ASSERT_EQ(apply_frame(m, index_frame(-99.98, 0), core::TimePoint{}), FrameOutcome::index);
  EXPECT_NEAR(m.index[0].value, 100.02, 1e-6);
  ASSERT_EQ(apply_frame(m, index_frame(0.25, 1), core::TimePoint{}), FrameOutcome::index);
  EXPECT_NEAR(m.index[1].value, 0.25, 1e-6);
}

}  // namespace axon::blmc::host::measurements_test

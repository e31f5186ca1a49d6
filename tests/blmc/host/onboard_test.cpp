// The on-board controller's settings as frames (spec 002: KP 0x006, KD 0x007, POS_REF 0x008,
// VEL_REF 0x009, commands 0x28..0x2B, 0x1F, 0x04/0x05): what goes on the wire, and what is refused
// in words before anything does.
#include "axon/blmc/host/error.hpp"
#include "axon/blmc/host/onboard.hpp"
#include "axon/blmc/protocol/frames.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <string>

namespace axon::blmc::host::onboard_test {
namespace {

using protocol::MessageId;

MotorPair pair_of(MessageId id, const can::Frame& f) { return protocol::decode_pair(id, f).value(); }
std::string command_of(const can::Frame& f) { return protocol::decode_command(f).value().to_string(); }

void expect_refused(const Result<std::vector<can::Frame>>& r, const std::string& words) {
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), HostErrc::invalid_argument);
  EXPECT_NE(r.error().detail.find(words), std::string::npos) << r.error().detail;
}

}  // namespace

TEST(BlmcOnboard, GainsReferencesAndLimitsGoOutAsTheSpecsMessages) {
  const auto gains = onboard_frames(OnboardGains{{8, 4}, {1.5, 0.25}}).value();
  ASSERT_EQ(gains.size(), 2u);
  EXPECT_EQ(pair_of(MessageId::kp, gains[0]), (MotorPair{8, 4}));
  EXPECT_EQ(pair_of(MessageId::kd, gains[1]), (MotorPair{1.5, 0.25}));
  const auto refs = onboard_frames(OnboardReferences{{0.5, -2}, {0.125, 0}}, PositionUnwrap{}).value();
  ASSERT_EQ(refs.size(), 2u);
  EXPECT_EQ(pair_of(MessageId::pos_ref, refs[0]), (MotorPair{0.5, -2}));
  EXPECT_EQ(pair_of(MessageId::vel_ref, refs[1]), (MotorPair{0.125, 0}));
  const auto limits = onboard_frames(OnboardCurrentLimits{{1, 2}, {0.5, 0.25}}).value();
  ASSERT_EQ(limits.size(), 4u);
  EXPECT_EQ(command_of(limits[0]), "CAN_CMD_P_CONTROLLER_LIMIT_IQ_MTR1=1");
  EXPECT_EQ(command_of(limits[1]), "CAN_CMD_P_CONTROLLER_LIMIT_IQ_MTR2=2");
  EXPECT_EQ(command_of(limits[2]), "CAN_CMD_D_CONTROLLER_LIMIT_IQ_MTR1=0.5");
  EXPECT_EQ(command_of(limits[3]), "CAN_CMD_D_CONTROLLER_LIMIT_IQ_MTR2=0.25");
  EXPECT_EQ(command_of(rollover_error_frame(true)), "ENABLE_POS_ROLLOVER_ERROR=1");
  const auto springs = virtual_spring_frames({true, false});
  ASSERT_EQ(springs.size(), 2u);
  EXPECT_EQ(command_of(springs[0]), "ENABLE_VSPRING1=1");
  EXPECT_EQ(command_of(springs[1]), "ENABLE_VSPRING2=0");
  const auto reset = onboard_reset_frames();
  ASSERT_EQ(reset.size(), 6u);
  EXPECT_EQ(command_of(reset[0]), "CAN_CMD_P_CONTROLLER_LIMIT_IQ_MTR1=0");
  EXPECT_EQ(command_of(reset[5]), "ENABLE_VSPRING2=0");
}

// The host's positions are unwrapped; the board compares POS_REF with its own counter. A motor one
// turn of the counter up (host 150 rev = counter -50 rev) gets the counter's reading of the place.
TEST(BlmcOnboard, APositionReferenceIsSentOnTheCountersCurrentTurnOrRefused) {
  PositionUnwrap u;
  u.wraps = {1, 0};
  const auto refs = onboard_frames(OnboardReferences{{150, 99.5}, {}}, u).value();
  EXPECT_EQ(pair_of(MessageId::pos_ref, refs[0]), (MotorPair{-50, 99.5}));
  expect_refused(onboard_frames(OnboardReferences{{99, 0}, {}}, u),
                 "motor 1 position reference 99 rev lies outside 100 .. 300 rev");
  expect_refused(onboard_frames(OnboardReferences{{150, 100}, {}}, u), "motor 2 position reference 100 rev");
}

TEST(BlmcOnboard, RefusesValuesTheBoardCannotTakeInWords) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expect_refused(onboard_frames(OnboardGains{{-1, 0}, {}}), "motor 1 KP must be a finite number within 0 .. 128 A/rev");
  expect_refused(onboard_frames(OnboardGains{{}, {0, nan}}), "motor 2 KD");
  expect_refused(onboard_frames(OnboardCurrentLimits{{200, 0}, {}}), "motor 1 P current limit");
  expect_refused(onboard_frames(OnboardCurrentLimits{{}, {0, -0.5}}), "motor 2 D current limit");
  expect_refused(onboard_frames(OnboardReferences{{nan, 0}, {}}, PositionUnwrap{}), "must be finite");
  expect_refused(onboard_frames(OnboardReferences{{}, {130, 0}}, PositionUnwrap{}), "motor 1 velocity reference");
}

}  // namespace axon::blmc::host::onboard_test

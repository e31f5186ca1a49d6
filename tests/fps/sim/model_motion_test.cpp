// PositionerModel: go-to moves at the set speed through the gear ratio, ETAs, the precise
// approach, stop and abort.
#include "harness.hpp"

#include <cmath>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::sim;
using namespace axon::fps::sim::testing;

namespace {

protocol::ArmTimes etas(const Message& m) { return protocol::ArmTimes::decode(m.payload.span()).value(); }

}  // namespace

TEST(FpsSimMotion, GoToAbsoluteRepliesWithEtasAndArrives) {
  Harness h;  // 2000 rpm at 1000:1 = 12 deg/s; precise approach 0.9 deg out and back
  const auto reply = h.ask(CommandId::go_to_absolute_position, positions(90, 150));
  ASSERT_EQ(reply.id.response, ResponseCode::accepted);
  const auto t = etas(reply);
  EXPECT_NEAR(t.alpha.seconds(), (90.0 + 2 * 0.9) / 12.0, 0.001);
  EXPECT_NEAR(t.beta.seconds(), (30.0 - 0.9 + 0.9) / 12.0 + 0.0, 0.001);  // 180 -> 150.9 -> 150
  EXPECT_FALSE(h.status().has(StatusBit::displacement_completed));

  h.wait(seconds(t.beta.seconds()));
  auto s = h.status();
  EXPECT_TRUE(s.has(StatusBit::displacement_completed_beta));
  EXPECT_FALSE(s.has(StatusBit::displacement_completed_alpha));
  EXPECT_FALSE(s.has(StatusBit::displacement_completed));

  h.wait(seconds(t.alpha.seconds() - t.beta.seconds()));
  EXPECT_TRUE(h.status().has(StatusBit::displacement_completed));
  const auto [a, b] = h.position();
  EXPECT_NEAR(a, 90.0, 1e-6);
  EXPECT_NEAR(b, 150.0, 1e-6);
}

TEST(FpsSimMotion, PositionIsInterpolatedDuringTheMove) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::switch_off_precise_move_alpha), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(60, 180)), ResponseCode::accepted);
  h.wait(2500ms);  // 12 deg/s
  EXPECT_NEAR(h.position().first, 30.0, 1e-3);
}

TEST(FpsSimMotion, SpeedGoesThroughTheGearRatio) {
  auto c = test_config();
  c.gear_ratio = 500;
  Harness h(c);
  ASSERT_EQ(h.code(CommandId::switch_off_precise_move_alpha), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::set_speed, two_u32(1000, 1000)), ResponseCode::accepted);
  const auto t = etas(h.ask(CommandId::go_to_absolute_position, positions(36, 180)));
  EXPECT_NEAR(t.alpha.seconds(), 3.0, 0.001);  // 1000 rpm / 500 * 6 = 12 deg/s
}

TEST(FpsSimMotion, PreciseApproachOvershootsThenComesBack) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(12, 180)), ResponseCode::accepted);
  h.wait(seconds(12.9 / 12.0));
  EXPECT_NEAR(h.position().first, 12.9, 1e-3);  // at target + 0.9
  h.wait_idle();
  EXPECT_NEAR(h.position().first, 12.0, 1e-6);
}

TEST(FpsSimMotion, RelativeZeroMoveStillDoesTheZigZag) {
  Harness h;
  const auto t = etas(h.ask(CommandId::go_to_relative_position, positions(0, 0)));
  EXPECT_NEAR(t.alpha.seconds(), 1.8 / 12.0, 0.001);
  EXPECT_NEAR(t.beta.seconds(), 1.8 / 12.0, 0.001);
  h.wait_idle();
  EXPECT_NEAR(h.position().second, 180.0, 1e-6);
}

TEST(FpsSimMotion, GoToRelativeAddsToThePosition) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::go_to_relative_position, positions(10, -20)), ResponseCode::accepted);
  h.wait_idle();
  const auto [a, b] = h.position();
  EXPECT_NEAR(a, 10.0, 1e-6);
  EXPECT_NEAR(b, 160.0, 1e-6);
}

TEST(FpsSimMotion, RefusesANewMoveWhileMoving) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(90, 90)), ResponseCode::accepted);
  EXPECT_EQ(h.code(CommandId::go_to_absolute_position, positions(10, 10)), ResponseCode::already_in_motion);
  EXPECT_EQ(h.code(CommandId::go_to_relative_position, positions(1, 1)), ResponseCode::already_in_motion);
  EXPECT_EQ(h.code(CommandId::send_new_trajectory, two_u32(1, 1)), ResponseCode::already_in_motion);
  EXPECT_EQ(h.code(CommandId::go_to_datums), ResponseCode::already_in_motion);
}

TEST(FpsSimMotion, TargetsBeyondTheHardStopsAreOutOfRange) {
  Harness h;  // stops at -5 and 365; the approach needs 0.9 deg above the target
  EXPECT_EQ(h.code(CommandId::go_to_absolute_position, positions(-5.5, 180)), ResponseCode::value_out_of_range);
  EXPECT_EQ(h.code(CommandId::go_to_absolute_position, positions(10, 364.5)), ResponseCode::value_out_of_range);
  EXPECT_EQ(h.code(CommandId::go_to_relative_position, positions(0, 190)), ResponseCode::value_out_of_range);
  EXPECT_EQ(h.code(CommandId::go_to_absolute_position, positions(-4, 364)), ResponseCode::accepted);
}

TEST(FpsSimMotion, StopTrajectoryStopsWhereTheArmIs) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::switch_off_precise_move_alpha), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(90, 180)), ResponseCode::accepted);
  h.wait(1s);
  EXPECT_EQ(h.code(CommandId::stop_trajectory), ResponseCode::accepted);
  EXPECT_TRUE(h.status().has(StatusBit::displacement_completed));
  h.wait(10s);
  EXPECT_NEAR(h.position().first, 12.0, 1e-3);
}

TEST(FpsSimMotion, TrajectoryAbortAsBroadcastStopsToo) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(90, 180)), ResponseCode::accepted);
  h.wait(1s);
  auto out = h.send(CommandId::trajectory_abort, {}, 0);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].id.response, ResponseCode::accepted);
  EXPECT_FALSE(h.model.moving());
}

TEST(FpsSimMotion, SetSpeedChecksTheFactoryLimits) {
  Harness h;
  EXPECT_EQ(h.code(CommandId::set_speed, two_u32(0, 2000)), ResponseCode::value_out_of_range);
  EXPECT_EQ(h.code(CommandId::set_speed, two_u32(2000, 5001)), ResponseCode::value_out_of_range);
  EXPECT_EQ(h.code(CommandId::set_speed, two_u32(5000, 1)), ResponseCode::accepted);
}

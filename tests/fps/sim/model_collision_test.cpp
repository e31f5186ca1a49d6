// PositionerModel: collisions (injected and with the hard stops), their flags, the unsolicited
// report, what TRAJECTORY_ABORT keeps and STOP_TRAJECTORY clears, and driving with detection off.
#include "harness.hpp"

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::sim;
using namespace axon::fps::sim::testing;

TEST(FpsSimCollision, InjectedCollisionStopsReportsAndBlocksMoves) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(90, 90)), ResponseCode::accepted);
  h.wait(1s);
  const auto out = h.model.inject_collision(Arm::beta, h.now);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].id.positioner, 7);
  EXPECT_EQ(out[0].id.command, 18);
  EXPECT_EQ(out[0].id.uid, 0);
  EXPECT_EQ(out[0].id.response, ResponseCode::beta_collision);
  EXPECT_TRUE(out[0].payload.empty());
  EXPECT_FALSE(h.model.moving());  // both arms stop
  auto s = h.status();
  EXPECT_TRUE(s.has(StatusBit::collision_beta));
  EXPECT_FALSE(s.has(StatusBit::collision_alpha));
  EXPECT_TRUE(s.has(StatusBit::displacement_completed));
  EXPECT_NEAR(h.position().first, 12, 1e-3);

  EXPECT_EQ(h.code(CommandId::go_to_relative_position, positions(-2, 0)), ResponseCode::beta_collision);
  EXPECT_EQ(h.code(CommandId::send_new_trajectory, two_u32(1, 0)), ResponseCode::beta_collision);
  EXPECT_EQ(h.code(CommandId::start_trajectory), ResponseCode::beta_collision);
  EXPECT_EQ(h.code(CommandId::trajectory_abort), ResponseCode::accepted);
  EXPECT_TRUE(h.status().collided());  // abort keeps the flags for diagnosis
  EXPECT_EQ(h.code(CommandId::stop_trajectory), ResponseCode::accepted);
  EXPECT_FALSE(h.status().collided());
  EXPECT_EQ(h.code(CommandId::go_to_relative_position, positions(-2, 0)), ResponseCode::accepted);
}

TEST(FpsSimCollision, AlphaCollisionIsCode8AndWinsOverBeta) {
  Harness h;
  (void)h.model.inject_collision(Arm::beta, h.now);
  const auto out = h.model.inject_collision(Arm::alpha, h.now);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].id.response, ResponseCode::alpha_collision);
  EXPECT_EQ(h.code(CommandId::go_to_datums), ResponseCode::alpha_collision);
  EXPECT_EQ(h.code(CommandId::calibrate_motors), ResponseCode::alpha_collision);
}

TEST(FpsSimCollision, WrongPositionDrivesIntoTheHardStop) {
  Harness h;  // physically at alpha 0; the stop is at -5
  ASSERT_EQ(h.code(CommandId::set_current_position, positions(50, 180)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::switch_off_precise_move_alpha), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(40, 180)), ResponseCode::accepted);
  h.wait(400ms);
  EXPECT_TRUE(h.unsolicited.empty());
  h.wait(100ms);  // 5 deg at 12 deg/s: contact after 0.417 s
  ASSERT_EQ(h.unsolicited.size(), 1u);
  EXPECT_EQ(h.unsolicited[0].id.command, 18);
  EXPECT_EQ(h.unsolicited[0].id.response, ResponseCode::alpha_collision);
  EXPECT_NEAR(h.model.physical_deg(Arm::alpha), -5, 1e-3);
  EXPECT_NEAR(h.position().first, 45, 1e-3);
  EXPECT_TRUE(h.status().has(StatusBit::collision_alpha));
  EXPECT_EQ(h.model.counters().collisions, 1u);
}

TEST(FpsSimCollision, OpenLoopWithoutDetectionLosesStepsAgainstTheStop) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::set_current_position, positions(50, 180)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::alpha_open_loop_without_collision_detection), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::switch_off_precise_move_alpha), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(40, 180)), ResponseCode::accepted);
  h.wait_idle();
  EXPECT_TRUE(h.unsolicited.empty());
  EXPECT_NEAR(h.model.physical_deg(Arm::alpha), -5, 1e-6);
  EXPECT_NEAR(h.position().first, 40, 1e-6);  // the firmware believes it got there
  const auto hall = protocol::ArmPositions::decode(h.ask(CommandId::get_hall_position).payload.span()).value();
  EXPECT_NEAR(hall.alpha.degrees(), 45, 1e-6);  // the sensors see where the arm is
  // Driving back, the arm follows at once: the lost steps stay lost.
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(50, 180)), ResponseCode::accepted);
  h.wait_idle();
  EXPECT_NEAR(h.model.physical_deg(Arm::alpha), 5, 1e-6);
}

TEST(FpsSimCollision, ClosedLoopWithoutDetectionWaitsAtTheStopAndKeepsCount) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::set_current_position, positions(50, 180)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::alpha_closed_loop_without_collision_detection), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::switch_off_precise_move_alpha), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(40, 180)), ResponseCode::accepted);
  h.wait_idle();
  EXPECT_TRUE(h.unsolicited.empty());
  EXPECT_NEAR(h.model.physical_deg(Arm::alpha), -5, 1e-6);
  EXPECT_NEAR(h.position().first, 45, 1e-6);  // counts what the arm did
}

TEST(FpsSimCollision, CollisionDuringATrajectoryStopsBothArms) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::send_new_trajectory, two_u32(1, 1)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::send_trajectory_data, point(100, 10)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::send_trajectory_data, point(80, 10)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::trajectory_data_end), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::start_trajectory), ResponseCode::accepted);
  h.wait(5s);
  (void)h.model.inject_collision(Arm::alpha, h.now);
  h.wait(5s);
  EXPECT_NEAR(h.position().first, 50, 1e-3);
  EXPECT_NEAR(h.position().second, 130, 1e-3);
  EXPECT_EQ(h.code(CommandId::stop_trajectory), ResponseCode::accepted);
  EXPECT_EQ(h.code(CommandId::start_trajectory), ResponseCode::accepted);  // nothing left to resume
  EXPECT_FALSE(h.model.moving());
}

TEST(FpsSimCollision, NothingWhenNotInTheApplication) {
  Harness h;
  h.model.power_off(h.now);
  EXPECT_TRUE(h.model.inject_collision(Arm::alpha, h.now).empty());
}

TEST(FpsSimCollision, FrictionAboveTheMarginGivesFalseCollisionsUntilTheMarginIsRaised) {
  Harness h;  // beta margin 20 by default
  h.model.set_friction_fault(Arm::beta, 25);
  ASSERT_EQ(h.code(CommandId::go_to_relative_position, positions(0, -10)), ResponseCode::accepted);
  h.wait(300ms);
  ASSERT_EQ(h.unsolicited.size(), 1u);
  EXPECT_EQ(h.unsolicited[0].id.response, ResponseCode::beta_collision);
  // Raise the margin, clear the flags, move again: no more false alarms.
  ASSERT_EQ(h.code(CommandId::set_collision_margin, two_i32(-5, 30)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::stop_trajectory), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::go_to_relative_position, positions(0, -10)), ResponseCode::accepted);
  h.wait_idle();
  EXPECT_EQ(h.unsolicited.size(), 1u);
  EXPECT_FALSE(h.status().collided());
}

TEST(FpsSimCollision, FrictionIsHarmlessWithDetectionOff) {
  Harness h;
  h.model.set_friction_fault(Arm::alpha, 30);
  ASSERT_EQ(h.code(CommandId::alpha_closed_loop_without_collision_detection), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::go_to_relative_position, positions(10, 0)), ResponseCode::accepted);
  h.wait_idle();
  EXPECT_TRUE(h.unsolicited.empty());
  EXPECT_NEAR(h.position().first, 10, 1e-6);
}

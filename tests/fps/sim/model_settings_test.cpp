// PositionerModel: settings and reads: positions, offsets, currents, torques, hall, cogging
// tables, modes, LED, precise moves, temperature, collision margins.
#include "harness.hpp"

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::sim;
using namespace axon::fps::sim::testing;

namespace {
protocol::PositionAndValue pos_value(const Message& m) {
  return protocol::PositionAndValue::decode(m.payload.span()).value();
}
}  // namespace

TEST(FpsSimSettings, SetCurrentPositionRedefinesWhereTheArmIs) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::set_current_position, positions(10, 20)), ResponseCode::accepted);
  auto [a, b] = h.position();
  EXPECT_NEAR(a, 10, 1e-6);
  EXPECT_NEAR(b, 20, 1e-6);
  EXPECT_NEAR(h.model.physical_deg(Arm::beta), 180, 1e-9);  // the arm did not move
}

TEST(FpsSimSettings, SetCurrentPositionInitialisesALostDatum) {
  auto c = test_config();
  c.datums_initialized = false;
  Harness h(c);
  EXPECT_FALSE(h.status().has(StatusBit::datum_alpha_initialized));
  ASSERT_EQ(h.code(CommandId::set_current_position, positions(0, 180)), ResponseCode::accepted);
  EXPECT_TRUE(h.status().initialized());
}

TEST(FpsSimSettings, OffsetsShiftReportedPositionsAndTargets) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::set_offsets, positions(5, -10)), ResponseCode::accepted);
  EXPECT_EQ(h.ask(CommandId::get_offsets).payload, positions(5, -10));
  auto [a, b] = h.position();
  EXPECT_NEAR(a, -5, 1e-6);
  EXPECT_NEAR(b, 190, 1e-6);
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(0, 190)), ResponseCode::accepted);
  h.wait_idle();
  EXPECT_NEAR(h.model.physical_deg(Arm::alpha), 5, 1e-6);
  EXPECT_NEAR(h.model.physical_deg(Arm::beta), 180, 1e-6);
}

TEST(FpsSimSettings, SettingsThatCannotChangeDuringAMove) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(30, 180)), ResponseCode::accepted);
  EXPECT_EQ(h.code(CommandId::set_current_position, positions(0, 0)), ResponseCode::already_in_motion);
  EXPECT_EQ(h.code(CommandId::set_offsets, positions(0, 0)), ResponseCode::already_in_motion);
  EXPECT_EQ(h.code(CommandId::alpha_open_loop_with_collision_detection), ResponseCode::already_in_motion);
  // Speeds, currents and reads are fine.
  EXPECT_EQ(h.code(CommandId::set_speed, two_u32(1000, 1000)), ResponseCode::accepted);
  EXPECT_EQ(h.code(CommandId::get_current_position), ResponseCode::accepted);
}

TEST(FpsSimSettings, SetCurrentChecksTheFactoryLimit) {
  auto c = test_config();
  c.max_current_percent = 80;
  c.default_drive_current_percent = 50;
  Harness h(c);
  EXPECT_EQ(h.code(CommandId::set_current, two_u32(81, 10)), ResponseCode::value_out_of_range);
  EXPECT_EQ(h.code(CommandId::set_current, two_u32(10, 101)), ResponseCode::value_out_of_range);
  EXPECT_EQ(h.code(CommandId::set_current, two_u32(80, 70)), ResponseCode::accepted);
}

TEST(FpsSimSettings, CurrentsAndTorquesAtRestAreTheHoldingCurrents) {
  Harness h;
  EXPECT_EQ(values(h.ask(CommandId::get_currents)), (protocol::ArmValues{0, 30}));
  EXPECT_EQ(values(h.ask(CommandId::get_torques)), (protocol::ArmValues{0, 30}));
  ASSERT_EQ(h.code(CommandId::set_holding_current, two_u32(45, 30)), ResponseCode::accepted);
  const auto pc = pos_value(h.ask(CommandId::get_position_and_current_alpha));
  EXPECT_EQ(pc.value, 45);
  EXPECT_NEAR(pc.position.degrees(), 0, 1e-6);
  const auto pt = pos_value(h.ask(CommandId::get_position_and_torque_beta));
  EXPECT_EQ(pt.value, 30);
  EXPECT_NEAR(pt.position.degrees(), 180, 1e-6);
  EXPECT_EQ(h.code(CommandId::set_holding_current, two_u32(101, 30)), ResponseCode::value_out_of_range);
}

TEST(FpsSimSettings, TorqueFollowsTheDirectionOfMotion) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(90, 90)), ResponseCode::accepted);
  h.wait(1s);
  const auto t = values(h.ask(CommandId::get_torques));
  EXPECT_GT(t.alpha, 0);
  EXPECT_LT(t.beta, 0);
  const auto cur = values(h.ask(CommandId::get_currents));
  EXPECT_GT(cur.alpha, 0);
  EXPECT_GT(cur.beta, 0);
  EXPECT_NEAR(pos_value(h.ask(CommandId::get_position_and_current_beta)).position.degrees(), 168, 1e-3);
}

TEST(FpsSimSettings, OpenLoopDrivesWithTheSetCurrent) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::alpha_open_loop_with_collision_detection), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::set_current, two_u32(70, 70)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(90, 180)), ResponseCode::accepted);
  h.wait(1s);
  EXPECT_EQ(values(h.ask(CommandId::get_currents)).alpha, 70);
}

TEST(FpsSimSettings, HallPositionTracksTheArm) {
  Harness h;
  const auto p = protocol::ArmPositions::decode(h.ask(CommandId::get_hall_position).payload.span()).value();
  EXPECT_NEAR(p.alpha.degrees(), 0, 1e-6);
  EXPECT_NEAR(p.beta.degrees(), 180, 1e-6);
}

TEST(FpsSimSettings, CoggingTables) {
  Harness h;
  EXPECT_EQ(h.ask(CommandId::get_cogging_vector_length).payload, Payload().put_u32(1024));
  const auto pos = values(h.ask(CommandId::get_cogging_positive, two_u32(10, 20)));
  const auto neg = values(h.ask(CommandId::get_cogging_negative, two_u32(10, 20)));
  EXPECT_LE(std::abs(pos.alpha), 1000);
  EXPECT_NE(pos.alpha, pos.beta);
  EXPECT_EQ(neg, values(h.ask(CommandId::get_cogging_negative, two_u32(10, 20))));  // stable
  EXPECT_EQ(values(h.ask(CommandId::get_cogging_angles, two_u32(0, 512))), (protocol::ArmValues{0, 180}));
  EXPECT_EQ(h.code(CommandId::get_cogging_positive, two_u32(1024, 0)), ResponseCode::value_out_of_range);
  EXPECT_EQ(h.code(CommandId::get_cogging_angles, two_u32(0, 5000)), ResponseCode::value_out_of_range);
}

TEST(FpsSimSettings, CoggingValuesAreZeroBeforeCalibration) {
  auto c = test_config();
  c.cogging_calibrated = false;
  Harness h(c);
  EXPECT_EQ(values(h.ask(CommandId::get_cogging_positive, two_u32(3, 3))), (protocol::ArmValues{0, 0}));
}

TEST(FpsSimSettings, ControlModesShowInTheStatus) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::alpha_open_loop_without_collision_detection), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::beta_closed_loop_without_collision_detection), ResponseCode::accepted);
  auto s = h.status();
  EXPECT_FALSE(s.has(StatusBit::closed_loop_alpha));
  EXPECT_TRUE(s.has(StatusBit::collision_detect_alpha_disable));
  EXPECT_TRUE(s.has(StatusBit::hall_alpha_disable));  // open loop without detection: sensors unused
  EXPECT_TRUE(s.has(StatusBit::closed_loop_beta));
  EXPECT_TRUE(s.has(StatusBit::collision_detect_beta_disable));
  EXPECT_FALSE(s.has(StatusBit::hall_beta_disable));
  ASSERT_EQ(h.code(CommandId::alpha_open_loop_with_collision_detection), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::beta_open_loop_with_collision_detection), ResponseCode::accepted);
  s = h.status();
  EXPECT_FALSE(s.has(StatusBit::collision_detect_alpha_disable));
  EXPECT_FALSE(s.has(StatusBit::closed_loop_beta));
  ASSERT_EQ(h.code(CommandId::alpha_closed_loop_with_collision_detection), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::alpha_closed_loop_without_collision_detection), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::beta_open_loop_without_collision_detection), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::beta_closed_loop_with_collision_detection), ResponseCode::accepted);
  s = h.status();
  EXPECT_TRUE(s.has(StatusBit::closed_loop_alpha));
  EXPECT_TRUE(s.has(StatusBit::collision_detect_alpha_disable));
  EXPECT_TRUE(s.has(StatusBit::closed_loop_beta));
  EXPECT_FALSE(s.has(StatusBit::collision_detect_beta_disable));
}

TEST(FpsSimSettings, PreciseMoveSwitches) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::switch_off_precise_move_alpha), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::switch_off_precise_move_beta), ResponseCode::accepted);
  auto s = h.status();
  EXPECT_FALSE(s.has(StatusBit::precise_move_alpha));
  EXPECT_FALSE(s.has(StatusBit::precise_move_beta));
  // Without the approach a zero relative move takes no time.
  const auto t = protocol::ArmTimes::decode(h.ask(CommandId::go_to_relative_position, positions(0, 0)).payload.span());
  EXPECT_EQ(t.value().alpha.ticks(), 0u);
  h.wait(1ms);
  ASSERT_EQ(h.code(CommandId::switch_on_precise_move_alpha), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::switch_on_precise_move_beta), ResponseCode::accepted);
  s = h.status();
  EXPECT_TRUE(s.has(StatusBit::precise_move_alpha));
  EXPECT_TRUE(s.has(StatusBit::precise_move_beta));
}

TEST(FpsSimSettings, LedBlinksAfterStartThenObeys) {
  Harness h;
  EXPECT_TRUE(h.model.led_on());
  h.wait(3s);
  EXPECT_FALSE(h.model.led_on());
  ASSERT_EQ(h.code(CommandId::switch_on_led), ResponseCode::accepted);
  EXPECT_TRUE(h.model.led_on());
  ASSERT_EQ(h.code(CommandId::switch_off_led), ResponseCode::accepted);
  EXPECT_FALSE(h.model.led_on());
}

TEST(FpsSimSettings, RawTemperature) {
  auto c = test_config();
  c.raw_temperature = 1234;
  Harness h(c);
  EXPECT_EQ(h.ask(CommandId::get_raw_temperature).payload, Payload().put_u32(1234));
}

TEST(FpsSimSettings, CollisionMarginRange) {
  Harness h;
  EXPECT_EQ(h.code(CommandId::set_collision_margin, two_i32(-30, 30)), ResponseCode::accepted);
  EXPECT_EQ(h.code(CommandId::set_collision_margin, two_i32(-31, 0)), ResponseCode::value_out_of_range);
  EXPECT_EQ(h.code(CommandId::set_collision_margin, two_i32(0, 31)), ResponseCode::value_out_of_range);
}

TEST(FpsSimSettings, HallSleepsAndNeedsTimeToWake) {
  Harness h;  // wake-up 5 s
  ASSERT_EQ(h.code(CommandId::switch_off_hall), ResponseCode::accepted);
  auto s = h.status();
  EXPECT_TRUE(s.has(StatusBit::hall_alpha_disable));
  EXPECT_TRUE(s.has(StatusBit::hall_beta_disable));
  EXPECT_TRUE(s.has(StatusBit::switch_off_hall_after_move));
  EXPECT_EQ(h.code(CommandId::go_to_relative_position, positions(1, 1)), ResponseCode::hall_sensors_disabled);
  EXPECT_EQ(h.code(CommandId::calibrate_motors), ResponseCode::hall_sensors_disabled);
  ASSERT_EQ(h.code(CommandId::switch_on_hall), ResponseCode::accepted);
  EXPECT_FALSE(h.status().has(StatusBit::switch_off_hall_after_move));
  h.wait(4s);
  EXPECT_EQ(h.code(CommandId::go_to_relative_position, positions(1, 1)), ResponseCode::hall_sensors_disabled);
  EXPECT_TRUE(h.status().hall_disabled());
  h.wait(1s);
  EXPECT_FALSE(h.status().hall_disabled());
  EXPECT_EQ(h.code(CommandId::go_to_relative_position, positions(1, 1)), ResponseCode::accepted);
}

TEST(FpsSimSettings, HallSwitchedOffDuringAMoveSleepsWhenItEnds) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::go_to_relative_position, positions(12, 0)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::switch_off_hall), ResponseCode::accepted);
  EXPECT_FALSE(h.status().hall_disabled());
  h.wait_idle();
  EXPECT_TRUE(h.status().hall_disabled());
  EXPECT_NEAR(h.position().first, 12, 1e-6);  // the move was not cut short
}

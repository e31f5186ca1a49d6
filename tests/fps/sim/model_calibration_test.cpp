// PositionerModel: datum searches (20..22), datum calibration (23..25), motor calibration
// (26..28), cogging calibration (47..49), save calibration (53), with time moved by hand.
#include "harness.hpp"

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::sim;
using namespace axon::fps::sim::testing;

namespace {

PositionerConfig lost(double alpha, double beta) {
  auto c = test_config();
  c.datums_initialized = false;
  c.start_position_deg = {{alpha, beta}};
  return c;
}
}  // namespace

TEST(FpsSimCalibration, GoToDatumsDrivesIntoTheStopsAndInitialises) {
  Harness h(lost(30, 100));
  EXPECT_FALSE(h.status().initialized());
  EXPECT_NEAR(h.position().first, 0, 1e-9);  // the counter restarted at zero
  ASSERT_EQ(h.code(CommandId::go_to_datums), ResponseCode::accepted);
  auto s = h.status();
  EXPECT_TRUE(s.has(StatusBit::datum_initialization));
  EXPECT_FALSE(s.has(StatusBit::displacement_completed));
  h.wait(3s);  // alpha: 35 deg at 12 deg/s = 2.92 s
  s = h.status();
  EXPECT_TRUE(s.has(StatusBit::datum_alpha_initialized));
  EXPECT_FALSE(s.has(StatusBit::datum_beta_initialized));
  h.wait(6s);  // beta: 105 deg = 8.75 s
  s = h.status();
  EXPECT_TRUE(s.initialized());
  EXPECT_FALSE(s.has(StatusBit::datum_initialization));
  EXPECT_TRUE(s.has(StatusBit::displacement_completed));
  const auto [a, b] = h.position();
  EXPECT_NEAR(a, -5, 1e-6);  // at the lower stops
  EXPECT_NEAR(b, -5, 1e-6);
  EXPECT_TRUE(h.unsolicited.empty());  // hitting the stop is expected, not a collision
}

TEST(FpsSimCalibration, GoToDatumOfOneArm) {
  Harness h(lost(30, 100));
  ASSERT_EQ(h.code(CommandId::go_to_datum_beta), ResponseCode::accepted);
  h.wait_idle();
  EXPECT_NEAR(h.model.physical_deg(Arm::alpha), 30, 1e-9);
  EXPECT_NEAR(h.model.physical_deg(Arm::beta), -5, 1e-9);
  auto s = h.status();
  EXPECT_FALSE(s.has(StatusBit::datum_alpha_initialized));
  EXPECT_TRUE(s.has(StatusBit::datum_beta_initialized));
  ASSERT_EQ(h.code(CommandId::go_to_datum_alpha), ResponseCode::accepted);
  h.wait_idle();
  EXPECT_TRUE(h.status().initialized());
}

TEST(FpsSimCalibration, GoToDatumsRepairsAWronglySetPosition) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::set_current_position, positions(40, 200)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::go_to_datums), ResponseCode::accepted);
  h.wait_idle();
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(0, 180)), ResponseCode::accepted);
  h.wait_idle();
  EXPECT_NEAR(h.model.physical_deg(Arm::alpha), 0, 1e-9);
  EXPECT_NEAR(h.model.physical_deg(Arm::beta), 180, 1e-9);
}

TEST(FpsSimCalibration, GoToDatumsNeedsCalibratedMotorsAndDatums) {
  auto c = test_config();
  c.datums_calibrated = false;
  Harness h(c);
  EXPECT_EQ(h.code(CommandId::go_to_datums), ResponseCode::datum_not_calibrated);
  EXPECT_EQ(h.code(CommandId::go_to_datum_alpha), ResponseCode::datum_not_calibrated);
  c.motors_calibrated = false;
  Harness m(c);
  EXPECT_EQ(m.code(CommandId::go_to_datum_beta), ResponseCode::motor_not_calibrated);
}

TEST(FpsSimCalibration, DatumCalibrationHitsTheStopThreeTimes) {
  auto c = lost(10, 20);
  c.datums_calibrated = false;
  Harness h(c);
  EXPECT_FALSE(h.status().datums_calibrated());
  ASSERT_EQ(h.code(CommandId::calibrate_datum), ResponseCode::accepted);
  EXPECT_TRUE(h.status().has(StatusBit::datum_calibration));
  EXPECT_TRUE(h.status().calibrating());
  // Everything that moves or changes the reference waits for the calibration.
  EXPECT_EQ(h.code(CommandId::go_to_absolute_position, positions(1, 1)), ResponseCode::calibration_mode_active);
  EXPECT_EQ(h.code(CommandId::calibrate_motors), ResponseCode::calibration_mode_active);
  EXPECT_EQ(h.code(CommandId::send_new_trajectory, two_u32(1, 1)), ResponseCode::calibration_mode_active);
  EXPECT_EQ(h.code(CommandId::set_current_position, positions(1, 1)), ResponseCode::calibration_mode_active);
  EXPECT_EQ(h.code(CommandId::save_calibration), ResponseCode::calibration_mode_active);
  // beta: 25 deg to the stop, then twice 5 deg out and back: 45 deg at 12 deg/s = 3.75 s.
  h.wait(3700ms);
  EXPECT_TRUE(h.status().has(StatusBit::datum_calibration));
  h.wait(100ms);
  const auto s = h.status();
  EXPECT_FALSE(s.has(StatusBit::datum_calibration));
  EXPECT_TRUE(s.datums_calibrated());
  EXPECT_TRUE(s.initialized());
  const auto spread = values(h.ask(CommandId::get_datum_calibration_error));
  EXPECT_GE(spread.alpha, 0);
  EXPECT_LE(spread.alpha, 40);  // motor degrees, at most the configured scatter
  EXPECT_GE(spread.beta, 0);
  EXPECT_LE(spread.beta, 40);
  EXPECT_NEAR(h.position().first, -5, 0.05);  // the new zero is the mean of the hits
}

TEST(FpsSimCalibration, DatumCalibrationOfOneArmAndItsPreconditions) {
  auto c = test_config();
  c.datums_calibrated = false;
  c.motors_calibrated = false;
  Harness h(c);
  EXPECT_EQ(h.code(CommandId::calibrate_datum_alpha), ResponseCode::motor_not_calibrated);
  ASSERT_EQ(h.code(CommandId::calibrate_motor_alpha), ResponseCode::accepted);
  h.wait_idle();
  ASSERT_EQ(h.code(CommandId::calibrate_datum_alpha), ResponseCode::accepted);
  h.wait_idle();
  const auto s = h.status();
  EXPECT_TRUE(s.has(StatusBit::datum_alpha_calibrated));
  EXPECT_FALSE(s.has(StatusBit::datum_beta_calibrated));
  EXPECT_EQ(h.code(CommandId::calibrate_datum_beta), ResponseCode::motor_not_calibrated);
}

TEST(FpsSimCalibration, MotorCalibrationTakesItsTimeAndReturns) {
  auto c = test_config();
  c.motors_calibrated = false;
  Harness h(c);
  EXPECT_FALSE(h.status().motors_calibrated());
  EXPECT_EQ(h.code(CommandId::go_to_relative_position, positions(1, 1)), ResponseCode::motor_not_calibrated);
  EXPECT_EQ(h.code(CommandId::calibrate_cogging), ResponseCode::motor_not_calibrated);
  EXPECT_EQ(h.code(CommandId::calibrate_datum), ResponseCode::motor_not_calibrated);
  ASSERT_EQ(h.code(CommandId::calibrate_motors), ResponseCode::accepted);
  EXPECT_TRUE(h.status().has(StatusBit::motor_calibration));
  h.wait(10s);
  EXPECT_GT(std::abs(h.model.physical_deg(Arm::alpha)), 0.5);  // a few motor turns away
  h.wait(9900ms);
  EXPECT_TRUE(h.status().has(StatusBit::motor_calibration));
  h.wait(100ms);
  const auto s = h.status();
  EXPECT_FALSE(s.has(StatusBit::motor_calibration));
  EXPECT_TRUE(s.motors_calibrated());
  EXPECT_NEAR(h.model.physical_deg(Arm::alpha), 0, 1e-9);
  EXPECT_NEAR(h.model.physical_deg(Arm::beta), 180, 1e-9);
  const auto err = values(h.ask(CommandId::get_motor_calibration_error));
  EXPECT_GE(err.alpha, 0);
  EXPECT_LE(err.alpha, 2);
  EXPECT_EQ(h.code(CommandId::go_to_relative_position, positions(1, 1)), ResponseCode::accepted);
}

TEST(FpsSimCalibration, OpenLoopWithoutDetectionNeedsNoMotorCalibrationToMove) {
  auto c = test_config();
  c.motors_calibrated = false;
  Harness h(c);
  ASSERT_EQ(h.code(CommandId::alpha_open_loop_without_collision_detection), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::beta_open_loop_without_collision_detection), ResponseCode::accepted);
  EXPECT_EQ(h.code(CommandId::go_to_relative_position, positions(1, 1)), ResponseCode::accepted);
}

TEST(FpsSimCalibration, CalibrationsNeedTheHallSensors) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::beta_open_loop_without_collision_detection), ResponseCode::accepted);
  EXPECT_EQ(h.code(CommandId::calibrate_motors), ResponseCode::hall_sensors_disabled);
  EXPECT_EQ(h.code(CommandId::calibrate_datum_beta), ResponseCode::hall_sensors_disabled);
  EXPECT_EQ(h.code(CommandId::calibrate_cogging_beta), ResponseCode::hall_sensors_disabled);
  EXPECT_EQ(h.code(CommandId::go_to_datum_beta), ResponseCode::hall_sensors_disabled);
  EXPECT_EQ(h.code(CommandId::calibrate_motor_alpha), ResponseCode::accepted);  // alpha is fine
}

TEST(FpsSimCalibration, CoggingCalibrationDrivesToTheStopThenTakesLong) {
  auto c = test_config();
  c.cogging_calibrated = false;
  Harness h(c);
  EXPECT_EQ(protocol::ArmValues::decode(h.ask(CommandId::get_cogging_positive, two_u32(1, 1)).payload.span()).value(),
            (protocol::ArmValues{0, 0}));
  ASSERT_EQ(h.code(CommandId::calibrate_cogging), ResponseCode::accepted);
  EXPECT_TRUE(h.status().has(StatusBit::cogging_calibration));
  h.wait(39min);
  EXPECT_TRUE(h.status().has(StatusBit::cogging_calibration));
  EXPECT_EQ(h.code(CommandId::go_to_datums), ResponseCode::calibration_mode_active);
  h.wait(1min + 16s);  // 40 min after reaching the stops (beta: 185 deg, 15.4 s away)
  const auto s = h.status();
  EXPECT_FALSE(s.has(StatusBit::cogging_calibration));
  EXPECT_TRUE(s.has(StatusBit::cogging_alpha_calibrated));
  EXPECT_TRUE(s.has(StatusBit::cogging_beta_calibrated));
  EXPECT_NE(values(h.ask(CommandId::get_cogging_positive, two_u32(1, 1))), (protocol::ArmValues{0, 0}));
  EXPECT_NEAR(h.model.physical_deg(Arm::beta), -5, 1e-9);  // it ends at the stop
}

TEST(FpsSimCalibration, StopEndsACalibrationWithoutResult) {
  auto c = test_config();
  c.cogging_calibrated = false;
  Harness h(c);
  ASSERT_EQ(h.code(CommandId::calibrate_cogging_alpha), ResponseCode::accepted);
  h.wait(10min);
  ASSERT_EQ(h.code(CommandId::stop_trajectory), ResponseCode::accepted);
  const auto s = h.status();
  EXPECT_FALSE(s.calibrating());
  EXPECT_TRUE(s.has(StatusBit::displacement_completed));
  EXPECT_FALSE(s.has(StatusBit::cogging_alpha_calibrated));
}

TEST(FpsSimCalibration, SavedCalibrationSurvivesAPowerCycleAndUnsavedDoesNot) {
  auto c = test_config();
  c.motors_calibrated = false;
  c.boot_time = 0s;
  Harness h(c);
  ASSERT_EQ(h.code(CommandId::calibrate_motors), ResponseCode::accepted);
  h.wait_idle();
  ASSERT_EQ(h.code(CommandId::set_offsets, positions(1, 2)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::set_holding_current, two_u32(45, 35)), ResponseCode::accepted);
  EXPECT_TRUE(h.status().motors_calibrated());
  h.model.power_cycle(h.now);
  EXPECT_FALSE(h.status().motors_calibrated());
  EXPECT_EQ(h.ask(CommandId::get_offsets).payload, positions(0, 0));
  EXPECT_EQ(h.ask(CommandId::get_holding_current).payload, two_u32(0, 30));

  ASSERT_EQ(h.code(CommandId::calibrate_motors), ResponseCode::accepted);
  h.wait_idle();
  ASSERT_EQ(h.code(CommandId::set_offsets, positions(1, 2)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::set_holding_current, two_u32(45, 35)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::save_calibration), ResponseCode::accepted);
  h.model.power_cycle(h.now);
  EXPECT_TRUE(h.status().motors_calibrated());
  EXPECT_EQ(h.ask(CommandId::get_offsets).payload, positions(1, 2));
  EXPECT_EQ(h.ask(CommandId::get_holding_current).payload, two_u32(45, 35));
}

// PositionerModel: identity, status and the plain reads, in the application and the bootloader.
#include "harness.hpp"

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::sim;
using namespace axon::fps::sim::testing;

TEST(FpsSimModel, AnswersGetIdWithItsOwnIdAndTheRequestsUid) {
  Harness h;
  auto out = h.raw(1);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].id.positioner, 7);
  EXPECT_EQ(out[0].id.command, 1);
  EXPECT_EQ(out[0].id.uid, h.next_uid);
  EXPECT_EQ(out[0].id.response, ResponseCode::accepted);
  EXPECT_EQ(protocol::PositionerIdReply::decode(out[0].payload.span()).value().id, 7);
}

TEST(FpsSimModel, AnswersBroadcastsWithItsOwnIdAndUidZero) {
  Harness h;
  auto out = h.send(CommandId::get_id, {}, 0);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].id.positioner, 7);
  EXPECT_EQ(out[0].id.uid, 0);
}

TEST(FpsSimModel, IgnoresRequestsForOtherPositioners) {
  Harness h;
  EXPECT_TRUE(h.send(CommandId::get_id, {}, 8).empty());
  EXPECT_EQ(h.model.counters().ignored, 1u);
}

TEST(FpsSimModel, ReportsTheConfiguredFirmwareVersion) {
  auto c = test_config();
  c.firmware = {4, 1, 21};
  Harness h(c);
  const auto m = h.ask(CommandId::get_firmware_version);
  EXPECT_EQ(m.payload.to_hex(), "15 01 04 00");  // ZZ YY XX 00
}

TEST(FpsSimModel, StatusOfACalibratedRobotAtRest) {
  Harness h;
  const auto m = h.ask(CommandId::get_status);
  EXPECT_EQ(m.payload.size(), 8u);
  const auto s = protocol::PositionerStatus::decode(m.payload.span()).value();
  EXPECT_TRUE(s.ready_to_move());
  EXPECT_TRUE(s.initialized());
  EXPECT_TRUE(s.motors_calibrated());
  EXPECT_TRUE(s.datums_calibrated());
  EXPECT_TRUE(s.has(StatusBit::cogging_alpha_calibrated));
  EXPECT_TRUE(s.has(StatusBit::cogging_beta_calibrated));  // bit 32: above the low word
  EXPECT_TRUE(s.has(StatusBit::closed_loop_alpha));
  EXPECT_TRUE(s.has(StatusBit::closed_loop_beta));
  EXPECT_TRUE(s.has(StatusBit::precise_move_alpha));
  EXPECT_TRUE(s.has(StatusBit::precise_move_beta));
  EXPECT_TRUE(s.has(StatusBit::position_restored));
  EXPECT_TRUE(s.has(StatusBit::low_power_after_move));
  EXPECT_FALSE(s.collided());
  EXPECT_FALSE(s.calibrating());
  EXPECT_FALSE(s.hall_disabled());
  EXPECT_EQ(s.unknown_bits(), 0u);
}

TEST(FpsSimModel, StartsFolded) {
  Harness h;
  const auto [a, b] = h.position();
  EXPECT_NEAR(a, 0.0, 1e-6);
  EXPECT_NEAR(b, 180.0, 1e-6);
}

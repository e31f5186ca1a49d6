// Board firmware: rates, order, alignment, receive timeout, errors and recovery, PD controller,
// malformed input. Time is passed by hand; frames are decoded with the protocol codec.
#include "board_harness.hpp"

#include "axon/blmc/protocol/message_id.hpp"
#include "axon/blmc/protocol/units.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace axon;
using namespace axon::blmc;
using namespace axon::blmc::sim;
using namespace axon::blmc::sim::test;
using protocol::ErrorCode;
using protocol::MessageId;

TEST(BlmcBoard, StatusOncePerSecondEvenWhileDisabled) {
  BoardHarness h;
  h.command("SEND_ALL=1");  // data is on, but the system is off: only status goes out
  h.run_until(3500ms);
  ASSERT_EQ(h.sent.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(h.sent[i].at, std::chrono::seconds(i));
    const auto* s = std::get_if<protocol::Status>(&h.sent[i].msg);
    ASSERT_NE(s, nullptr);
    EXPECT_EQ(*s, protocol::Status{});
  }
}

TEST(BlmcBoard, DataEveryMillisecondInTheDocumentedOrder) {
  BoardConfig c;
  c.adc[0].offset = 0.25;
  c.adc[1] = AdcSignal{AdcSignal::Kind::sine, 0.5, 0.25, 1.0, 0.0};
  BoardHarness h(c);
  h.command("ENABLE_SYS=1");
  h.command("SEND_ALL=1");
  h.run_until(1010ms);
  // Cycles 0..1010 ms (the commands took effect in cycle 0), four data frames each; plus status at
  // 0 and 1000 ms.
  std::vector<MessageId> ids;
  for (const auto& s : h.sent) {
    if (s.at < 1ms || s.at > 10ms) continue;
    ids.push_back(std::get<protocol::PairMessage>(s.msg).id);
  }
  ASSERT_EQ(ids.size(), 40u);
  for (std::size_t i = 0; i < ids.size(); i += 4) {
    EXPECT_EQ(ids[i], MessageId::current);
    EXPECT_EQ(ids[i + 1], MessageId::position);
    EXPECT_EQ(ids[i + 2], MessageId::velocity);
    EXPECT_EQ(ids[i + 3], MessageId::adc6);
  }
  EXPECT_EQ(h.of(MessageId::current).size(), 1011u);
  EXPECT_EQ(h.statuses().size(), 2u);
  // Contents: standing motors, the scripted ADC signals.
  const auto adc = h.of(MessageId::adc6);
  for (const auto& s : adc) {
    const auto& v = std::get<protocol::PairMessage>(s.msg).values;
    EXPECT_NEAR(v.motor1, 0.25, 1e-7);
    const double t = std::chrono::duration<double>(s.at).count();
    EXPECT_NEAR(v.motor2, 0.5 + 0.25 * std::sin(protocol::kTwoPi * t), 1e-7);
  }
  for (const auto& s : h.of(MessageId::position)) EXPECT_EQ(std::get<protocol::PairMessage>(s.msg).values, protocol::MotorPair{});
}

TEST(BlmcBoard, EachSendFlagSelectsItsMessage) {
  BoardHarness h;
  h.command("ENABLE_SYS=1");
  h.command("SEND_POSITION=1");
  h.command("SEND_ADC6=1");
  h.run_until(5ms);
  EXPECT_EQ(h.of(MessageId::position).size(), 6u);  // cycles 0..5
  EXPECT_EQ(h.of(MessageId::adc6).size(), 6u);
  EXPECT_TRUE(h.of(MessageId::current).empty());
  EXPECT_TRUE(h.of(MessageId::velocity).empty());
  h.command("SEND_ALL=0");
  const auto before = h.sent.size();
  h.run_for(5ms);
  EXPECT_EQ(h.sent.size(), before);
}

TEST(BlmcBoard, AlignmentOnFirstEnableThenReady) {
  BoardHarness h;
  h.command("ENABLE_SYS=1");
  h.command("ENABLE_MTR1=1");
  h.run_for(1ms);
  EXPECT_TRUE(h.board.status().motor1_enabled);
  EXPECT_FALSE(h.board.status().motor1_ready);
  h.run_for(h.board.config().alignment_time - 10ms);
  EXPECT_FALSE(h.board.status().motor1_ready);
  h.run_for(20ms);
  EXPECT_TRUE(h.board.status().motor1_ready);
  EXPECT_FALSE(h.board.status().motor2_ready);
  // Ready stays across disable/enable: no second alignment.
  h.command("ENABLE_MTR1=0");
  h.run_for(1ms);
  h.command("ENABLE_MTR1=1");
  h.run_for(2ms);
  EXPECT_TRUE(h.board.status().motor1_ready);
  // The status frames say the same.
  h.run_until(3000ms);
  const auto st = h.statuses();
  ASSERT_EQ(st.size(), 4u);
  EXPECT_FALSE(st[1].motor1_ready);  // at 1 s: aligning
  EXPECT_TRUE(st[1].motor1_enabled);
  EXPECT_TRUE(st[3].motor1_ready);
  // A power cycle forgets it.
  h.board.power_cycle();
  EXPECT_FALSE(h.board.status().motor1_ready);
  EXPECT_FALSE(h.board.status().system_enabled);
}

TEST(BlmcBoard, IqRefIsIgnoredDuringAlignment) {
  BoardHarness h;
  h.command("ENABLE_SYS=1");
  h.command("SEND_ALL=1");
  h.command("ENABLE_MTR1=1");
  h.iq_ref(1.0);
  h.run_for(h.board.config().alignment_time - 5ms);
  EXPECT_EQ(h.board.motor(0).continuous_position_rev(), 0.0);
  for (const auto& s : h.of(MessageId::current)) EXPECT_EQ(std::get<protocol::PairMessage>(s.msg).values.motor1, 0.0);
  h.run_for(100ms);
  EXPECT_TRUE(h.board.status().motor1_ready);
  EXPECT_NEAR(h.board.motor(0).current_a(), 1.0, 1e-12);
  EXPECT_GT(h.board.motor(0).velocity_rev_s(), 1.0);
  EXPECT_NEAR(std::get<protocol::PairMessage>(h.of(MessageId::current).back().msg).values.motor1, 1.0, 1e-6);
}

TEST(BlmcBoard, DisablingDuringAlignmentRestartsIt) {
  BoardHarness h;
  h.command("ENABLE_SYS=1");
  h.command("ENABLE_MTR1=1");
  h.run_for(h.board.config().alignment_time / 2);
  h.command("ENABLE_MTR1=0");
  h.run_for(1ms);
  h.command("ENABLE_MTR1=1");
  h.run_for(h.board.config().alignment_time - 10ms);
  EXPECT_FALSE(h.board.status().motor1_ready);
  h.run_for(20ms);
  EXPECT_TRUE(h.board.status().motor1_ready);
}

TEST(BlmcBoard, ReceiveTimeoutFiresOneCycleAfterTheTimeoutAndDisables) {
  BoardHarness h;
  h.enable_and_align();
  h.command("SET_CAN_RECV_TIMEOUT=10");
  h.iq_ref(0.5);
  const BoardTime t0 = h.now;
  // Other frames do not reset it.
  h.run_for(5ms);
  h.command("SEND_ALL=1");
  h.run_until(t0 + 10ms);
  EXPECT_EQ(h.board.status().error, ErrorCode::none);
  h.run_until(t0 + 11ms);
  const auto s = h.board.status();
  EXPECT_EQ(s.error, ErrorCode::can_recv_timeout);
  EXPECT_FALSE(s.system_enabled);
  EXPECT_FALSE(s.motor1_enabled);
  EXPECT_TRUE(s.motor1_ready);
  // Disabled: no more data, no more current.
  const auto data = h.of(MessageId::current).size();
  h.run_for(10ms);
  EXPECT_EQ(h.of(MessageId::current).size(), data);
  EXPECT_EQ(h.board.motor(0).current_a(), 0.0);
  // The next status frame carries the error.
  h.run_until(std::chrono::duration_cast<BoardTime>(std::chrono::ceil<std::chrono::seconds>(h.now)));
  EXPECT_EQ(h.statuses().back().error, ErrorCode::can_recv_timeout);
}

TEST(BlmcBoard, ReceiveTimeoutOnlyWithAnEnabledMotorAndNonZeroIqRef) {
  BoardHarness h;
  h.enable_and_align();
  h.command("SET_CAN_RECV_TIMEOUT=10");
  h.iq_ref(0.0);  // zero reference: quiet host is fine
  h.run_for(500ms);
  EXPECT_EQ(h.board.status().error, ErrorCode::none);
  h.iq_ref(0.0, 0.3);  // non-zero, but motor 2 is not enabled
  h.run_for(500ms);
  EXPECT_EQ(h.board.status().error, ErrorCode::none);
  // IqRef in a loop keeps it alive.
  h.iq_ref(0.2);
  for (int i = 0; i < 100; ++i) {
    h.run_for(5ms);
    h.iq_ref(0.2);
  }
  EXPECT_EQ(h.board.status().error, ErrorCode::none);
  EXPECT_TRUE(h.board.status().system_enabled);
  h.run_for(20ms);
  EXPECT_EQ(h.board.status().error, ErrorCode::can_recv_timeout);
}

TEST(BlmcBoard, RecoveryIsEnableSysThenZeroCurrentThenEnableMotor) {
  BoardHarness h;
  h.enable_and_align();
  h.command("SET_CAN_RECV_TIMEOUT=10");
  h.iq_ref(0.5);
  h.run_for(20ms);
  ASSERT_EQ(h.board.status().error, ErrorCode::can_recv_timeout);
  // Enabling the motor again with the stale non-zero reference times out at once.
  h.command("ENABLE_SYS=1");
  h.run_for(1ms);
  EXPECT_EQ(h.board.status().error, ErrorCode::none);
  EXPECT_TRUE(h.board.status().system_enabled);
  h.command("ENABLE_MTR1=1");
  h.run_for(2ms);
  EXPECT_EQ(h.board.status().error, ErrorCode::can_recv_timeout);
  // The documented order works.
  h.command("ENABLE_SYS=1");
  h.iq_ref(0.0);
  h.command("ENABLE_MTR1=1");
  h.run_for(200ms);
  const auto s = h.board.status();
  EXPECT_EQ(s.error, ErrorCode::none);
  EXPECT_TRUE(s.system_enabled);
  EXPECT_TRUE(s.motor1_enabled);
  EXPECT_TRUE(s.motor1_ready);
}

TEST(BlmcBoard, ErrorPrecedenceWhenSeveralHold) {
  {
    BoardHarness h;
    h.enable_and_align();
    h.command("SET_CAN_RECV_TIMEOUT=5");
    h.iq_ref(1.0);
    h.run_for(10ms);
    ASSERT_EQ(h.board.status().error, ErrorCode::can_recv_timeout);
    h.board.inject(FaultKind::pos_converter);
    h.run_for(1ms);
    EXPECT_EQ(h.board.status().error, ErrorCode::can_recv_timeout);  // timeout outranks position converter
    h.board.inject(FaultKind::transmit);
    h.run_for(1ms);
    EXPECT_EQ(h.board.status().error, ErrorCode::other);  // transmit (as OTHER) outranks timeout
    h.board.inject(FaultKind::encoder);
    h.run_for(1ms);
    EXPECT_EQ(h.board.status().error, ErrorCode::encoder);  // encoder outranks everything
    EXPECT_TRUE(h.board.faults().recv_timeout);
    EXPECT_TRUE(h.board.faults().pos_converter);
  }
  {
    BoardHarness h;
    h.command("ENABLE_SYS=1");
    h.command("ENABLE_POS_ROLLOVER_ERROR=1");
    h.board.motor(0).set_state(99.99, 50.0);
    h.board.inject(FaultKind::over_current);
    h.run_for(2ms);
    EXPECT_TRUE(h.board.faults().pos_rollover);
    EXPECT_EQ(h.board.status().error, ErrorCode::pos_rollover);  // rollover outranks over-current
    h.board.inject(FaultKind::pos_converter);
    h.run_for(1ms);
    EXPECT_EQ(h.board.status().error, ErrorCode::pos_converter);
  }
}

TEST(BlmcBoard, AnyErrorDisablesTheSystem) {
  for (FaultKind k : {FaultKind::encoder, FaultKind::pos_converter, FaultKind::transmit, FaultKind::over_current}) {
    BoardHarness h;
    h.enable_and_align(true);
    h.board.inject(k);
    h.run_for(1ms);
    const auto s = h.board.status();
    EXPECT_NE(s.error, ErrorCode::none) << name(k);
    EXPECT_FALSE(s.system_enabled) << name(k);
    EXPECT_FALSE(s.motor1_enabled || s.motor2_enabled) << name(k);
    // A glitch clears with the recovery sequence.
    h.command("ENABLE_SYS=1");
    h.run_for(1ms);
    EXPECT_EQ(h.board.status().error, ErrorCode::none) << name(k);
    EXPECT_TRUE(h.board.status().system_enabled) << name(k);
  }
}

TEST(BlmcBoard, RecoveryIsRefusedWhileTheCauseRemains) {
  BoardFaultPlan plan;
  plan.events.push_back(FaultEvent{100ms, FaultKind::encoder, 500ms, false});
  BoardHarness h({}, plan);
  h.command("ENABLE_SYS=1");
  h.run_until(150ms);
  EXPECT_EQ(h.board.status().error, ErrorCode::encoder);
  h.command("ENABLE_SYS=1");
  h.run_for(1ms);
  EXPECT_EQ(h.board.status().error, ErrorCode::encoder);
  EXPECT_FALSE(h.board.status().system_enabled);
  EXPECT_EQ(h.board.stats().recoveries_refused, 1u);
  h.run_until(600ms);
  h.command("ENABLE_SYS=1");
  h.run_for(1ms);
  EXPECT_EQ(h.board.status().error, ErrorCode::none);
  EXPECT_TRUE(h.board.status().system_enabled);
}

TEST(BlmcBoard, OverCurrentTripAboveTheConfiguredCurrent) {
  BoardConfig c;
  c.over_current_trip_a = 5.0;
  BoardHarness h(c);
  h.enable_and_align();
  h.iq_ref(4.0);
  h.run_for(5ms);
  EXPECT_EQ(h.board.status().error, ErrorCode::none);
  h.iq_ref(6.0);
  h.run_for(2ms);
  EXPECT_TRUE(h.board.over_current_latched());
  EXPECT_EQ(h.board.status().error, ErrorCode::other);
  EXPECT_FALSE(h.board.status().system_enabled);
}

TEST(BlmcBoard, PositionRolloverErrorOnlyWhenEnabled) {
  BoardHarness h;
  h.command("ENABLE_SYS=1");
  h.run_for(1ms);
  h.board.motor(1).set_state(99.99, 50.0);
  h.run_for(5ms);
  EXPECT_EQ(h.board.status().error, ErrorCode::none);
  EXPECT_LT(h.board.motor(1).position_rev(), 0.0);  // wrapped to about -100
  h.command("ENABLE_POS_ROLLOVER_ERROR=1");
  h.run_for(1ms);
  h.board.motor(1).set_state(-99.99, -50.0);
  h.run_for(5ms);
  EXPECT_EQ(h.board.status().error, ErrorCode::pos_rollover);
}

TEST(BlmcBoard, PdControllerDrivesToPosRef) {
  BoardHarness h;
  h.enable_and_align();
  h.command("SEND_ALL=1");
  h.command("CAN_CMD_P_CONTROLLER_LIMIT_IQ_MTR1=3");
  h.command("CAN_CMD_D_CONTROLLER_LIMIT_IQ_MTR1=3");
  h.pair(MessageId::kp, 5.0);    // A per rev
  h.pair(MessageId::kd, 10.0);   // A per krpm
  h.pair(MessageId::pos_ref, 2.0);
  h.pair(MessageId::vel_ref, 0.0);
  h.iq_ref(0.0);
  h.run_for(2s);
  EXPECT_NEAR(h.board.motor(0).position_rev(), 2.0, 0.03);
  EXPECT_NEAR(h.board.motor(0).velocity_rev_s(), 0.0, 0.05);
  const auto pos = h.of(MessageId::position);
  EXPECT_NEAR(std::get<protocol::PairMessage>(pos.back().msg).values.motor1, 2.0, 0.03);
  // The P limit held: never more than 3 A (+ 3 A of D) asked for.
  for (const auto& s : h.of(MessageId::current)) EXPECT_LE(std::abs(std::get<protocol::PairMessage>(s.msg).values.motor1), 6.0 + 1e-6);
}

TEST(BlmcBoard, PdControllerContributesNothingWithoutLimits) {
  BoardHarness h;
  h.enable_and_align();
  h.pair(MessageId::kp, 5.0);
  h.pair(MessageId::pos_ref, 2.0);
  h.run_for(200ms);
  EXPECT_EQ(h.board.motor(0).continuous_position_rev(), 0.0);
}

TEST(BlmcBoard, VirtualSpringHoldsTheEnablePosition) {
  BoardConfig c;
  c.vspring_gain_a_per_rev = 5.0;
  BoardHarness h(c);
  h.enable_and_align();
  h.command("ENABLE_VSPRING1=1");
  h.board.motor(0).set_state(0.0, 5.0);  // a push
  h.run_for(1s);
  EXPECT_NEAR(h.board.motor(0).position_rev(), 0.0, 0.05);
}

TEST(BlmcBoard, EncoderIndexFramesWhenEnabled) {
  BoardConfig c;
  c.motors[1].index_offset_rev = 0.5;
  BoardHarness h(c);
  h.enable_and_align(true);
  h.command("SEND_ENC_INDEX=1");
  h.iq_ref(0.0, 0.5);
  h.run_for(300ms);
  std::vector<protocol::EncoderIndex> idx;
  for (const auto& s : h.sent)
    if (const auto* e = std::get_if<protocol::EncoderIndex>(&s.msg)) idx.push_back(*e);
  const double turns = h.board.motor(1).continuous_position_rev();
  ASSERT_GT(turns, 3.0);
  ASSERT_LT(turns, 99.0);
  EXPECT_EQ(idx.size(), static_cast<std::size_t>(std::floor(turns - 0.5)) + 1);
  for (std::size_t k = 0; k < idx.size(); ++k) {
    EXPECT_EQ(idx[k].motor, 1);
    EXPECT_NEAR(idx[k].position_rev, static_cast<double>(k) + 0.5, 1e-6);
  }
  EXPECT_TRUE(h.of(MessageId::position).empty());  // SEND_ENC_INDEX alone sends no data
}

TEST(BlmcBoard, MalformedFramesAreCountedAndChangeNothing) {
  BoardHarness h;
  const auto frame = [](std::string_view text) { return can::Frame::parse(text).value(); };
  EXPECT_FALSE(h.board.receive(frame("005#00000001000000"), h.now));     // IqRef, 7 bytes
  EXPECT_FALSE(h.board.receive(frame("000#0000000100000077"), h.now));   // unknown command 0x77
  EXPECT_FALSE(h.board.receive(frame("000#0000000200000001"), h.now));   // ENABLE_SYS=2
  EXPECT_FALSE(h.board.receive(frame("000#00"), h.now));                 // command, 1 byte
  EXPECT_EQ(h.board.stats().malformed, 4u);
  EXPECT_FALSE(h.board.receive(frame("100#0102030405060708"), h.now));   // a force sensor
  EXPECT_FALSE(h.board.receive(frame("00000000#0000000100000001"), h.now));  // extended
  EXPECT_FALSE(h.board.receive(frame("010#01"), h.now));                 // a board's status
  EXPECT_EQ(h.board.stats().ignored, 3u);
  EXPECT_EQ(h.board.stats().malformed, 4u);
  h.run_for(5ms);
  EXPECT_FALSE(h.board.status().system_enabled);
  // And the board still works.
  h.command("ENABLE_SYS=1");
  h.run_for(1ms);
  EXPECT_TRUE(h.board.status().system_enabled);
}

TEST(BlmcBoard, ReceiveQueueOverflowIsCounted) {
  BoardConfig c;
  c.receive_queue = 4;
  BoardHarness h(c);
  for (int i = 0; i < 6; ++i) h.iq_ref(0.0);
  EXPECT_EQ(h.board.stats().rx_overflow, 2u);
  h.run_for(1ms);
  EXPECT_EQ(h.board.stats().iq_refs, 4u);
}

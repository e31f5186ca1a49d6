// ControlLoop without a bus: ports fed by hand, cycles run with step() and a manual clock, and one
// run of the real thread that asserts behaviour only (no timing).
#include "axon/blmc/host/control_loop.hpp"
#include "axon/blmc/host/homing.hpp"
#include "axon/blmc/host/pd_controller.hpp"
#include "rig.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <thread>

namespace axon::blmc::host {
namespace {

using testing::pair_frame;
using testing::status_frame;
using protocol::MessageId;
namespace proto = axon::blmc::protocol;

void feed(CyclicPort& p, std::vector<can::Frame> frames) {
  for (const auto& f : frames) ASSERT_TRUE(p.link().deliver(f));
}
void feed_data(CyclicPort& p, double pos1 = 0, double pos2 = 0) {
  feed(p, {pair_frame(MessageId::current, 0, 0), pair_frame(MessageId::position, pos1, pos2),
           pair_frame(MessageId::velocity, 0, 0), pair_frame(MessageId::adc6, 0.5, 0.5)});
}
std::vector<can::Frame> drain(CyclicPort& p) {
  std::vector<can::Frame> out;
  can::Frame f;
  while (p.link().take(f)) out.push_back(f);
  return out;
}

struct Constant final : Controller {
  MotorPair value{};
  int calls = 0;
  void update(const ControlInput&, std::span<MotorPair> c) noexcept override {
    ++calls;
    for (auto& x : c) x = value;
  }
};

TEST(BlmcControlLoop, CycleSendsSafeCurrentsAndRecords) {
  core::ManualClock clock;
  CyclicPort port(64);
  Constant ctl;
  ctl.value = {5.0, -0.5};
  SafetyLimits lim;
  lim.max_current_a = 2.0;
  ControlLoop loop({&port}, ctl, {lim}, {}, clock);
  feed(port, {status_frame(true, true, true, true, true)});
  feed_data(port, 0.25, -0.25);
  loop.step(clock.now(), clock.now());
  const auto sent = drain(port);
  ASSERT_EQ(sent.size(), 1u);
  const auto iq = protocol::decode_pair(MessageId::iq_ref, sent[0]).value();
  EXPECT_DOUBLE_EQ(iq.motor1, 2.0);
  EXPECT_DOUBLE_EQ(iq.motor2, -0.5);
  CycleRecord rec;
  ASSERT_TRUE(loop.pop_record(rec));
  EXPECT_EQ(rec.cycle, 0u);
  EXPECT_EQ(rec.boards, 1);
  EXPECT_DOUBLE_EQ(rec.board[0].position.motor1, 0.25);
  EXPECT_DOUBLE_EQ(rec.board[0].command.motor1, 2.0);
  EXPECT_FALSE(loop.faulted());
}

// The records carry the overruns so far, for a watcher that sees only them (web::BlmcView).
TEST(BlmcControlLoop, RecordsCountTheOverrunsSoFar) {
  core::ManualClock clock;
  CyclicPort port(64);
  Constant ctl;
  ControlLoop loop({&port}, ctl, {SafetyLimits{}}, {}, clock);
  const auto start = clock.now();
  loop.step(start, clock.now());
  clock.advance(3ms);  // the second cycle, due 1 ms after the first, ends after its successor's deadline
  loop.step(start + 1ms, clock.now());
  CycleRecord first, second;
  ASSERT_TRUE(loop.pop_record(first));
  ASSERT_TRUE(loop.pop_record(second));
  EXPECT_EQ(first.overruns, 0u);
  EXPECT_EQ(second.overruns, 1u);
  EXPECT_EQ(loop.overruns(), 1u);
}

TEST(BlmcControlLoop, TimingBookkeepingWithAManualClock) {
  core::ManualClock clock;
  CyclicPort port(64);
  Constant ctl;
  SafetyLimits lim;
  lim.stale_after = std::chrono::hours(1);
  lim.status_stale_after = std::chrono::hours(1);
  ControlLoop loop({&port}, ctl, {lim}, {}, clock);
  auto deadline = clock.now();
  for (int i = 0; i < 5; ++i) {
    clock.advance(i == 3 ? 1300us : 1000us);
    deadline += 1ms;
    loop.step(deadline, clock.now());
  }
  const auto s = loop.stats();
  EXPECT_EQ(s.cycles, 5u);
  EXPECT_EQ(s.jitter_max, 300us);
  EXPECT_EQ(s.late_max, 300us);
  EXPECT_EQ(ctl.calls, 5);
  EXPECT_EQ(loop.cycles(), 5u);
}

TEST(BlmcControlLoop, StaleDataDisablesEveryBoardAndReports) {
  core::ManualClock clock;
  CyclicPort a(64), b(64);
  Constant ctl;
  ctl.value = {1, 1};
  ControlLoop loop({&a, &b}, ctl, {SafetyLimits{}}, {}, clock);
  feed(a, {status_frame(true, true, true, true, true)});
  feed(b, {status_frame(true, true, true, true, true)});
  feed_data(a);
  feed_data(b);
  loop.step(clock.now(), clock.now());
  EXPECT_EQ(drain(a).size(), 1u);
  EXPECT_EQ(drain(b).size(), 1u);
  // Board b keeps talking, board a goes quiet.
  for (int i = 0; i < 12; ++i) {
    clock.advance(1ms);
    feed_data(b);
    loop.step(clock.now(), clock.now());
    if (loop.faulted()) break;
  }
  ASSERT_TRUE(loop.faulted());
  const auto f = loop.fault().value();
  EXPECT_EQ(f.board, 0u);
  EXPECT_EQ(f.fault.kind, FaultKind::stale_data);
  // Both boards got zero current and their motors disabled in the tripping cycle.
  for (auto* p : {&a, &b}) {
    auto frames = drain(*p);
    ASSERT_GE(frames.size(), 3u);
    const auto tail = std::vector<can::Frame>(frames.end() - 3, frames.end());
    EXPECT_EQ(protocol::decode_pair(MessageId::iq_ref, tail[0]).value(), (MotorPair{0, 0}));
    EXPECT_EQ(protocol::decode_command(tail[1]).value().to_string(), "ENABLE_MTR1=0");
    EXPECT_EQ(protocol::decode_command(tail[2]).value().to_string(), "ENABLE_MTR2=0");
  }
  // Later cycles only send zeros.
  clock.advance(1ms);
  loop.step(clock.now(), clock.now());
  auto later = drain(b);
  ASSERT_EQ(later.size(), 1u);
  EXPECT_EQ(protocol::decode_pair(MessageId::iq_ref, later[0]).value(), (MotorPair{0, 0}));
}

TEST(BlmcControlLoop, BoardErrorIsReportedByName) {
  core::ManualClock clock;
  CyclicPort port(64);
  Constant ctl;
  ControlLoop loop({&port}, ctl, {SafetyLimits{}}, {}, clock);
  feed(port, {status_frame(false, false, true, false, true, protocol::ErrorCode::encoder)});
  feed_data(port);
  loop.step(clock.now(), clock.now());
  ASSERT_TRUE(loop.faulted());
  EXPECT_EQ(loop.fault()->fault.describe(), "board error ENCODER");
}

// A status frame with the error code the spec does not define (6): the loop stops in that very
// cycle, every board gets zero current and its motors disabled, and the report says what came.
TEST(BlmcControlLoop, AnUndocumentedErrorCodeDisablesEveryBoardInTheSameCycle) {
  core::ManualClock clock;
  CyclicPort a(64), b(64);
  Constant ctl;
  ctl.value = {1, 1};
  ControlLoop loop({&a, &b}, ctl, {SafetyLimits{}}, {}, clock);
  for (auto* p : {&a, &b}) {
    feed(*p, {status_frame(true, true, true, true, true)});
    feed_data(*p);
  }
  loop.step(clock.now(), clock.now());
  ASSERT_FALSE(loop.faulted());
  (void)drain(a);
  (void)drain(b);
  clock.advance(1ms);
  feed(b, {can::Frame::standard(0x010, std::vector<std::uint8_t>{0xDF}).value()});  // code 6, flags still on
  feed_data(a);
  feed_data(b);
  loop.step(clock.now(), clock.now());
  ASSERT_TRUE(loop.faulted());
  const auto f = loop.fault().value();
  EXPECT_EQ(f.board, 1u);
  EXPECT_EQ(f.fault.kind, FaultKind::undocumented_error);
  EXPECT_EQ(f.fault.describe(), "board sent undocumented error code 6");
  for (auto* p : {&a, &b}) {
    const auto frames = drain(*p);
    ASSERT_EQ(frames.size(), 3u);
    EXPECT_EQ(protocol::decode_pair(MessageId::iq_ref, frames[0]).value(), (MotorPair{0, 0}));
    EXPECT_EQ(protocol::decode_command(frames[1]).value().to_string(), "ENABLE_MTR1=0");
    EXPECT_EQ(protocol::decode_command(frames[2]).value().to_string(), "ENABLE_MTR2=0");
  }
}

// A board that disabled itself shows first as stale data; the undocumented code in its next
// status still makes it into the report.
TEST(BlmcControlLoop, AStaleDataFaultLearnsAnUndocumentedCodeFromTheNextStatus) {
  core::ManualClock clock;
  CyclicPort port(64);
  Constant ctl;
  ControlLoop loop({&port}, ctl, {SafetyLimits{}}, {}, clock);
  feed(port, {status_frame(true, true, true, true, true)});
  feed_data(port);
  loop.step(clock.now(), clock.now());
  clock.advance(20ms);
  loop.step(clock.now(), clock.now());
  ASSERT_TRUE(loop.faulted());
  clock.advance(1ms);
  feed(port, {can::Frame::standard(0x010, std::vector<std::uint8_t>{0xC0}).value()});
  loop.step(clock.now(), clock.now());
  const auto text = loop.fault()->fault.describe();
  EXPECT_EQ(loop.fault()->fault.kind, FaultKind::stale_data);
  EXPECT_NE(text.find("(board sent undocumented error code 6)"), std::string::npos) << text;
}

TEST(BlmcControlLoop, RejectsBadConfiguration) {
  Constant ctl;
  CyclicPort p(4);
  EXPECT_THROW(ControlLoop({}, ctl, {SafetyLimits{}}), Exception);
  EXPECT_THROW(ControlLoop({&p}, ctl, {SafetyLimits{}, SafetyLimits{}, SafetyLimits{}}), Exception);
}

// Negative or zero limits would make the clamp undefined (lo > hi) or let no current through;
// both are refused with words when the loop is built.
TEST(BlmcControlLoop, RejectsLimitsThatAreNotPositive) {
  Constant ctl;
  CyclicPort p(4);
  auto refused = [&](SafetyLimits lim) -> std::string {
    try {
      ControlLoop loop({&p}, ctl, {lim});
    } catch (const Exception& e) {
      return e.what();
    }
    return "accepted";
  };
  SafetyLimits a;
  a.max_current_a = -1;
  EXPECT_NE(refused(a).find("max current must be > 0 A, got -1"), std::string::npos) << refused(a);
  SafetyLimits b;
  b.max_velocity_krpm = 0;
  EXPECT_NE(refused(b).find("max velocity must be > 0"), std::string::npos) << refused(b);
  SafetyLimits c;
  c.stale_after = -1ms;
  EXPECT_NE(refused(c).find("stale limits must be > 0"), std::string::npos) << refused(c);
  SafetyLimits d;
  d.position[1] = {true, 1.0, -1.0};
  EXPECT_NE(refused(d).find("motor 2 position limit"), std::string::npos) << refused(d);
  SafetyLimits e;
  e.max_current_a = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(refused(e).find("max current"), std::string::npos) << refused(e);
}

// A disable that finds the link to the bus full is queued again in the next cycles, not lost.
TEST(BlmcControlLoop, FaultDisableIsRetriedWhenTheLinkWasFull) {
  core::ManualClock clock;
  CyclicPort port(5);
  Constant ctl;
  ctl.value = {1, 1};
  ControlLoop loop({&port}, ctl, {SafetyLimits{}}, {}, clock);
  feed(port, {status_frame(true, true, true, true, true)});
  feed_data(port);
  for (int i = 0; i < 3; ++i) {
    loop.step(clock.now(), clock.now());  // three IqRef frames wait in the link (room for 5)
    clock.advance(1ms);
  }
  feed(port, {status_frame(false, false, true, false, true, protocol::ErrorCode::encoder)});
  loop.step(clock.now(), clock.now());  // trips: only part of the disable fits
  ASSERT_TRUE(loop.faulted());
  drain(port);
  clock.advance(1ms);
  loop.step(clock.now(), clock.now());
  const auto t = drain(port);
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(protocol::decode_pair(MessageId::iq_ref, t[0]).value(), (MotorPair{0, 0}));
  EXPECT_EQ(protocol::decode_command(t[1]).value().to_string(), "ENABLE_MTR1=0");
  EXPECT_EQ(protocol::decode_command(t[2]).value().to_string(), "ENABLE_MTR2=0");
  clock.advance(1ms);
  loop.step(clock.now(), clock.now());  // then zero current as before
  const auto z = drain(port);
  ASSERT_EQ(z.size(), 1u);
  EXPECT_EQ(protocol::decode_pair(MessageId::iq_ref, z[0]).value(), (MotorPair{0, 0}));
}

// Stopped on request, the loop's last frame is zero current: the board must not keep the
// controller's last value while the caller gets round to disabling it.
TEST(BlmcControlLoop, StopOnRequestEndsWithZeroCurrent) {
  CyclicPort port(4096);
  Constant ctl;
  ctl.value = {0.5, -0.5};
  SafetyLimits lim;
  lim.stale_after = std::chrono::hours(1);
  lim.status_stale_after = std::chrono::hours(1);
  LoopOptions opt;
  opt.realtime = false;
  ControlLoop loop({&port}, ctl, {lim}, opt);
  ASSERT_TRUE(loop.start());
  std::vector<can::Frame> sent;
  for (int i = 0; i < 5000 && sent.size() < 5; ++i) {
    can::Frame f;
    while (port.link().take(f)) sent.push_back(f);
    std::this_thread::sleep_for(1ms);
  }
  loop.stop();
  can::Frame f;
  while (port.link().take(f)) sent.push_back(f);
  ASSERT_GE(sent.size(), 6u);
  EXPECT_EQ(protocol::decode_pair(MessageId::iq_ref, sent.front()).value(), (MotorPair{0.5, -0.5}));
  EXPECT_EQ(protocol::decode_pair(MessageId::iq_ref, sent.back()).value(), (MotorPair{0, 0}));
}

TEST(BlmcControlLoop, ThreadRunsTheControllerAndStops) {
  CyclicPort port(4096);
  Constant ctl;
  ctl.value = {0.1, 0.2};
  SafetyLimits lim;
  lim.stale_after = std::chrono::hours(1);
  lim.status_stale_after = std::chrono::hours(1);
  LoopOptions opt;
  opt.realtime = false;
  ControlLoop loop({&port}, ctl, {lim}, opt);
  ASSERT_TRUE(loop.start());
  std::size_t sent = 0;
  for (int i = 0; i < 5000 && sent < 20; ++i) {
    can::Frame f;
    while (port.link().take(f)) ++sent;
    std::this_thread::sleep_for(1ms);
  }
  loop.stop();
  EXPECT_FALSE(loop.running());
  EXPECT_GE(sent, 20u);
  EXPECT_GE(loop.stats().cycles, 20u);
  CycleRecord r;
  std::size_t records = 0;
  while (loop.pop_record(r)) ++records;
  EXPECT_EQ(records + loop.records_dropped(), loop.stats().cycles);
}

TEST(BlmcControlLoop, ThreadEndsOnFault) {
  CyclicPort port(4096);
  Constant ctl;
  LoopOptions opt;
  opt.realtime = false;
  ControlLoop loop({&port}, ctl, {SafetyLimits{}}, opt);  // nothing ever arrives: stale
  ASSERT_TRUE(loop.start());
  for (int i = 0; i < 5000 && loop.running(); ++i) std::this_thread::sleep_for(1ms);
  EXPECT_FALSE(loop.running());
  ASSERT_TRUE(loop.faulted());
  EXPECT_EQ(loop.fault()->fault.kind, FaultKind::stale_data);
}

TEST(BlmcHoming, MovesUntilTheIndexThenHoldsThere) {
  core::ManualClock clock;
  CyclicPort port(256);
  HomingOptions ho;
  ho.motors = {true, false};
  ho.speed_rev_s = 1.0;
  HomingController homing(1, ho);
  SafetyLimits lim;
  lim.stale_after = std::chrono::hours(1);
  lim.status_stale_after = std::chrono::hours(1);
  ControlLoop loop({&port}, homing, {lim}, {}, clock);
  feed(port, {status_frame(true, true, true, true, true)});
  feed_data(port, 0.0, 0.0);
  loop.step(clock.now(), clock.now());
  (void)drain(port);
  clock.advance(100ms);  // target has moved 0.1 rev ahead: positive current
  feed_data(port, 0.0, 0.0);
  loop.step(clock.now(), clock.now());
  auto f = drain(port);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_GT(protocol::decode_pair(MessageId::iq_ref, f[0]).value().motor1, 0.0);
  EXPECT_EQ(protocol::decode_pair(MessageId::iq_ref, f[0]).value().motor2, 0.0);
  EXPECT_FALSE(homing.done());
  // The index passes at 0.375 rev; the motor overshoots to 0.45.
  feed(port, {proto::encode(proto::EncoderIndex{0.375, 0}).value()});
  feed_data(port, 0.45, 0.0);
  clock.advance(1ms);
  loop.step(clock.now(), clock.now());
  EXPECT_TRUE(homing.done());
  ASSERT_EQ(homing.result(0, 0).state, MotorHoming::State::found);
  EXPECT_DOUBLE_EQ(homing.result(0, 0).index_rev, 0.375);
  EXPECT_TRUE(homing.all_found());
  f = drain(port);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_LT(protocol::decode_pair(MessageId::iq_ref, f[0]).value().motor1, 0.0);  // pulls back to the index
}

TEST(BlmcHoming, FailsAfterMaxTravel) {
  core::ManualClock clock;
  CyclicPort port(256);
  HomingOptions ho;
  ho.motors = {false, true};
  ho.max_travel_rev = 0.5;
  HomingController homing(1, ho);
  SafetyLimits lim;
  lim.stale_after = std::chrono::hours(1);
  lim.status_stale_after = std::chrono::hours(1);
  ControlLoop loop({&port}, homing, {lim}, {}, clock);
  feed_data(port);
  loop.step(clock.now(), clock.now());
  clock.advance(2s);
  loop.step(clock.now(), clock.now());
  EXPECT_TRUE(homing.done());
  EXPECT_EQ(homing.result(0, 1).state, MotorHoming::State::failed);
  EXPECT_FALSE(homing.all_found());
}

}  // namespace
}  // namespace axon::blmc::host

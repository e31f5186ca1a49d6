// Board against a scripted peer on the in-process virtual bus.
#include "axon/blmc/host/board.hpp"
#include "axon/blmc/host/error.hpp"
#include "rig.hpp"

#include <gtest/gtest.h>

namespace axon::blmc::host {
namespace {

using namespace testing;
using protocol::MessageId;

std::vector<std::string> texts(const std::vector<can::Frame>& frames) {
  std::vector<std::string> out;
  for (const auto& f : frames) {
    auto m = proto::decode_to_board(f);
    out.push_back(m ? proto::to_string(m.value()) : f.to_string());
  }
  return out;
}

// A peer that acts on enables like a board whose motors are already aligned, and answers every
// command with a status.
struct EnablingPeer {
  proto::Status st;
  proto::ErrorCode error = proto::ErrorCode::none;
  bool become_ready = true;
  std::vector<can::Frame> operator()(const can::Frame& f) {
    auto c = proto::decode_command(f);
    if (!c) return {};
    const bool on = c.value().raw_value() != 0;
    switch (c.value().code()) {
      case proto::CommandCode::enable_sys: st.system_enabled = on; break;
      case proto::CommandCode::enable_mtr1: st.motor1_enabled = on; st.motor1_ready = on && become_ready; break;
      case proto::CommandCode::enable_mtr2: st.motor2_enabled = on; st.motor2_ready = on && become_ready; break;
      default: break;
    }
    st.error = error;
    return {proto::encode(st).value()};
  }
};

TEST(BlmcBoard, EnableSendsZeroCurrentFirstThenEnablesAndWaitsForReady) {
  Rig rig;
  EnablingPeer peer;
  rig.script = std::ref(peer);
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    auto r = co_await board.enable();
    EXPECT_TRUE(r) << (r ? "" : r.error().message());
    EXPECT_TRUE(board.latest().status.value.motor2_ready);
  });
  EXPECT_EQ(texts(rig.received),
            (std::vector<std::string>{"IQ_REF m1=0 m2=0", "COMMAND ENABLE_SYS=1", "COMMAND SEND_ALL=1",
                                      "COMMAND ENABLE_MTR1=1", "COMMAND ENABLE_MTR2=1"}));
}

TEST(BlmcBoard, EnableOnlyTheMotorsInUse) {
  Rig rig;
  EnablingPeer peer;
  rig.script = std::ref(peer);
  rig.run([&]() -> asio::awaitable<void> {
    BoardOptions o;
    o.motors = {false, true};
    o.send_all = false;
    Board board(*rig.host, o);
    auto r = co_await board.enable();
    EXPECT_TRUE(r);
  });
  EXPECT_EQ(texts(rig.received),
            (std::vector<std::string>{"IQ_REF m1=0 m2=0", "COMMAND ENABLE_SYS=1", "COMMAND ENABLE_MTR2=1"}));
}

TEST(BlmcBoard, EnableFailsWithTheBoardErrorName) {
  Rig rig;
  EnablingPeer peer;
  peer.error = proto::ErrorCode::encoder;
  rig.script = std::ref(peer);
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    auto r = co_await board.enable();
    CO_ASSERT(!r);
    EXPECT_EQ(r.error(), HostErrc::board_error);
    EXPECT_NE(r.error().detail.find("ENCODER"), std::string::npos) << r.error().detail;
  });
}

TEST(BlmcBoard, NotReadyWithinTheTimeout) {
  Rig rig;
  EnablingPeer peer;
  peer.become_ready = false;
  rig.script = std::ref(peer);
  rig.run([&]() -> asio::awaitable<void> {
    BoardOptions o;
    o.ready_timeout = 150ms;
    Board board(*rig.host, o);
    auto r = co_await board.enable();
    CO_ASSERT(!r);
    EXPECT_EQ(r.error(), HostErrc::not_ready);
  });
}

TEST(BlmcBoard, NoStatusAtAllIsATimeout) {
  Rig rig;
  rig.run([&]() -> asio::awaitable<void> {
    BoardOptions o;
    o.ready_timeout = 100ms;
    Board board(*rig.host, o);
    auto r = co_await board.enable();
    CO_ASSERT(!r);
    EXPECT_EQ(r.error(), HostErrc::timeout);
  });
}

TEST(BlmcBoard, DecodesEveryMeasurementWithTimestampsAndCountsBadFrames) {
  Rig rig;
  core::ManualClock clock;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host, {}, clock);
    clock.advance(5ms);
    std::vector<can::Frame> batch1{pair_frame(MessageId::current, 1.5, -0.5), pair_frame(MessageId::position, 10.25, -3.0)};
    co_await rig.send(batch1);
    co_await eventually([&] { return board.latest().frames >= 2; });
    clock.advance(1ms);
    const auto bad_len = can::Frame::standard(0x040, std::vector<std::uint8_t>{1, 2, 3}).value();
    const auto bad_status = can::Frame::standard(0x010, std::vector<std::uint8_t>{0xC0}).value();  // code 6
    const auto bad_adc = pair_frame(MessageId::adc6, 0.5, 0.5);  // fixed below
    auto adc_raw = std::vector<std::uint8_t>(bad_adc.payload().begin(), bad_adc.payload().end());
    adc_raw[0] = 0x7F;  // 127 (far above 1)
    const auto adc_out = can::Frame::standard(0x050, adc_raw).value();
    const auto foreign = can::Frame::standard(0x100, std::vector<std::uint8_t>{1, 2}).value();
    std::vector<can::Frame> batch2{pair_frame(MessageId::velocity, 2.0, -1.0), pair_frame(MessageId::adc6, 0.25, 0.75),
                       proto::encode(proto::EncoderIndex{0.125, 1}).value(),
                       status_frame(true, true, true, false, false), bad_len, bad_status, adc_out, foreign};
    co_await rig.send(batch2);
    co_await eventually([&] { return board.latest().frames + board.latest().rejected + board.latest().foreign >= 10; });
    const auto& m = board.latest();
    EXPECT_EQ(m.current.value, (MotorPair{1.5, -0.5}));
    EXPECT_EQ(m.position.value, (MotorPair{10.25, -3.0}));
    EXPECT_EQ(m.velocity.value, (MotorPair{2.0, -1.0}));
    EXPECT_EQ(m.adc.value, (MotorPair{0.25, 0.75}));
    EXPECT_EQ(m.current.at, core::TimePoint(5ms));
    EXPECT_EQ(m.velocity.at, core::TimePoint(6ms));
    EXPECT_EQ(m.index[1].value, 0.125);
    EXPECT_EQ(m.index[1].count, 1u);
    EXPECT_EQ(m.index[0].count, 0u);
    EXPECT_TRUE(m.status.value.motor1_ready);  // the last status that decoded
    // The status with error code 6 is not a rejected frame: the board reported an error.
    EXPECT_EQ(m.status_byte.value, 0xC0);
    EXPECT_TRUE(m.undocumented_error());
    EXPECT_EQ(m.undocumented_errors, 1u);
    EXPECT_EQ(m.frames, 7u);
    EXPECT_EQ(m.rejected, 2u);
    EXPECT_EQ(m.foreign, 1u);
  });
}

TEST(BlmcBoard, DisableAndRecoverSequences) {
  Rig rig;
  EnablingPeer peer;
  rig.script = std::ref(peer);
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    auto r = co_await board.recover();
    EXPECT_TRUE(r);
    auto d = co_await board.disable();
    EXPECT_TRUE(d);
    co_await eventually([&] { return rig.received.size() >= 8; });
  });
  EXPECT_EQ(texts(rig.received),
            (std::vector<std::string>{"COMMAND ENABLE_SYS=1", "IQ_REF m1=0 m2=0", "COMMAND ENABLE_MTR1=1",
                                      "COMMAND ENABLE_MTR2=1", "IQ_REF m1=0 m2=0", "COMMAND ENABLE_MTR1=0",
                                      "COMMAND ENABLE_MTR2=0", "COMMAND ENABLE_SYS=0"}));
}

TEST(BlmcBoard, DestroyedWhileEnabledDisablesTheMotors) {
  Rig rig;
  EnablingPeer peer;
  rig.script = std::ref(peer);
  rig.run([&]() -> asio::awaitable<void> {
    {
      Board board(*rig.host);
      auto r = co_await board.enable();
      EXPECT_TRUE(r);
    }
    co_await eventually([&] { return !peer.st.system_enabled; });
  });
  const auto t = texts(rig.received);
  ASSERT_GE(t.size(), 4u);
  EXPECT_EQ(std::vector<std::string>(t.end() - 4, t.end()),
            (std::vector<std::string>{"IQ_REF m1=0 m2=0", "COMMAND ENABLE_MTR1=0", "COMMAND ENABLE_MTR2=0",
                                      "COMMAND ENABLE_SYS=0"}));
}

// disable() is the way out of every path, cyclic mode included (the real-time thread stopped but
// stop_cyclic() was never reached, e.g. an exception): it ends cyclic mode and sends the sequence.
TEST(BlmcBoard, DisableInCyclicModeEndsItAndDisables) {
  Rig rig;
  EnablingPeer peer;
  rig.script = std::ref(peer);
  rig.run([&]() -> asio::awaitable<void> {
    BoardOptions o;
    o.recv_timeout_ms = 0;
    Board board(*rig.host, o);
    auto r = co_await board.enable();
    CO_ASSERT(r);
    auto c = co_await board.start_cyclic();
    CO_ASSERT(c);
    EXPECT_TRUE(board.port().send_currents({0.5, 0.5}));
    co_await eventually([&] { return rig.received.size() >= 7; });
    auto d = co_await board.disable();
    EXPECT_TRUE(d) << (d ? "" : d.error().message());
    EXPECT_FALSE(board.cyclic());
    co_await eventually([&] { return !peer.st.system_enabled; });
  });
  const auto t = texts(rig.received);
  ASSERT_GE(t.size(), 4u);
  EXPECT_EQ(std::vector<std::string>(t.end() - 4, t.end()),
            (std::vector<std::string>{"IQ_REF m1=0 m2=0", "COMMAND ENABLE_MTR1=0", "COMMAND ENABLE_MTR2=0",
                                      "COMMAND ENABLE_SYS=0"}));
  EXPECT_FALSE(peer.st.motor1_enabled || peer.st.motor2_enabled);
}

TEST(BlmcBoard, InterruptEndsTheWaitAndRefusesANewEnable) {
  Rig rig;
  EnablingPeer peer;
  peer.become_ready = false;  // the enable would wait for the whole ready timeout
  rig.script = std::ref(peer);
  rig.run([&]() -> asio::awaitable<void> {
    BoardOptions o;
    o.ready_timeout = 30s;
    Board board(*rig.host, o);
    asio::co_spawn(
        rig.io,
        [&]() -> asio::awaitable<void> {
          co_await eventually([&] { return peer.st.motor2_enabled; });
          board.interrupt();
        },
        asio::detached);
    auto r = co_await board.enable();
    CO_ASSERT(!r);
    EXPECT_EQ(r.error(), HostErrc::interrupted);
    const auto before = rig.received.size();
    auto again = co_await board.enable();
    EXPECT_EQ(again.error(), HostErrc::interrupted);
    EXPECT_EQ(rig.received.size(), before) << "an interrupted board sends no enable";
    auto d = co_await board.disable();  // the way out still works
    EXPECT_TRUE(d);
    co_await eventually([&] { return !peer.st.system_enabled; });
  });
}

TEST(BlmcBoard, CyclicModeSetsTheReceiveTimeoutAndExchangesFramesThroughThePort) {
  Rig rig;
  core::ManualClock clock;
  rig.run([&]() -> asio::awaitable<void> {
    BoardOptions o;
    o.recv_timeout_ms = 20;
    Board board(*rig.host, o, clock);
    auto r = co_await board.start_cyclic();
    CO_ASSERT(r);
    EXPECT_TRUE(board.cyclic());
    // Coroutine calls are refused while the real-time side owns the board.
    auto refused = co_await board.send_currents({1, 1});
    EXPECT_EQ(refused.error(), HostErrc::cyclic_active);
    // The "real-time thread" (this test) sends and polls through the port.
    EXPECT_TRUE(board.port().send_currents({0.5, -0.5}));
    std::vector<can::Frame> batch3{pair_frame(MessageId::position, 3.0, 4.0)};
    co_await rig.send(batch3);
    co_await eventually([&] { return rig.received.size() >= 3; });
    co_await eventually([&] {
      board.port().poll(clock.now());
      return board.port().latest().position.received();
    });
    EXPECT_EQ(board.port().latest().position.value, (MotorPair{3.0, 4.0}));
    EXPECT_FALSE(board.latest().position.received());  // the coroutine-side copy is not touched
    auto s = co_await board.stop_cyclic();
    EXPECT_TRUE(s);
    EXPECT_EQ(board.latest().position.value, (MotorPair{3.0, 4.0}));
    // Frames the RT side never polled are not lost when cyclic mode ends.
    std::vector<can::Frame> batch4{pair_frame(MessageId::velocity, 1.0, 1.0)};
    co_await rig.send(batch4);
    co_await eventually([&] { return board.latest().velocity.received(); });
    EXPECT_EQ(board.latest().velocity.value, (MotorPair{1.0, 1.0}));
  });
  EXPECT_EQ(texts(rig.received), (std::vector<std::string>{"IQ_REF m1=0 m2=0", "COMMAND SET_CAN_RECV_TIMEOUT=20",
                                                           "IQ_REF m1=0.5 m2=-0.5", "IQ_REF m1=0 m2=0"}));
}

TEST(BlmcBoard, TapSeesBothDirections) {
  Rig rig;
  EnablingPeer peer;
  rig.script = std::ref(peer);
  std::vector<std::pair<std::uint32_t, bool>> seen;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    board.set_tap([&](const can::Frame& f, bool out) { seen.emplace_back(f.id(), out); });
    const auto cmd = proto::Command::flag(proto::CommandCode::enable_sys, true).value();
    auto r = co_await board.command(cmd);
    EXPECT_TRUE(r);
    auto st = co_await board.wait_status(1s);
    EXPECT_TRUE(st);
  });
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[0], (std::pair<std::uint32_t, bool>{0x000, true}));
  EXPECT_EQ(seen[1], (std::pair<std::uint32_t, bool>{0x010, false}));
}

}  // namespace
}  // namespace axon::blmc::host

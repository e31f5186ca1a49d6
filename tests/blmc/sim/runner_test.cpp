// Runner: boards on virtual buses, driven by a manual clock; a host node on each bus.
#include "axon/blmc/protocol/command.hpp"
#include "axon/blmc/protocol/frames.hpp"
#include "axon/blmc/sim/runner.hpp"
#include "axon/can/virtual_bus.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <gtest/gtest.h>

using namespace axon;
using namespace axon::blmc;
using namespace axon::blmc::sim;
using namespace std::chrono_literals;
using protocol::MessageId;

namespace {

struct Rig {
  Rig() : runner(io.get_executor(), options()) {
    for (int i = 0; i < 2; ++i) {
      auto bus = registry.add("can" + std::to_string(i));
      EXPECT_TRUE(bus);
      hosts.push_back(registry.open("can" + std::to_string(i)).value());
      boards.push_back(runner.add({}, {}, registry, "can" + std::to_string(i)).value());
    }
    runner.start();
  }
  RunnerOptions options() {
    RunnerOptions o;
    o.tick = core::Duration::zero();
    o.clock = &clock;
    return o;
  }
  void send(std::size_t bus, const can::Frame& f) {
    asio::co_spawn(io, [&, f]() -> asio::awaitable<void> {
      auto r = co_await hosts[bus]->send(f);
      EXPECT_TRUE(r);
    }, asio::detached);
    io.poll();
  }
  void command(std::size_t bus, std::string_view text) { send(bus, protocol::encode(protocol::Command::parse(text).value()).value()); }
  // Moves the clock in 1 ms steps, stepping the runner each time.
  void run_for(core::Duration d) {
    for (auto t = core::Duration::zero(); t < d; t += 1ms) {
      clock.advance(1ms);
      runner.step();
      io.poll();
    }
  }
  std::vector<protocol::FromBoard> received(std::size_t bus) {
    std::vector<protocol::FromBoard> out;
    while (auto f = hosts[bus]->try_receive()) {
      auto m = protocol::decode_from_board(*f);
      EXPECT_TRUE(m) << f->to_string();
      if (m) out.push_back(m.value());
    }
    return out;
  }

  asio::io_context io;
  core::ManualClock clock;
  can::VirtualBusRegistry registry{io.get_executor()};
  Runner runner;
  std::vector<std::unique_ptr<can::Bus>> hosts;
  std::vector<Board*> boards;
};

}  // namespace

TEST(BlmcSimRunner, EachBoardServesItsOwnBus) {
  Rig rig;
  rig.run_for(1ms);  // cycle 0 and 1: the power-up status on both buses
  for (std::size_t b = 0; b < 2; ++b) {
    const auto got = rig.received(b);
    ASSERT_EQ(got.size(), 1u) << "bus " << b;
    EXPECT_EQ(std::get<protocol::Status>(got[0]), protocol::Status{});
  }
  rig.command(1, "ENABLE_SYS=1");
  rig.command(1, "SEND_ALL=1");
  rig.run_for(5ms);
  EXPECT_TRUE(rig.received(0).empty());  // board 0 was not addressed
  const auto got = rig.received(1);
  ASSERT_EQ(got.size(), 20u);
  const MessageId order[] = {MessageId::current, MessageId::position, MessageId::velocity, MessageId::adc6};
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_EQ(std::get<protocol::PairMessage>(got[i]).id, order[i % 4]);
  EXPECT_TRUE(rig.boards[1]->status().system_enabled);
  EXPECT_FALSE(rig.boards[0]->status().system_enabled);
}

TEST(BlmcSimRunner, StatusEverySecondOfTheClock) {
  Rig rig;
  rig.run_for(3000ms);
  EXPECT_EQ(rig.received(0).size(), 4u);  // 0, 1, 2, 3 s
}

TEST(BlmcSimRunner, AClockJumpSendsOnlyTheLatestCycles) {
  Rig rig;
  rig.command(0, "ENABLE_SYS=1");
  rig.command(0, "SEND_POSITION=1");
  rig.run_for(1ms);
  (void)rig.received(0);
  rig.clock.advance(500ms);  // the process was descheduled
  rig.runner.step();
  rig.io.poll();
  const auto got = rig.received(0);
  // max_catch_up 2 ms: the data of the last 3 cycles, not 500 frames at once.
  EXPECT_EQ(got.size(), 3u);
  EXPECT_EQ(rig.boards[0]->stats().data_skipped, 497u);
  EXPECT_EQ(rig.boards[0]->next_cycle_time(), 502ms);
}

TEST(BlmcSimRunner, MalformedFramesAreCountedNotFatal) {
  Rig rig;
  rig.send(0, can::Frame::parse("005#0102").value());
  rig.send(0, can::Frame::parse("100#0102030405060708").value());
  rig.run_for(1ms);
  EXPECT_EQ(rig.boards[0]->stats().malformed, 1u);
  EXPECT_EQ(rig.boards[0]->stats().ignored, 1u);
  EXPECT_EQ(rig.runner.stats().receive_errors, 2u);
  rig.command(0, "ENABLE_SYS=1");
  rig.run_for(1ms);
  EXPECT_TRUE(rig.boards[0]->status().system_enabled);
}

TEST(BlmcSimRunner, RealTimeTickRunsTheBoards) {
  asio::io_context io;
  can::VirtualBusRegistry registry(io.get_executor());
  ASSERT_TRUE(registry.add("can0"));
  auto host = registry.open("can0").value();
  Runner runner(io.get_executor());
  Board* board = runner.add({}, {}, registry, "can0").value();
  runner.start();
  asio::steady_timer stop(io);
  stop.expires_after(50ms);
  stop.async_wait([&](const boost::system::error_code&) { runner.stop(); });
  io.run();
  EXPECT_GT(runner.stats().ticks, 10u);
  EXPECT_GE(board->next_cycle_time(), 10ms);
  EXPECT_TRUE(host->try_receive());  // the power-up status
}

TEST(BlmcSimRunner, ALateHostTripsTheReceiveTimeout) {
  Rig rig;
  rig.command(0, "ENABLE_SYS=1");
  rig.command(0, "ENABLE_MTR1=1");
  rig.run_for(rig.boards[0]->config().alignment_time + 5ms);
  ASSERT_TRUE(rig.boards[0]->status().motor1_ready);
  rig.command(0, "SET_CAN_RECV_TIMEOUT=20");
  const auto iq = protocol::encode_iq_ref({0.2, 0.0}).value();
  // A host loop at 1 kHz keeps the board running ...
  for (int k = 0; k < 100; ++k) {
    rig.send(0, iq);
    rig.run_for(1ms);
  }
  EXPECT_TRUE(rig.boards[0]->status().system_enabled);
  EXPECT_GT(rig.boards[0]->motor(0).velocity_rev_s(), 0.0);
  // ... until it misses its deadlines for longer than the timeout (the test simply stops sending).
  rig.run_for(19ms);
  EXPECT_EQ(rig.boards[0]->status().error, protocol::ErrorCode::none);
  rig.run_for(3ms);
  EXPECT_EQ(rig.boards[0]->status().error, protocol::ErrorCode::can_recv_timeout);
  EXPECT_FALSE(rig.boards[0]->status().system_enabled);
}

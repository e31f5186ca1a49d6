// The virtual bus as its users see it: who receives what, in which order, and what happens when
// queues overflow or nodes go away.
#include "axon/can/virtual_bus.hpp"
#include "frame_text.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/io_context.hpp>
#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

using namespace axon;
using namespace axon::can;

namespace {

using axon::can::test::F;

// Runs `body` as a coroutine on `io`, then runs `io` until nothing is left to do.
void run_to_end(asio::io_context& io, std::function<asio::awaitable<void>()> body) {
  asio::co_spawn(io, std::move(body), [](std::exception_ptr e) {
    if (e) std::rethrow_exception(e);
  });
  io.run();
  io.restart();
}

std::vector<std::string> drain(Bus& bus) {
  std::vector<std::string> out;
  while (auto f = bus.try_receive()) out.push_back(f->to_string());
  return out;
}

using Strings = std::vector<std::string>;

}  // namespace

TEST(VirtualBus, DeliversToEveryOtherNodeButNotTheSender) {
  asio::io_context io;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0");
  auto a = medium->attach("a"), b = medium->attach("b"), c = medium->attach("c");
  EXPECT_EQ(medium->node_count(), 3u);
  run_to_end(io, [&]() -> asio::awaitable<void> {
    EXPECT_TRUE((co_await a->send(F("123#01"))).has_value());
    EXPECT_TRUE((co_await b->send(F("456#02"))).has_value());
  });
  EXPECT_EQ(drain(*a), (Strings{"456#02"}));
  EXPECT_EQ(drain(*b), (Strings{"123#01"}));
  EXPECT_EQ(drain(*c), (Strings{"123#01", "456#02"}));
  EXPECT_EQ(a->stats().frames_out, 1u);
  EXPECT_EQ(c->stats().frames_in, 2u);
  EXPECT_EQ(medium->stats().frames, 2u);
}

TEST(VirtualBus, ReceiveCoroutineWakesOnDelivery) {
  asio::io_context io;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0");
  auto a = medium->attach(), b = medium->attach();
  std::string got;
  asio::co_spawn(io, [&]() -> asio::awaitable<void> {
    auto f = co_await b->receive();
    if (f) got = f.value().to_string();
  }, asio::detached);
  asio::co_spawn(io, [&]() -> asio::awaitable<void> { (void)co_await a->send(F("7FF#CAFE")); }, asio::detached);
  io.run();
  EXPECT_EQ(got, "7FF#CAFE");
}

TEST(VirtualBus, TimestampsDeliveredFrames) {
  asio::io_context io;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0");
  auto a = medium->attach(), b = medium->attach();
  run_to_end(io, [&]() -> asio::awaitable<void> { (void)co_await a->send(F("100#")); });
  auto f = b->try_receive();
  ASSERT_TRUE(f);
  EXPECT_GT(f->timestamp().count(), 0);
}

TEST(VirtualBus, ReceiverFiltersApply) {
  asio::io_context io;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0");
  auto a = medium->attach(), b = medium->attach();
  b->set_filters({Filter{0x100, 0x700}});
  run_to_end(io, [&]() -> asio::awaitable<void> {
    for (const char* t : {"100#", "1FF#01", "200#", "000#"}) (void)co_await a->send(F(t));
  });
  EXPECT_EQ(drain(*b), (Strings{"100#", "1FF#01"}));
  EXPECT_EQ(b->stats().rx_filtered, 2u);
}

TEST(VirtualBus, ArbitrationPicksLowestHeadAndKeepsEachNodesOrder) {
  asio::io_context io;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0");
  auto a = medium->attach("a"), b = medium->attach("b"), rx = medium->attach("rx");
  // All four are queued before the medium runs. Only queue heads compete: a's 0x100 waits behind
  // its own 0x300 although it would beat everything.
  run_to_end(io, [&]() -> asio::awaitable<void> {
    (void)co_await a->send(F("300#"));
    (void)co_await a->send(F("100#"));
    (void)co_await b->send(F("200#"));
    (void)co_await b->send(F("050#"));
    EXPECT_EQ(a->tx_pending(), 2u);
    EXPECT_EQ(b->tx_pending(), 2u);
  });
  EXPECT_EQ(drain(*rx), (Strings{"200#", "050#", "300#", "100#"}));
  EXPECT_EQ(a->tx_pending(), 0u);
  EXPECT_EQ(medium->stats().arbitration_rounds_contended, 2u);  // the last two had no rival
}

TEST(VirtualBus, ArbitrationStandardBeatsExtendedAndDataBeatsRemote) {
  asio::io_context io;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0");
  auto a = medium->attach(), b = medium->attach(), c = medium->attach(), rx = medium->attach();
  run_to_end(io, [&]() -> asio::awaitable<void> {
    (void)co_await a->send(F("04000000#"));  // extended, same base id as 0x010
    (void)co_await b->send(F("010#R"));
    (void)co_await c->send(F("010#"));
  });
  EXPECT_EQ(drain(*rx), (Strings{"010#", "010#R", "04000000#"}));
}

TEST(VirtualBus, EqualKeysGoInQueueingOrder) {
  asio::io_context io;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0");
  auto a = medium->attach(), b = medium->attach(), rx = medium->attach();
  run_to_end(io, [&]() -> asio::awaitable<void> {
    (void)co_await b->send(F("123#0B"));
    (void)co_await a->send(F("123#0A"));
  });
  EXPECT_EQ(drain(*rx), (Strings{"123#0B", "123#0A"}));
}

TEST(VirtualBus, SingleNodeKeepsItsOrder) {
  asio::io_context io;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0");
  auto a = medium->attach(), rx = medium->attach();
  Strings sent;
  run_to_end(io, [&]() -> asio::awaitable<void> {
    for (int i = 0; i < 50; ++i) {
      auto f = Frame::standard(static_cast<std::uint32_t>((i * 37) % 0x800), {}).value();
      sent.push_back(f.to_string());
      (void)co_await a->send(f);
    }
  });
  EXPECT_EQ(drain(*rx), sent);
}

TEST(VirtualBus, TransmitQueueOverflow) {
  asio::io_context io;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0");
  BusOptions small;
  small.tx_capacity = 2;
  auto a = medium->attach("a", small), rx = medium->attach();
  run_to_end(io, [&]() -> asio::awaitable<void> {
    EXPECT_TRUE((co_await a->send(F("001#"))).has_value());
    EXPECT_TRUE((co_await a->send(F("002#"))).has_value());
    auto r = co_await a->send(F("003#"));
    EXPECT_FALSE(r.has_value());
    if (!r) {
      EXPECT_EQ(r.error(), CanErrc::tx_overflow);
    }
    EXPECT_EQ(a->tx_pending(), 2u);
  });
  EXPECT_EQ(a->stats().tx_dropped, 1u);
  EXPECT_EQ(a->stats().frames_out, 2u);
  EXPECT_EQ(drain(*rx), (Strings{"001#", "002#"}));
  // Once the medium has taken the frames there is room again.
  run_to_end(io, [&]() -> asio::awaitable<void> { EXPECT_TRUE((co_await a->send(F("004#"))).has_value()); });
  EXPECT_EQ(drain(*rx), (Strings{"004#"}));
}

TEST(VirtualBus, ClosedNodeDropsItsQueueAndRefusesToSend) {
  asio::io_context io;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0");
  auto a = medium->attach(), b = medium->attach(), c = medium->attach();
  run_to_end(io, [&]() -> asio::awaitable<void> {
    (void)co_await a->send(F("001#"));
    (void)co_await a->send(F("002#"));
    (void)co_await b->send(F("003#"));
    a->close();  // before the medium ran: a's frames never go out
    EXPECT_EQ(medium->node_count(), 2u);
    auto r = co_await a->send(F("004#"));
    EXPECT_FALSE(r.has_value());
    if (!r) {
      EXPECT_EQ(r.error(), CanErrc::closed);
    }
  });
  EXPECT_EQ(drain(*c), (Strings{"003#"}));
  EXPECT_TRUE(drain(*a).empty());  // detached: b's frame did not reach it
  EXPECT_EQ(a->state(), BusState::closed);
  a->close();  // twice is fine
  // The rest of the bus keeps working.
  run_to_end(io, [&]() -> asio::awaitable<void> { (void)co_await c->send(F("005#")); });
  EXPECT_EQ(drain(*b), (Strings{"005#"}));
}

TEST(VirtualBus, ReceiveOnClosedNodeReportsClosed) {
  asio::io_context io;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0");
  auto a = medium->attach();
  bool closed = false;
  asio::co_spawn(io, [&]() -> asio::awaitable<void> {
    auto r = co_await a->receive();
    closed = !r && r.error() == CanErrc::closed;
  }, asio::detached);
  asio::co_spawn(io, [&]() -> asio::awaitable<void> {
    a->close();
    co_return;
  }, asio::detached);
  io.run();
  EXPECT_TRUE(closed);
}

TEST(VirtualBus, DestroyedNodeDetaches) {
  asio::io_context io;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0");
  auto a = medium->attach(), b = medium->attach();
  {
    auto gone = medium->attach();
    EXPECT_EQ(medium->node_count(), 3u);
  }
  EXPECT_EQ(medium->node_count(), 2u);
  run_to_end(io, [&]() -> asio::awaitable<void> { (void)co_await a->send(F("001#")); });
  EXPECT_EQ(drain(*b), (Strings{"001#"}));
}

TEST(VirtualBus, NodesKeepTheMediumAlive) {
  asio::io_context io;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0");
  std::weak_ptr<VirtualBus> weak = medium;
  auto a = medium->attach(), b = medium->attach();
  medium.reset();
  ASSERT_FALSE(weak.expired());
  run_to_end(io, [&]() -> asio::awaitable<void> { (void)co_await a->send(F("001#")); });
  EXPECT_EQ(drain(*b), (Strings{"001#"}));
  a.reset();
  b.reset();
  EXPECT_TRUE(weak.expired());
}

TEST(VirtualBus, NodesRunAtTheBusBitrate) {
  asio::io_context io;
  WireModel wire;
  wire.bitrate = 500'000;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0", wire);
  auto a = medium->attach();
  EXPECT_EQ(a->options().bitrate, 500'000u);
}

TEST(VirtualBusRegistry, AddFindOpen) {
  asio::io_context io;
  VirtualBusRegistry reg(io.get_executor());
  ASSERT_TRUE(reg.add("vcan0").has_value());
  ASSERT_TRUE(reg.add("vcan1").has_value());
  auto dup = reg.add("vcan0");
  ASSERT_FALSE(dup.has_value());
  EXPECT_EQ(dup.error(), CanErrc::bad_spec);
  EXPECT_EQ(reg.channels(), (Strings{"vcan0", "vcan1"}));
  EXPECT_TRUE(reg.find("vcan1"));
  EXPECT_FALSE(reg.find("vcan2"));

  auto a = reg.open("vcan0").value();
  auto b = reg.open("vcan0").value();
  auto other = reg.open("vcan1").value();
  EXPECT_EQ(reg.find("vcan0")->node_count(), 2u);
  run_to_end(io, [&]() -> asio::awaitable<void> { (void)co_await a->send(F("123#")); });
  EXPECT_EQ(drain(*b), (Strings{"123#"}));
  EXPECT_TRUE(drain(*other).empty());
}

TEST(VirtualBusRegistry, OpenUnknownNamesTheKnownBuses) {
  asio::io_context io;
  VirtualBusRegistry reg(io.get_executor());
  ASSERT_TRUE(reg.add("alpha").has_value());
  ASSERT_TRUE(reg.add("beta").has_value());
  auto r = reg.open("gamma");
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error(), CanErrc::bad_spec);
  EXPECT_NE(r.error().detail.find("gamma"), std::string::npos);
  EXPECT_NE(r.error().detail.find("alpha, beta"), std::string::npos);
}

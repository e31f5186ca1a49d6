// CanNetGateway against the emulator on loopback, over virtual buses: what a host relies on when
// it drives CAN buses through a CAN@net gateway.
#include "axon/can/cannet_client.hpp"
#include "axon/can/cannet_server.hpp"
#include "axon/can/open.hpp"
#include "axon/can/virtual_bus.hpp"

#include "can/cannet_harness.hpp"
#include "frame_text.hpp"

#include <boost/asio/detached.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/this_coro.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <memory>
#include <string>

using namespace axon;
using namespace axon::can;
using namespace axon::can::test;

namespace {

using axon::can::test::F;

// Two virtual buses ("can0" behind gateway channel 1, "can1" behind channel 2), an emulator on an
// ephemeral loopback port, and an observer node on each bus.
struct ClientBench {
  asio::io_context io;
  VirtualBusRegistry registry{io.get_executor()};
  std::unique_ptr<CanNetGatewayEmulator> emulator;
  std::unique_ptr<Bus> can0, can1;

  explicit ClientBench(WireModel wire = {}, CanNetEmulatorOptions options = {}) {
    (void)registry.add("can0", wire).value();
    (void)registry.add("can1", wire).value();
    options.port = 0;
    emulator = std::make_unique<CanNetGatewayEmulator>(io.get_executor(), registry,
                                                       std::vector<std::string>{"can0", "can1"}, options);
    auto started = emulator->start();
    EXPECT_TRUE(started) << started.error().message();
    can0 = registry.open("can0").value();
    can1 = registry.open("can1").value();
  }

  // (Channels as separate arguments: gcc 12 cannot keep a braced list alive across co_await.)
  template <class... Ch>
  asio::awaitable<Result<std::shared_ptr<CanNetGateway>>> connect(Ch... channels) {
    return connect_with(CanNetOptions{}, channels...);
  }
  template <class... Ch>
  asio::awaitable<Result<std::shared_ptr<CanNetGateway>>> connect_with(CanNetOptions options, Ch... channels) {
    return CanNetGateway::connect(io.get_executor(), emulator->local_endpoint(), std::vector<int>{channels...}, options);
  }
};

}  // namespace

TEST(CanNetClient, SetsUpEveryChannelAndQueriesTheGateway) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    auto gw = co_await b.connect(1, 2);
    CO_ASSERT_TRUE(gw);
    auto& g = *gw.value();
    EXPECT_TRUE(g.is_connected());
    EXPECT_EQ(g.channels(), (std::vector<int>{1, 2}));
    // Five set-up commands per channel, all accepted.
    EXPECT_EQ(b.emulator->stats().commands, 10u);
    EXPECT_EQ(b.emulator->stats().error_replies, 0u);
    EXPECT_EQ(g.stats().commands, 10u);
    auto st = co_await g.status(1);
    CO_ASSERT_TRUE(st);
    EXPECT_EQ(st.value().flags, cannet::StatusFlags{});  // running, no errors
    EXPECT_EQ(st.value().free_tx, 100u);
    auto id = co_await g.identify();
    CO_ASSERT_TRUE(id);
    EXPECT_EQ(id.value(), "CAN@net NT 420");
    auto ver = co_await g.version();
    CO_ASSERT_TRUE(ver);
    EXPECT_EQ(ver.value(), "V1.5.0");
    // The gateway refuses a port with nothing behind it (this bench fits two).
    auto st3 = co_await g.status(3);
    EXPECT_EQ(st3.error(), CanErrc::device_error);
    g.close();
  });
}

TEST(CanNetClient, FramesBothWaysOnTwoChannels) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    auto gw = co_await b.connect(1, 2);
    CO_ASSERT_TRUE(gw);
    auto bus1 = gw.value()->bus(1);
    auto bus2 = gw.value()->bus(2);
    CO_ASSERT_TRUE(bus1 && bus2);
    auto& ch1 = *bus1.value();
    auto& ch2 = *bus2.value();

    // Host -> buses: each channel's frames reach its own bus only.
    for (const char* f : {"123#0102", "1ABCDEF0#0102030405060708", "7FF#R2", "00000001#R0", "000#"})
      CO_ASSERT_TRUE((co_await ch1.send(F(f))).has_value());
    CO_ASSERT_TRUE((co_await ch2.send(F("456#AA"))).has_value());
    std::vector<std::string> on_can0;
    for (int i = 0; i < 5; ++i) {
      auto f = co_await b.can0->receive(5s);
      CO_ASSERT_TRUE(f);
      on_can0.push_back(f.value().to_string());
    }
    EXPECT_EQ(on_can0, (std::vector<std::string>{"123#0102", "1ABCDEF0#0102030405060708", "7FF#R2", "00000001#R", "000#"}));
    auto on_can1 = co_await b.can1->receive(5s);
    CO_ASSERT_TRUE(on_can1);
    EXPECT_EQ(on_can1.value().to_string(), "456#AA");
    EXPECT_EQ(ch1.stats().frames_out, 5u);

    // Buses -> host: demultiplexed by channel, in order, timestamped.
    CO_ASSERT_TRUE((co_await b.can1->send(F("18FE0201#DEADBEEF"))).has_value());
    CO_ASSERT_TRUE((co_await b.can0->send(F("321#R8"))).has_value());
    CO_ASSERT_TRUE((co_await b.can0->send(F("0C0#11"))).has_value());
    auto r2 = co_await ch2.receive(5s);
    CO_ASSERT_TRUE(r2);
    EXPECT_EQ(r2.value().to_string(), "18FE0201#DEADBEEF");
    EXPECT_GT(r2.value().timestamp().count(), 0);
    auto r1a = co_await ch1.receive(5s);
    auto r1b = co_await ch1.receive(5s);
    CO_ASSERT_TRUE(r1a && r1b);
    EXPECT_EQ(r1a.value().to_string(), "321#R8");
    EXPECT_EQ(r1b.value().to_string(), "0C0#11");
    EXPECT_EQ(ch1.pending(), 0u);
    EXPECT_EQ(ch2.pending(), 0u);
    EXPECT_EQ(ch1.stats().frames_in, 2u);
    EXPECT_EQ(gw.value()->stats().protocol_errors, 0u);
    gw.value()->close();
  });
}

TEST(CanNetClient, BusPerChannelRules) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    auto gw = co_await b.connect(2);
    CO_ASSERT_TRUE(gw);
    auto& g = *gw.value();
    EXPECT_EQ(g.bus(1).error(), CanErrc::bad_spec);  // not set up
    auto first = g.bus(2);
    CO_ASSERT_TRUE(first);
    EXPECT_EQ(first.value()->name(), fmt::format("cannet://{}:{}/2", b.emulator->local_endpoint().host,
                                                 b.emulator->local_endpoint().port));
    EXPECT_EQ(g.bus(2).error(), CanErrc::bad_spec);  // one open bus per channel
    first.value()->close();
    auto second = g.bus(2);
    CO_ASSERT_TRUE(second);
    // The bus keeps the connection alive after the caller lets go of the gateway.
    std::weak_ptr<CanNetGateway> weak = gw.value();
    gw.value().reset();
    EXPECT_FALSE(weak.expired());
    CO_ASSERT_TRUE((co_await second.value()->send(F("100#01"))).has_value());
    auto f = co_await b.can1->receive(5s);
    EXPECT_TRUE(f);
    second.value().reset();
    first.value().reset();
    EXPECT_TRUE(weak.expired());
  });
}

TEST(CanNetClient, EventsChangeTheBusState) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    auto gw = co_await b.connect(1, 2);
    CO_ASSERT_TRUE(gw);
    auto& g = *gw.value();
    auto bus2 = g.bus(2);
    CO_ASSERT_TRUE(bus2);
    auto& ch2 = *bus2.value();

    b.emulator->inject_error_warning(2, true);
    (void)co_await g.status(2);  // a round trip: the event line came before the reply
    EXPECT_EQ(ch2.state(), BusState::error_warning);
    EXPECT_EQ(ch2.stats().error_warning_events, 1u);
    b.emulator->inject_error_warning(2, false);
    (void)co_await g.status(2);
    EXPECT_EQ(ch2.state(), BusState::active);

    b.emulator->inject_bus_off(2);
    auto st = co_await g.status(2);
    CO_ASSERT_TRUE(st);
    EXPECT_TRUE(st.value().flags.bus_off);
    EXPECT_EQ(ch2.state(), BusState::bus_off);
    EXPECT_EQ(ch2.stats().bus_off_events, 1u);
    // A bus-off channel refuses frames instead of losing them.
    EXPECT_EQ((co_await ch2.send(F("100#01"))).error(), CanErrc::bus_off);

    CO_ASSERT_TRUE(co_await g.restart(2));
    EXPECT_EQ(ch2.state(), BusState::active);
    CO_ASSERT_TRUE((co_await ch2.send(F("100#02"))).has_value());
    auto f = co_await b.can1->receive(5s);
    CO_ASSERT_TRUE(f);
    EXPECT_EQ(f.value().to_string(), "100#02");
    g.close();
  });
}

TEST(CanNetClient, StateReportedBeforeTheBusWasOpenedIsKept) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    auto gw = co_await b.connect(1);
    CO_ASSERT_TRUE(gw);
    b.emulator->inject_bus_off(1);
    (void)co_await gw.value()->status(1);
    auto bus = gw.value()->bus(1);
    CO_ASSERT_TRUE(bus);
    EXPECT_EQ(bus.value()->state(), BusState::bus_off);
    gw.value()->close();
  });
}

TEST(CanNetClient, MalformedLinesAreCountedAndTheConnectionKept) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    auto gw = co_await b.connect(1);
    CO_ASSERT_TRUE(gw);
    auto& g = *gw.value();
    auto bus = g.bus(1);
    CO_ASSERT_TRUE(bus);
    auto& ch1 = *bus.value();
    for (const char* bad : {"garbage", "M 7 CSD 123 01", "M 1 CSD 123 1 2 3 4 5 6 7 8 9", "M 1 CSD 800 01",
                            "CAN 1 STOP", "R ok", "E 1 BUSOFF LATER"})
      b.emulator->send_raw(bad);
    b.emulator->send_raw(std::string(1000, 'M'));
    b.emulator->send_raw("");  // blank: ignored, not an error
    // A frame after them: once it arrives, every line before it has been handled.
    CO_ASSERT_TRUE((co_await b.can0->send(F("0AB#CD"))).has_value());
    auto f = co_await ch1.receive(5s);
    CO_ASSERT_TRUE(f);
    EXPECT_EQ(f.value().to_string(), "0AB#CD");
    EXPECT_EQ(g.stats().protocol_errors, 8u);
    EXPECT_EQ(ch1.stats().protocol_errors, 8u);
    EXPECT_EQ(ch1.state(), BusState::active);  // the broken BUSOFF event changed nothing
    EXPECT_TRUE(g.is_connected());
    // Commands still work.
    auto st = co_await g.status(1);
    EXPECT_TRUE(st);
    g.close();
  });
}

TEST(CanNetClient, ANewClientReplacesTheOldOneWhoseBusesClose) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    auto old_gw = co_await b.connect(1);
    CO_ASSERT_TRUE(old_gw);
    auto old_bus = old_gw.value()->bus(1);
    CO_ASSERT_TRUE(old_bus);
    CO_ASSERT_TRUE((co_await b.can0->send(F("111#01"))).has_value());
    auto queued = co_await old_bus.value()->receive(5s);
    CO_ASSERT_TRUE(queued);

    auto new_gw = co_await b.connect(1);
    CO_ASSERT_TRUE(new_gw);
    auto new_bus = new_gw.value()->bus(1);
    CO_ASSERT_TRUE(new_bus);
    // The old connection was closed by the gateway: its bus reports closed, sends fail.
    auto r = co_await old_bus.value()->receive(5s);
    EXPECT_EQ(r.error(), CanErrc::closed);
    EXPECT_FALSE(old_gw.value()->is_connected());
    EXPECT_EQ((co_await old_bus.value()->send(F("111#02"))).error(), CanErrc::io);
    EXPECT_EQ((co_await old_gw.value()->status(1)).error(), CanErrc::io);
    // The new one works.
    CO_ASSERT_TRUE((co_await b.can0->send(F("222#02"))).has_value());
    auto f = co_await new_bus.value()->receive(5s);
    CO_ASSERT_TRUE(f);
    EXPECT_EQ(f.value().to_string(), "222#02");
    EXPECT_EQ(b.emulator->stats().replaced, 1u);
    // The old client is told why, as far as it can know: the gateway closed the connection, which
    // a CAN@net gateway does when another client takes it over.
    EXPECT_NE(old_gw.value()->disconnect_reason().detail.find("another client"), std::string::npos)
        << old_gw.value()->disconnect_reason().detail;
    new_gw.value()->close();
  });
}

TEST(CanNetClient, BusesOnOneGatewayOpenedTogetherShareOneConnection) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    const auto ep = b.emulator->local_endpoint().to_string();
    std::vector<BusSpec> specs{parse_bus_spec(fmt::format("cannet://{}/1", ep)).value(),
                               parse_bus_spec(fmt::format("cannet://{}/2", ep)).value()};
    auto opened = co_await open_buses(b.io.get_executor(), specs);
    CO_ASSERT_TRUE(opened);
    auto& buses = opened.value();
    CO_ASSERT_TRUE(buses.size() == 2u);
    EXPECT_EQ(b.emulator->stats().connections, 1u);
    EXPECT_EQ(b.emulator->stats().replaced, 0u);
    // Both buses work, each on its own channel.
    CO_ASSERT_TRUE((co_await buses[0]->send(F("101#01"))).has_value());
    CO_ASSERT_TRUE((co_await buses[1]->send(F("102#02"))).has_value());
    auto on0 = co_await b.can0->receive(5s);
    auto on1 = co_await b.can1->receive(5s);
    CO_ASSERT_TRUE(on0 && on1);
    EXPECT_EQ(on0.value().to_string(), "101#01");
    EXPECT_EQ(on1.value().to_string(), "102#02");
    CO_ASSERT_TRUE((co_await b.can0->send(F("201#AA"))).has_value());
    auto back = co_await buses[0]->receive(5s);
    CO_ASSERT_TRUE(back);
    EXPECT_EQ(back.value().to_string(), "201#AA");
    for (auto& bus : buses) bus->close();

    // The same bus twice is refused before anything connects.
    std::vector<BusSpec> twice{specs[0], specs[0]};
    auto refused = co_await open_buses(b.io.get_executor(), twice);
    CO_ASSERT_TRUE(!refused);
    EXPECT_EQ(refused.error(), CanErrc::bad_spec);
    EXPECT_EQ(b.emulator->stats().connections, 1u);
  });
}

// Two names of one gateway are one gateway: a second connection would take it over.
TEST(CanNetClient, TwoNamesOfOneGatewayShareOneConnection) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    const auto port = b.emulator->local_endpoint().port;
    std::vector<BusSpec> specs{parse_bus_spec(fmt::format("cannet://localhost:{}/1", port)).value(),
                               parse_bus_spec(fmt::format("cannet://127.0.0.1:{}/2", port)).value()};
    auto opened = co_await open_buses(b.io.get_executor(), specs);
    CO_ASSERT_TRUE(opened);
    EXPECT_EQ(opened.value().size(), 2u);
    EXPECT_EQ(b.emulator->stats().connections, 1u);
    EXPECT_EQ(b.emulator->stats().replaced, 0u);
    for (auto& bus : opened.value()) bus->close();
    // And one bus under two names is the same bus listed twice.
    std::vector<BusSpec> twice{specs[0], parse_bus_spec(fmt::format("cannet://127.0.0.1:{}/1", port)).value()};
    auto refused = co_await open_buses(b.io.get_executor(), twice);
    CO_ASSERT_TRUE(!refused);
    EXPECT_EQ(refused.error(), CanErrc::bad_spec);
  });
}

TEST(CanNetClient, ConnectionLossClosesBusesAfterQueuedFrames) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    auto gw = co_await b.connect(1);
    CO_ASSERT_TRUE(gw);
    auto bus = gw.value()->bus(1);
    CO_ASSERT_TRUE(bus);
    CO_ASSERT_TRUE((co_await b.can0->send(F("123#01"))).has_value());
    (void)co_await gw.value()->status(1);  // the frame is queued on the bus now
    b.emulator->stop();
    auto first = co_await bus.value()->receive(5s);
    CO_ASSERT_TRUE(first);  // what arrived before the loss is still there
    EXPECT_EQ(first.value().to_string(), "123#01");
    auto next = co_await bus.value()->receive(5s);
    EXPECT_EQ(next.error(), CanErrc::closed);
    EXPECT_FALSE(gw.value()->is_connected());
    EXPECT_EQ((co_await bus.value()->send(F("123#02"))).error(), CanErrc::io);
  });
}

TEST(CanNetClient, ClosingTheGatewayClosesItsBuses) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    auto gw = co_await b.connect(1, 2);
    CO_ASSERT_TRUE(gw);
    auto bus = gw.value()->bus(2);
    CO_ASSERT_TRUE(bus);
    gw.value()->close();
    EXPECT_FALSE(gw.value()->is_connected());
    EXPECT_FALSE(bus.value()->is_open());
    EXPECT_EQ((co_await bus.value()->send(F("123#01"))).error(), CanErrc::closed);
    EXPECT_EQ((co_await bus.value()->receive(5s)).error(), CanErrc::closed);
    EXPECT_EQ((co_await gw.value()->status(1)).error(), CanErrc::closed);
    EXPECT_EQ(gw.value()->bus(1).error(), CanErrc::closed);
  });
}

TEST(CanNetClient, RefusedInitIsADeviceError) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    CanNetOptions o;
    o.bitrate_kbit = 333;
    auto gw = co_await b.connect_with(o, 1);
    CO_ASSERT_TRUE(!gw);
    EXPECT_EQ(gw.error(), CanErrc::device_error);
    EXPECT_NE(gw.error().detail.find("CAN 1 INIT STD 333"), std::string::npos) << gw.error().detail;
    EXPECT_NE(gw.error().detail.find("invalid baudrate"), std::string::npos) << gw.error().detail;
  });
}

TEST(CanNetClient, ChannelWithoutABusIsADeviceError) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    auto gw = co_await b.connect(1, 4);
    CO_ASSERT_TRUE(!gw);
    EXPECT_EQ(gw.error(), CanErrc::device_error);
    EXPECT_NE(gw.error().detail.find("port 4 not available"), std::string::npos) << gw.error().detail;
  });
}

TEST(CanNetClient, RejectsBadArguments) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    EXPECT_EQ((co_await b.connect()).error(), CanErrc::bad_spec);
    EXPECT_EQ((co_await b.connect(5)).error(), CanErrc::bad_spec);
    EXPECT_EQ((co_await b.connect(1, 1)).error(), CanErrc::bad_spec);
    CanNetOptions o;
    o.bitrate_kbit = 0;
    EXPECT_EQ((co_await b.connect_with(o, 1)).error(), CanErrc::bad_spec);
    EXPECT_EQ(b.emulator->stats().connections, 0u);  // nothing reached the gateway
  });
}

TEST(CanNetClient, ConnectFailsWhenNobodyListens) {
  asio::io_context io;
  // A port that was free a moment ago and has no listener now.
  tcp::acceptor probe(io, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
  const std::uint16_t port = probe.local_endpoint().port();
  probe.close();
  run(io, [&]() -> asio::awaitable<void> {
    // (A named endpoint: gcc 12 corrupts aggregate temporaries built inside a co_await expression.)
    const net::Endpoint ep{"127.0.0.1", port};
    auto gw = co_await CanNetGateway::connect(io.get_executor(), ep, std::vector<int>(1, 1));
    CO_ASSERT_TRUE(!gw);
    EXPECT_EQ(gw.error(), CanErrc::connect_failed);
  });
}

TEST(CanNetClient, SilentGatewayTimesOut) {
  asio::io_context io;
  // Accepts connections and never answers.
  tcp::acceptor silent(io, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
  tcp::socket accepted(io);
  silent.async_accept(accepted, [](const boost::system::error_code&) {});
  run(io, [&]() -> asio::awaitable<void> {
    CanNetOptions o;
    o.reply_timeout = 200ms;
    const net::Endpoint ep{"127.0.0.1", silent.local_endpoint().port()};
    auto gw = co_await CanNetGateway::connect(io.get_executor(), ep, std::vector<int>(1, 1), o);
    CO_ASSERT_TRUE(!gw);
    EXPECT_EQ(gw.error(), CanErrc::timeout);
    EXPECT_NE(gw.error().detail.find("CAN 1 STOP"), std::string::npos) << gw.error().detail;
  });
}

TEST(CanNetClient, CommandsFromSeveralCoroutinesGetTheirOwnReplies) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    auto gw = co_await b.connect(1, 2);
    CO_ASSERT_TRUE(gw);
    auto g = gw.value();
    int finished = 0;
    std::string id, ver;
    std::uint32_t free1 = 0, free2 = 0;
    asio::co_spawn(b.io, [&]() -> asio::awaitable<void> { id = (co_await g->identify()).value(); ++finished; }, asio::detached);
    asio::co_spawn(b.io, [&]() -> asio::awaitable<void> { free1 = (co_await g->status(1)).value().free_tx; ++finished; }, asio::detached);
    asio::co_spawn(b.io, [&]() -> asio::awaitable<void> { ver = (co_await g->version()).value(); ++finished; }, asio::detached);
    asio::co_spawn(b.io, [&]() -> asio::awaitable<void> { free2 = (co_await g->status(2)).value().free_tx; ++finished; }, asio::detached);
    // A command of our own, queued behind them (let them start first).
    co_await asio::post(b.io, asio::use_awaitable);
    auto raw = co_await g->command(cannet::DevIdentify{});
    CO_ASSERT_TRUE(raw);
    EXPECT_EQ(raw.value(), cannet::Line(cannet::ReplyText{"CAN@net NT 420"}));
    EXPECT_EQ(finished, 4);
    EXPECT_EQ(id, "CAN@net NT 420");
    EXPECT_EQ(ver, "V1.5.0");
    EXPECT_EQ(free1, 100u);
    EXPECT_EQ(free2, 100u);
    EXPECT_EQ((co_await g->command(cannet::ReplyOk{})).error(), CanErrc::bad_spec);  // not a host command
    g->close();
  });
}

// The gateway's transmit FIFO holds 100 frames per channel. A host that sends many more at once
// than the bus can carry loses the excess; the emulator reports each loss, so nothing vanishes
// unaccounted: every frame sent is either delivered on the bus or reported dropped.
TEST(CanNetClient, TransmitFifoOverflowIsReportedNotSilent) {
  WireModel paced;
  paced.enabled = true;
  paced.pace_realtime = true;
  paced.bitrate = 125'000;  // about 1 ms per frame: 1000 frames at once far outrun the wire
  ClientBench b(paced);
  run(b.io, [&]() -> asio::awaitable<void> {
    CanNetOptions o;
    o.bitrate_kbit = 125;
    auto gw = co_await b.connect_with(o, 1);
    CO_ASSERT_TRUE(gw);
    auto bus = gw.value()->bus(1);
    CO_ASSERT_TRUE(bus);
    auto& ch1 = *bus.value();
    constexpr std::uint64_t kSent = 1000;
    for (std::uint64_t i = 0; i < kSent; ++i) {
      const std::uint8_t bytes[2] = {static_cast<std::uint8_t>(i >> 8), static_cast<std::uint8_t>(i)};
      CO_ASSERT_TRUE((co_await ch1.send(Frame::standard(0x100, bytes).value())).has_value());
    }
    EXPECT_EQ(ch1.stats().frames_out, kSent);
    // Collect until everything is accounted for (or give up after a generous while).
    std::uint64_t delivered = 0;
    std::uint16_t last = 0;
    bool in_order = true;
    const auto give_up = std::chrono::steady_clock::now() + 20s;
    while (delivered + ch1.stats().tx_dropped < kSent && std::chrono::steady_clock::now() < give_up) {
      auto f = co_await b.can0->receive(100ms);
      if (!f) continue;
      const auto p = f.value().payload();
      const auto n = static_cast<std::uint16_t>(p[0] << 8 | p[1]);
      if (delivered > 0 && n <= last) in_order = false;
      last = n;
      ++delivered;
    }
    EXPECT_EQ(delivered + ch1.stats().tx_dropped, kSent);
    EXPECT_GE(delivered, 100u);  // at least what the FIFO holds
    EXPECT_GT(ch1.stats().tx_dropped, 0u);
    EXPECT_TRUE(in_order);
    EXPECT_EQ(b.emulator->stats().tx_overflow_drops, ch1.stats().tx_dropped);
    EXPECT_EQ(b.emulator->stats().frames_to_bus, delivered);
    // Drained now: the whole FIFO is free again.
    auto st = co_await gw.value()->status(1);
    CO_ASSERT_TRUE(st);
    EXPECT_EQ(st.value().free_tx, 100u);
    gw.value()->close();
  });
}

TEST(CanNetClient, FifoOverflowCanBeSilentLikeTheDevice) {
  WireModel paced;
  paced.enabled = true;
  paced.pace_realtime = true;
  paced.bitrate = 125'000;
  CanNetEmulatorOptions eo;
  eo.report_tx_overflow = false;
  ClientBench b(paced, eo);
  run(b.io, [&]() -> asio::awaitable<void> {
    CanNetOptions o;
    o.bitrate_kbit = 125;
    auto gw = co_await b.connect_with(o, 1);
    CO_ASSERT_TRUE(gw);
    auto bus = gw.value()->bus(1);
    CO_ASSERT_TRUE(bus);
    for (int i = 0; i < 400; ++i) CO_ASSERT_TRUE((co_await bus.value()->send(F("100#01"))).has_value());
    // While the wire drains, the status shows the FIFO in use.
    auto st = co_await gw.value()->status(1);
    CO_ASSERT_TRUE(st);
    EXPECT_TRUE(st.value().flags.tx_pending);
    EXPECT_LT(st.value().free_tx, 100u);
    EXPECT_EQ(bus.value()->stats().tx_dropped, 0u);  // nobody told the host
    gw.value()->close();
  });
  EXPECT_GT(b.emulator->stats().tx_overflow_drops, 0u);
}

// Frames leave in the order send() was called, also when more than the client's output buffer
// (64 kB) is queued and senders have to wait for the socket: a sender that comes along while
// others wait queues behind them instead of slipping in while the writer makes room. Several
// coroutines send at once, each numbering its frame at the call; the bus must see the numbers in
// ascending order, none missing.
TEST(CanNetClient, FramesKeepTheirOrderWhenTheOutputBufferIsFull) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    auto gw = co_await b.connect(1);
    CO_ASSERT_TRUE(gw);
    auto bus = gw.value()->bus(1);
    CO_ASSERT_TRUE(bus);
    auto& ch1 = *bus.value();
    constexpr std::uint32_t kFrames = 12000;  // about 430 kB of lines: the buffer fills many times
    constexpr int kSenders = 6;
    std::uint32_t next = 0;
    int finished = 0;
    bool send_failed = false;
    auto ex = co_await asio::this_coro::executor;
    for (int s = 0; s < kSenders; ++s) {
      asio::co_spawn(ex, [&, s]() -> asio::awaitable<void> {
        for (int i = 0; next < kFrames; ++i) {
          const std::uint32_t n = next++;
          const std::uint8_t bytes[8] = {static_cast<std::uint8_t>(n >> 24), static_cast<std::uint8_t>(n >> 16),
                                         static_cast<std::uint8_t>(n >> 8),  static_cast<std::uint8_t>(n),
                                         0xAA, 0x55, static_cast<std::uint8_t>(s), 0};
          auto sent = co_await ch1.send(Frame::standard(0x123, bytes).value());
          if (!sent) send_failed = true;
          // The first sender runs on until the buffer is full; the others yield after every frame,
          // so they come back while the writer is busy and the first one waits for room.
          if (s > 0) co_await asio::post(ex, asio::use_awaitable);
        }
        ++finished;
      }, asio::detached);
    }
    std::uint32_t received = 0, out_of_order = 0, expected = 0;
    const auto give_up = std::chrono::steady_clock::now() + 20s;
    while (received < kFrames && std::chrono::steady_clock::now() < give_up) {
      auto f = co_await b.can0->receive(100ms);
      if (!f) continue;
      const auto p = f.value().payload();
      const std::uint32_t n = std::uint32_t{p[0]} << 24 | std::uint32_t{p[1]} << 16 | std::uint32_t{p[2]} << 8 | p[3];
      if (n != expected) ++out_of_order;
      expected = n + 1;
      ++received;
    }
    EXPECT_FALSE(send_failed);
    EXPECT_EQ(finished, kSenders);
    EXPECT_EQ(received, kFrames);
    EXPECT_EQ(out_of_order, 0u);
    EXPECT_EQ(ch1.stats().frames_out, kFrames);
    gw.value()->close();
  });
}

// A reconnectable gateway (what fps::host::FocalPlaneArray opens) whose power is cut: its buses
// stay open while it is away, and carry frames again once reconnect() found it back, on the same
// port with every channel set up anew.
TEST(CanNetClient, ReconnectableBusesSurviveAPowerCycleOfTheGateway) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    CanNetOptions o;
    o.reconnectable = true;
    auto gw = co_await b.connect_with(o, 1, 2);
    CO_ASSERT_TRUE(gw);
    auto bus = gw.value()->bus(2);
    CO_ASSERT_TRUE(bus);
    const net::Endpoint where = b.emulator->local_endpoint();
    b.emulator->power_off();
    // The host sees a failure, not the orderly close of a takeover; the bus is open, silent.
    auto silent = co_await bus.value()->receive(300ms);
    EXPECT_EQ(silent.error(), CanErrc::timeout);
    EXPECT_FALSE(gw.value()->is_connected());
    EXPECT_EQ(gw.value()->disconnect_kind(), DisconnectKind::failed);
    EXPECT_TRUE(bus.value()->is_open());
    EXPECT_EQ((co_await bus.value()->send(F("123#01"))).error(), CanErrc::io);
    // Away: a reconnection fails and changes nothing.
    auto early = co_await gw.value()->reconnect(500ms);
    EXPECT_EQ(early.error(), CanErrc::connect_failed);
    EXPECT_TRUE(bus.value()->is_open());

    CanNetEmulatorOptions back;
    back.port = where.port;
    CanNetGatewayEmulator again(b.io.get_executor(), b.registry, std::vector<std::string>{"can0", "can1"}, back);
    CO_ASSERT_TRUE(again.start());
    auto r = co_await gw.value()->reconnect();
    CO_ASSERT_TRUE(r);
    EXPECT_TRUE(gw.value()->is_connected());
    EXPECT_EQ(gw.value()->stats().reconnections, 1u);
    EXPECT_FALSE(again.status(1).flags.stopped || again.status(2).flags.stopped);
    CO_ASSERT_TRUE((co_await bus.value()->send(F("123#02"))).has_value());
    auto out = co_await b.can1->receive(5s);
    CO_ASSERT_TRUE(out);
    EXPECT_EQ(out.value().to_string(), "123#02");
    CO_ASSERT_TRUE((co_await b.can1->send(F("321#03"))).has_value());
    auto in = co_await bus.value()->receive(5s);
    CO_ASSERT_TRUE(in);
    EXPECT_EQ(in.value().to_string(), "321#03");
    gw.value()->close();
    EXPECT_FALSE(bus.value()->is_open());
    EXPECT_EQ((co_await gw.value()->reconnect()).error(), CanErrc::closed);
  });
}

// Another client takes a reconnectable gateway over: the loss says so (an orderly close by the
// gateway), the buses wait, and reconnect() takes the gateway back.
TEST(CanNetClient, ATakenOverGatewayIsTakenBackOnlyByReconnect) {
  ClientBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    CanNetOptions o;
    o.reconnectable = true;
    auto gw = co_await b.connect_with(o, 1);
    CO_ASSERT_TRUE(gw);
    auto bus = gw.value()->bus(1);
    CO_ASSERT_TRUE(bus);
    auto other = co_await b.connect(1);
    CO_ASSERT_TRUE(other);
    EXPECT_EQ((co_await bus.value()->receive(300ms)).error(), CanErrc::timeout);
    EXPECT_EQ(gw.value()->disconnect_kind(), DisconnectKind::by_gateway);
    EXPECT_TRUE(other.value()->is_connected());
    CO_ASSERT_TRUE(co_await gw.value()->reconnect());
    CO_ASSERT_TRUE((co_await b.can0->send(F("0AB#01"))).has_value());
    auto in = co_await bus.value()->receive(5s);
    CO_ASSERT_TRUE(in);
    EXPECT_EQ(in.value().to_string(), "0AB#01");
    EXPECT_EQ(b.emulator->stats().replaced, 2u);
    gw.value()->close();
  });
}

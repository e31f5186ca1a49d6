// The CAN@net gateway emulator seen from the wire: the exact lines it answers to a bare TCP
// client, and what it forwards between that client and a virtual bus.
#include "axon/can/cannet_server.hpp"
#include "axon/can/virtual_bus.hpp"

#include "can/cannet_harness.hpp"
#include "frame_text.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <memory>
#include <string>

using namespace axon;
using namespace axon::can;
using namespace axon::can::test;

namespace {

using axon::can::test::F;

// Two virtual buses behind an emulator listening on an ephemeral loopback port, plus an observer
// node on each bus.
struct EmulatorBench {
  asio::io_context io;
  VirtualBusRegistry registry{io.get_executor()};
  std::unique_ptr<CanNetGatewayEmulator> emulator;
  std::unique_ptr<Bus> can0, can1;  // observers on the two buses

  explicit EmulatorBench(CanNetEmulatorOptions options = {}) {
    (void)registry.add("can0").value();
    (void)registry.add("can1").value();
    options.port = 0;
    emulator = std::make_unique<CanNetGatewayEmulator>(io.get_executor(), registry,
                                                       std::vector<std::string>{"can0", "can1"}, options);
    auto started = emulator->start();
    EXPECT_TRUE(started) << started.error().message();
    can0 = registry.open("can0").value();
    can1 = registry.open("can1").value();
  }
};

// Sends the field set-up sequence for `channel`; true when every line was answered "R ok".
asio::awaitable<bool> set_up(LineClient& c, int channel) {
  bool all_ok = true;
  for (const char* cmd : {"STOP", "INIT STD 1000", "FILTER CLEAR", "FILTER ADD EXT 00000000 00000000", "START"}) {
    const std::string reply = co_await c.ask(fmt::format("CAN {} {}", channel, cmd));
    EXPECT_EQ(reply, "R ok") << "CAN " << channel << " " << cmd;
    all_ok = all_ok && reply == "R ok";
  }
  co_return all_ok;
}

}  // namespace

TEST(CanNetEmulator, AnswersIdentifyVersionAndStatus) {
  EmulatorBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    LineClient c(b.io.get_executor());
    CO_ASSERT_TRUE(co_await c.connect(b.emulator->local_endpoint()));
    EXPECT_EQ(co_await c.ask("DEV IDENTIFY"), "R CAN@net NT 420");
    EXPECT_EQ(co_await c.ask("DEV VERSION"), "R V1.5.0");
    // Not initialised yet: stopped (I), all 100 transmit buffers free.
    EXPECT_EQ(co_await c.ask("CAN 1 STATUS"), "R CAN 1 ----I 100");
    CO_ASSERT_TRUE(co_await set_up(c, 1));
    EXPECT_EQ(co_await c.ask("CAN 1 STATUS"), "R CAN 1 ----- 100");
    EXPECT_EQ(co_await c.ask("CAN 1 STOP"), "R ok");
    EXPECT_EQ(co_await c.ask("CAN 1 STATUS"), "R CAN 1 ----I 100");
  });
}

TEST(CanNetEmulator, OwnTextsFromOptions) {
  CanNetEmulatorOptions o;
  o.identify = "CAN@net NT 420 (axon)";
  o.version = "V9.9.9";
  EmulatorBench b(o);
  run(b.io, [&]() -> asio::awaitable<void> {
    LineClient c(b.io.get_executor());
    CO_ASSERT_TRUE(co_await c.connect(b.emulator->local_endpoint()));
    EXPECT_EQ(co_await c.ask("DEV IDENTIFY"), "R CAN@net NT 420 (axon)");
    EXPECT_EQ(co_await c.ask("DEV VERSION"), "R V9.9.9");
  });
}

TEST(CanNetEmulator, RefusesBadCommandsAndKeepsTheConnection) {
  EmulatorBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    LineClient c(b.io.get_executor());
    CO_ASSERT_TRUE(co_await c.connect(b.emulator->local_endpoint()));
    EXPECT_EQ(co_await c.ask("CAN 1 INIT STD 333"), "R ERR 1 invalid baudrate");
    EXPECT_EQ(co_await c.ask("CAN 3 STOP"), "R ERR 2 port 3 not available");  // nothing behind port 3
    EXPECT_EQ(co_await c.ask("CAN 1 START"), "R ERR 5 port not initialized");
    const std::string syntax = co_await c.ask("CAN 1 FILTER ADD EXT 00000000");
    EXPECT_EQ(syntax.rfind("R ERR 3 ", 0), 0u) << syntax;
    EXPECT_NE(syntax.find("too few fields"), std::string::npos) << syntax;
    EXPECT_EQ((co_await c.ask("HELLO")).rfind("R ERR 3 ", 0), 0u);
    EXPECT_EQ((co_await c.ask("R ok")).rfind("R ERR 4 ", 0), 0u);
    EXPECT_EQ((co_await c.ask(std::string(1000, 'x'))).rfind("R ERR 3 line longer than", 0), 0u);
    // Still there, and every refusal was an R ERR.
    EXPECT_EQ(co_await c.ask("DEV IDENTIFY"), "R CAN@net NT 420");
    EXPECT_EQ(b.emulator->stats().error_replies, 7u);
    EXPECT_EQ(b.emulator->stats().connections, 1u);
  });
}

TEST(CanNetEmulator, BlankLinesAreIgnored) {
  EmulatorBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    LineClient c(b.io.get_executor());
    CO_ASSERT_TRUE(co_await c.connect(b.emulator->local_endpoint()));
    CO_ASSERT_TRUE(co_await c.send(""));
    CO_ASSERT_TRUE(co_await c.send("\r"));
    EXPECT_EQ(co_await c.ask("DEV VERSION"), "R V1.5.0");  // the first answer is to DEV VERSION
  });
}

TEST(CanNetEmulator, AcceptsCrLfLineEndings) {
  EmulatorBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    LineClient c(b.io.get_executor());
    CO_ASSERT_TRUE(co_await c.connect(b.emulator->local_endpoint()));
    EXPECT_EQ(co_await c.ask("DEV IDENTIFY\r"), "R CAN@net NT 420");
  });
}

TEST(CanNetEmulator, ForwardsFramesOnlyOnStartedChannels) {
  EmulatorBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    LineClient c(b.io.get_executor());
    CO_ASSERT_TRUE(co_await c.connect(b.emulator->local_endpoint()));
    // Before set-up nothing passes either way.
    CO_ASSERT_TRUE(co_await c.send("M 1 CSD 111 01"));
    CO_ASSERT_TRUE((co_await b.can0->send(F("222#02"))).has_value());
    CO_ASSERT_TRUE(co_await set_up(c, 1));
    EXPECT_EQ(b.emulator->stats().not_running_drops, 1u);

    CO_ASSERT_TRUE((co_await b.can0->send(F("12345678#DEADBEEF"))).has_value());
    CO_ASSERT_TRUE((co_await b.can0->send(F("7FF#R3"))).has_value());
    // The frame sent before START never shows up: the first line is the one after it.
    EXPECT_EQ(co_await c.read_line(), std::optional<std::string>("M 1 CED 12345678 DE AD BE EF"));
    EXPECT_EQ(co_await c.read_line(), std::optional<std::string>("M 1 CSR 7FF dlc=3"));

    CO_ASSERT_TRUE(co_await c.send("M 1 CED 0123ABCD 01 02 03 04 05 06 07 08"));
    CO_ASSERT_TRUE(co_await c.send("M 1 CSR 123 dlc=2"));
    auto f1 = co_await b.can0->receive(5s);
    auto f2 = co_await b.can0->receive(5s);
    CO_ASSERT_TRUE(f1 && f2);
    EXPECT_EQ(f1.value().to_string(), "0123ABCD#0102030405060708");
    EXPECT_EQ(f2.value().to_string(), "123#R2");
    // Channel 2 was never started: the other bus saw nothing from channel 1.
    EXPECT_EQ(b.can1->pending(), 0u);
    EXPECT_EQ(b.emulator->stats().frames_to_bus, 2u);
    EXPECT_EQ(b.emulator->stats().frames_to_client, 2u);
  });
}

TEST(CanNetEmulator, FiltersKeepTheirIdFormat) {
  EmulatorBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    LineClient c(b.io.get_executor());
    CO_ASSERT_TRUE(co_await c.connect(b.emulator->local_endpoint()));
    for (const char* cmd : {"CAN 1 INIT STD 1000", "CAN 1 FILTER CLEAR", "CAN 1 FILTER ADD EXT 00000100 1FFFFF00", "CAN 1 START"})
      EXPECT_EQ(co_await c.ask(cmd), "R ok") << cmd;
    CO_ASSERT_TRUE((co_await b.can0->send(F("00000223#01"))).has_value());  // extended, no entry matches
    CO_ASSERT_TRUE((co_await b.can0->send(F("00000123#02"))).has_value());  // extended, matches
    CO_ASSERT_TRUE((co_await b.can0->send(F("223#03"))).has_value());       // standard: no STD entries
    EXPECT_EQ(co_await c.read_line(), std::optional<std::string>("M 1 CED 00000123 02"));
    EXPECT_EQ(co_await c.read_line(), std::optional<std::string>("M 1 CSD 223 03"));
    EXPECT_EQ(b.emulator->stats().filtered, 1u);
  });
}

TEST(CanNetEmulator, NewConnectionReplacesTheOldOneAndResetsState) {
  EmulatorBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    LineClient first(b.io.get_executor());
    CO_ASSERT_TRUE(co_await first.connect(b.emulator->local_endpoint()));
    CO_ASSERT_TRUE(co_await set_up(first, 1));
    LineClient second(b.io.get_executor());
    CO_ASSERT_TRUE(co_await second.connect(b.emulator->local_endpoint()));
    // The first connection is closed by the emulator.
    EXPECT_EQ(co_await first.read_line(), std::nullopt);
    EXPECT_TRUE(first.closed());
    // The second one starts from scratch: channel 1 is stopped again.
    EXPECT_EQ(co_await second.ask("CAN 1 STATUS"), "R CAN 1 ----I 100");
    EXPECT_EQ(b.emulator->stats().connections, 2u);
    EXPECT_EQ(b.emulator->stats().replaced, 1u);
    EXPECT_TRUE(b.emulator->has_client());
  });
}

// Collects what is logged while it lives (on the default logger).
struct LogCapture {
  std::shared_ptr<spdlog::sinks::ringbuffer_sink_mt> sink = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(64);
  LogCapture() { spdlog::default_logger()->sinks().push_back(sink); }
  ~LogCapture() {
    auto& sinks = spdlog::default_logger()->sinks();
    sinks.erase(std::remove(sinks.begin(), sinks.end(), sink), sinks.end());
  }
  [[nodiscard]] std::vector<std::string> warnings() const {
    std::vector<std::string> out;
    for (const auto& m : sink->last_raw()) {
      if (m.level == spdlog::level::warn) out.emplace_back(m.payload.data(), m.payload.size());
    }
    return out;
  }
};

TEST(CanNetEmulator, TakeoverIsLoggedNamingBothClientsAndTheOldOneSeesItsConnectionEnd) {
  LogCapture log;
  EmulatorBench b;
  std::string first_peer, second_peer;
  run(b.io, [&]() -> asio::awaitable<void> {
    LineClient first(b.io.get_executor());
    CO_ASSERT_TRUE(co_await first.connect(b.emulator->local_endpoint()));
    CO_ASSERT_TRUE(co_await set_up(first, 1));
    LineClient second(b.io.get_executor());
    CO_ASSERT_TRUE(co_await second.connect(b.emulator->local_endpoint()));
    first_peer = first.local();
    second_peer = second.local();
    // The device's protocol has no line for "taken over": the old client reads the end of its stream.
    EXPECT_EQ(co_await first.read_line(), std::nullopt);
    EXPECT_TRUE(first.closed());
    EXPECT_EQ(co_await second.ask("CAN 1 STATUS"), "R CAN 1 ----I 100");
  });
  const auto warnings = log.warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("client " + second_peer + " takes over from client " + first_peer), std::string::npos)
      << warnings[0];
  EXPECT_NE(warnings[0].find(b.emulator->local_endpoint().to_string()), std::string::npos) << warnings[0];
}

TEST(CanNetEmulator, FaultHooksSendEventsAndHoldTheChannel) {
  EmulatorBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    LineClient c(b.io.get_executor());
    CO_ASSERT_TRUE(co_await c.connect(b.emulator->local_endpoint()));
    CO_ASSERT_TRUE(co_await set_up(c, 2));
    b.emulator->inject_error_warning(2, true);
    EXPECT_EQ(co_await c.read_line(), std::optional<std::string>("E 2 ERRORWARNING SET"));
    b.emulator->inject_error_warning(2, false);
    EXPECT_EQ(co_await c.read_line(), std::optional<std::string>("E 2 ERRORWARNING RESET"));
    b.emulator->inject_bus_off(2);
    EXPECT_EQ(co_await c.read_line(), std::optional<std::string>("E 2 BUSOFF SET"));
    // Bus-off: nothing crosses in either direction.
    CO_ASSERT_TRUE(co_await c.send("M 2 CSD 100 01"));
    CO_ASSERT_TRUE((co_await b.can1->send(F("200#02"))).has_value());
    // (The round trip lets the emulator take the bus frame before the restart below.)
    EXPECT_EQ(co_await c.ask("CAN 2 STATUS"), "R CAN 2 B---- 100");
    EXPECT_EQ(b.emulator->stats().bus_frames_discarded, 1u);
    // Restart: frames flow again; the ones sent during bus-off are gone.
    EXPECT_EQ(co_await c.ask("CAN 2 START"), "R ok");
    EXPECT_EQ(co_await c.ask("CAN 2 STATUS"), "R CAN 2 ----- 100");
    CO_ASSERT_TRUE((co_await b.can1->send(F("300#03"))).has_value());
    EXPECT_EQ(co_await c.read_line(), std::optional<std::string>("M 2 CSD 300 03"));
    EXPECT_EQ(b.emulator->stats().not_running_drops, 1u);
    EXPECT_EQ(b.can1->pending(), 0u);
  });
}

TEST(CanNetEmulator, SendsRawLinesForFaultTests) {
  EmulatorBench b;
  run(b.io, [&]() -> asio::awaitable<void> {
    LineClient c(b.io.get_executor());
    CO_ASSERT_TRUE(co_await c.connect(b.emulator->local_endpoint()));
    EXPECT_EQ(co_await c.ask("DEV VERSION"), "R V1.5.0");  // connected and served
    b.emulator->send_raw("M 9 garbage");
    EXPECT_EQ(co_await c.read_line(), std::optional<std::string>("M 9 garbage"));
  });
}

TEST(CanNetEmulator, RejectsBadConfiguration) {
  asio::io_context io;
  VirtualBusRegistry registry(io.get_executor());
  (void)registry.add("can0").value();
  CanNetGatewayEmulator unknown(io.get_executor(), registry, {"can0", "nope"}, CanNetEmulatorOptions{.port = 0});
  auto r = unknown.start();
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), CanErrc::bad_spec);
  CanNetEmulatorOptions big;
  big.port = 0;
  big.tx_fifo = 101;
  CanNetGatewayEmulator fifo(io.get_executor(), registry, {"can0"}, big);
  EXPECT_EQ(fifo.start().error(), CanErrc::bad_spec);
  EXPECT_THROW((CanNetGatewayEmulator(io.get_executor(), registry, {"a", "b", "c", "d", "e"})), Exception);
}

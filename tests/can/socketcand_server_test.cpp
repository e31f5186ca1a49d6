// The socketcand server as a client sees it on the wire: exact text, modes, errors, several clients.
#include "axon/can/socketcand_server.hpp"

#include "axon/can/socketcand_codec.hpp"
#include "axon/can/virtual_bus.hpp"
#include "socketcand_test_util.hpp"
#include "frame_text.hpp"

#include <gtest/gtest.h>

#include <fmt/format.h>

#include <memory>
#include <regex>

namespace axon::can {
namespace {

using namespace std::chrono_literals;
using testing::TextPeer;
namespace sc = socketcand;

using axon::can::test::F;

// The frame a `< frame ... >` / `< rtr ... >` message carries (fails the test if it is not one).
Frame frame_of(const std::string& text) {
  auto m = sc::parse(text);
  EXPECT_TRUE(m) << text;
  if (!m) return Frame{};
  const auto* f = std::get_if<sc::FrameMessage>(&m.value());
  EXPECT_NE(f, nullptr) << text;
  return f ? f->frame : Frame{};
}

class SocketcandServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    vcan0_ = registry_.add("vcan0").value();
    registry_.add("vcan1").value();
    start_server({});
  }

  void start_server(SocketcandServerOptions options) {
    server_.reset();
    server_ = std::make_unique<SocketcandServer>(io_.get_executor(), registry_, net::Endpoint{"127.0.0.1", 0}, options);
  }

  void run(std::function<asio::awaitable<void>()> body) {
    testing::run_test(io_, std::move(body), [this] { server_->stop(); });
  }

  std::uint16_t port() const { return server_->local_endpoint().port; }

  // Connects, checks the greeting, opens `channel` and (optionally) enters raw mode.
  asio::awaitable<TextPeer> raw_client(const char* channel = "vcan0", bool raw = true) {
    auto peer = co_await TextPeer::connect(io_.get_executor(), port());
    EXPECT_EQ(co_await peer.next(), "< hi >");
    co_await peer.write(fmt::format("< open {} >", channel));
    EXPECT_EQ(co_await peer.next(), "< ok >");
    if (raw) {
      co_await peer.write("< rawmode >");
      EXPECT_EQ(co_await peer.next(), "< ok >");
    }
    co_return peer;
  }

  asio::io_context io_;
  VirtualBusRegistry registry_{io_.get_executor()};
  std::shared_ptr<VirtualBus> vcan0_;
  std::unique_ptr<SocketcandServer> server_;
};

TEST_F(SocketcandServerTest, ListensOnAnEphemeralPort) {
  EXPECT_EQ(server_->local_endpoint().host, "127.0.0.1");
  EXPECT_NE(server_->local_endpoint().port, 0);
}

TEST_F(SocketcandServerTest, AddressThatCannotBeBoundIsAnError) {
  auto taken = SocketcandServer::create(io_.get_executor(), registry_, server_->local_endpoint());
  ASSERT_FALSE(taken);
  EXPECT_EQ(taken.error(), CanErrc::io);
  EXPECT_NE(taken.error().detail.find("binding"), std::string::npos) << taken.error().detail;
  auto unknown = SocketcandServer::create(io_.get_executor(), registry_, net::Endpoint{"no-such-host.invalid", 0});
  ASSERT_FALSE(unknown);
  EXPECT_EQ(unknown.error(), CanErrc::io);
  EXPECT_THROW(SocketcandServer(io_.get_executor(), registry_, server_->local_endpoint()), Exception);
  auto fine = SocketcandServer::create(io_.get_executor(), registry_, net::Endpoint{"127.0.0.1", 0});
  ASSERT_TRUE(fine);
  EXPECT_NE(fine.value()->local_endpoint().port, server_->local_endpoint().port);
}

TEST_F(SocketcandServerTest, HandshakeAnswersComeAloneAndUnterminated) {
  // python-can 4.1 compares each handshake read with "< hi >" / "< ok >" as a whole.
  run([&]() -> asio::awaitable<void> {
    auto peer = co_await TextPeer::connect(io_.get_executor(), port());
    EXPECT_EQ(co_await peer.read_some(), "< hi >");
    co_await peer.write("< open vcan0 >");
    EXPECT_EQ(co_await peer.read_some(), "< ok >");
    co_await peer.write("< rawmode >");
    EXPECT_EQ(co_await peer.read_some(), "< ok >");
  });
  EXPECT_EQ(server_->stats().clients_accepted, 1u);
  EXPECT_EQ(server_->stats().errors, 0u);
}

TEST_F(SocketcandServerTest, RawModeOkIsNotFollowedAtOnceByFramesOnABusyBus) {
  SocketcandServerOptions o;
  o.raw_start_delay = std::chrono::seconds(30);  // longer than the test: the first read must be the ok alone
  start_server(o);
  auto node = vcan0_->attach("node");
  run([&]() -> asio::awaitable<void> {
    auto peer = co_await TextPeer::connect(io_.get_executor(), port());
    EXPECT_EQ(co_await peer.read_some(), "< hi >");
    co_await peer.write("< open vcan0 >");
    EXPECT_EQ(co_await peer.read_some(), "< ok >");
    co_await peer.write("< rawmode >");
    // Keep the bus busy around the mode switch.
    for (int i = 0; i < 50; ++i) EXPECT_TRUE(co_await node->send(F("123#01")));
    EXPECT_EQ(co_await peer.read_some(), "< ok >");
    for (int i = 0; i < 50; ++i) EXPECT_TRUE(co_await node->send(F("123#02")));
    // Commands are still answered while frames wait.
    co_await peer.write("< echo >");
    EXPECT_EQ(co_await peer.next(), "< echo >");
  });
}

TEST_F(SocketcandServerTest, ForwardsBusFramesInTheDaemonsFormat) {
  auto node = vcan0_->attach("node");
  run([&]() -> asio::awaitable<void> {
    auto peer = co_await raw_client();
    const auto before = core::SteadyClock::instance().wall();
    EXPECT_TRUE(co_await node->send(F("123#1122")));
    EXPECT_TRUE(co_await node->send(F("00000456#AABBCCDDEEFF0011")));
    EXPECT_TRUE(co_await node->send(F("7FF#")));
    EXPECT_TRUE(co_await node->send(F("1ABCDEF0#R3")));
    const std::string m1 = co_await peer.next(), m2 = co_await peer.next(), m3 = co_await peer.next(),
                      m4 = co_await peer.next();
    const auto after = core::SteadyClock::instance().wall();
    const std::regex ts(R"(\d+\.\d{6})");
    EXPECT_TRUE(std::regex_match(m1, std::regex(R"(< frame 123 \d+\.\d{6} 1122 >)"))) << m1;
    EXPECT_TRUE(std::regex_match(m2, std::regex(R"(< frame 00000456 \d+\.\d{6} AABBCCDDEEFF0011 >)"))) << m2;
    EXPECT_TRUE(std::regex_match(m3, std::regex(R"(< frame 7FF \d+\.\d{6}  >)"))) << m3;  // two spaces
    EXPECT_TRUE(std::regex_match(m4, std::regex(R"(< rtr 1ABCDEF0 \d+\.\d{6} 3 >)"))) << m4;
    // Wall-clock timestamps of when the frames were on the bus.
    for (const auto& m : {m1, m2, m3, m4}) {
      const auto t = frame_of(m).timestamp();
      EXPECT_GE(t, before - 1us) << m;
      EXPECT_LE(t, after) << m;
    }
    EXPECT_EQ(frame_of(m2), F("00000456#AABBCCDDEEFF0011"));
    EXPECT_EQ(frame_of(m4), F("1ABCDEF0#R3"));
    // In raw mode a newline goes before every message (see SocketcandServerOptions).
    EXPECT_EQ(peer.raw(), "< hi >< ok >< ok >\n" + m1 + "\n" + m2 + "\n" + m3 + "\n" + m4);
  });
  EXPECT_EQ(server_->stats().frames_out, 4u);
}

TEST_F(SocketcandServerTest, KeepsTheFramesOwnTimestamp) {
  auto node = vcan0_->attach("node");
  run([&]() -> asio::awaitable<void> {
    auto peer = co_await raw_client();
    EXPECT_TRUE(co_await node->send(F("321#01")));
    const auto seen_by_node_peer = frame_of(co_await peer.next()).timestamp();
    EXPECT_GT(seen_by_node_peer.count(), 0);
    EXPECT_EQ(seen_by_node_peer.count() % 1000, 0);  // microsecond resolution on the wire
  });
}

TEST_F(SocketcandServerTest, WithoutSeparatorsTheOutputIsByteForByteTheDaemons) {
  SocketcandServerOptions o;
  o.separate_messages = false;
  o.raw_start_delay = core::Duration::zero();
  start_server(o);
  auto node = vcan0_->attach("node");
  run([&]() -> asio::awaitable<void> {
    auto peer = co_await raw_client();
    EXPECT_TRUE(co_await node->send(F("123#11")));
    EXPECT_TRUE(co_await node->send(F("124#22")));
    const std::string m1 = co_await peer.next(), m2 = co_await peer.next();
    EXPECT_EQ(peer.raw(), "< hi >< ok >< ok >" + m1 + m2);
  });
}

TEST_F(SocketcandServerTest, ClientSendsReachTheBusAsPythonCanAndTheDaemonWriteThem) {
  auto node = vcan0_->attach("node");
  run([&]() -> asio::awaitable<void> {
    auto peer = co_await raw_client();
    co_await peer.write("< send 123 0  >");                      // python-can, no data
    co_await peer.write("< send 5 3 1 f1 0 >");                  // python-can, unpadded
    co_await peer.write("< send 12345 1 ab >");                  // python-can, extended > 0x7FF
    co_await peer.write("< send 00000012 2 AA BB >");            // the daemon's 8-digit extended
    co_await peer.write("< send 7FF 8 1 2 3 4 5 6 7 8 >< echo >");  // two in one write
    co_await peer.write("< sendrtr 1ABCDEF0 4 >");
    co_await peer.write("< echo >");
    // Echo answers come after the sends before them were handled.
    EXPECT_EQ(co_await peer.next(), "< echo >");
    EXPECT_EQ(co_await peer.next(), "< echo >");
    std::vector<std::string> got;
    for (int i = 0; i < 6; ++i) {
      auto f = co_await node->receive(5s);
      EXPECT_TRUE(f);
      if (!f) break;
      got.push_back(f.value().to_string());
    }
    EXPECT_EQ(got, (std::vector<std::string>{"123#", "005#01F100", "00012345#AB", "00000012#AABB", "7FF#0102030405060708",
                                             "1ABCDEF0#R4"}));
  });
  EXPECT_EQ(server_->stats().frames_in, 6u);
  EXPECT_EQ(server_->stats().errors, 0u);
}

TEST_F(SocketcandServerTest, SplitReadsAreReassembled) {
  auto node = vcan0_->attach("node");
  run([&]() -> asio::awaitable<void> {
    auto peer = co_await raw_client();
    const std::string text = "< send 321 2 de ad >< echo >";
    for (char c : text) co_await peer.write(std::string(1, c));
    EXPECT_EQ(co_await peer.next(), "< echo >");
    auto f = co_await node->receive(5s);
    EXPECT_TRUE(f);
    if (f) {
      EXPECT_EQ(f.value(), F("321#DEAD"));
    }
  });
}

TEST_F(SocketcandServerTest, MalformedMessagesAreAnsweredCountedAndTheConnectionKept) {
  auto node = vcan0_->attach("node");
  run([&]() -> asio::awaitable<void> {
    auto peer = co_await raw_client();
    co_await peer.write("< send 123 2 11 >");
    EXPECT_EQ(co_await peer.next(), "< error length 2 but 1 data bytes >");
    co_await peer.write("junk< bogus >");
    const std::string e1 = co_await peer.next(), e2 = co_await peer.next();
    EXPECT_TRUE(e1.starts_with("< error socketcand stream: 4 garbage byte(s) between messages")) << e1;
    EXPECT_EQ(e2, "< error unknown command 'bogus' >");
    co_await peer.write("< send 3FFFFFFF 0 >< subscribe 0 0 123 >< statistics 100 >< open vcan1 >< frame 1 1.0  >");
    EXPECT_EQ(co_await peer.next(), "< error id '3FFFFFFF' is wider than 29 bits >");
    EXPECT_EQ(co_await peer.next(), "< error 'subscribe' (broadcast manager / ISO-TP) is not supported >");
    EXPECT_EQ(co_await peer.next(), "< error 'statistics' is only available in control mode >");
    EXPECT_EQ(co_await peer.next(), "< error channel vcan0 is already open >");
    EXPECT_EQ(co_await peer.next(), "< error 'frame' is not a client command >");
    co_await peer.write("< isotpmode >");
    EXPECT_EQ(co_await peer.next(), "< error ISO-TP mode is not supported >");
    // Still connected and working.
    co_await peer.write("< send 123 1 11 >< echo >");
    EXPECT_EQ(co_await peer.next(), "< echo >");
    auto f = co_await node->receive(5s);
    EXPECT_TRUE(f);
    if (f) {
      EXPECT_EQ(f.value(), F("123#11"));
    }
  });
  EXPECT_EQ(server_->stats().errors, 9u);
  EXPECT_EQ(server_->stats().frames_in, 1u);
}

TEST_F(SocketcandServerTest, OverlongMessageIsAnErrorNotADisconnect) {
  run([&]() -> asio::awaitable<void> {
    auto peer = co_await raw_client();
    co_await peer.write("< send " + std::string(2000, '1') + " >< echo >");
    const std::string e = co_await peer.next();
    EXPECT_TRUE(e.starts_with("< error socketcand stream: message longer than")) << e;
    EXPECT_EQ(co_await peer.next(), "< echo >");
  });
  EXPECT_EQ(server_->stats().errors, 1u);
}

TEST_F(SocketcandServerTest, CommandsBeforeOpenAreRefusedButTheConnectionStays) {
  run([&]() -> asio::awaitable<void> {
    auto peer = co_await TextPeer::connect(io_.get_executor(), port());
    EXPECT_EQ(co_await peer.next(), "< hi >");
    co_await peer.write("< rawmode >< echo >< open vcan1 >");
    EXPECT_EQ(co_await peer.next(), "< error no channel open: 'rawmode' needs '? open CHANNEL ?' first >");
    EXPECT_EQ(co_await peer.next(), "< echo >");
    EXPECT_EQ(co_await peer.next(), "< ok >");
  });
  EXPECT_EQ(server_->stats().errors, 1u);
}

TEST_F(SocketcandServerTest, UnknownChannelIsAnErrorAndTheServerHangsUp) {
  run([&]() -> asio::awaitable<void> {
    auto peer = co_await TextPeer::connect(io_.get_executor(), port());
    EXPECT_EQ(co_await peer.next(), "< hi >");
    co_await peer.write("< open can9 >");
    EXPECT_EQ(co_await peer.next(), "< error could not open bus can9 >");
    EXPECT_EQ(co_await peer.next(), "");  // end of stream
  });
  EXPECT_EQ(server_->stats().errors, 1u);
  EXPECT_EQ(server_->stats().clients_active, 0u);
}

TEST_F(SocketcandServerTest, TwoClientsSeeEachOthersFramesButNotTheirOwn) {
  auto node = vcan0_->attach("node");
  run([&]() -> asio::awaitable<void> {
    auto a = co_await raw_client();
    auto b = co_await raw_client();
    co_await a.write("< send 100 1 0a >");
    co_await b.write("< send 200 1 0b >");
    EXPECT_EQ(frame_of(co_await b.next()), F("100#0A"));
    EXPECT_EQ(frame_of(co_await a.next()), F("200#0B"));
    // The virtual node saw both, in order; then it talks and both clients hear it.
    auto f1 = co_await node->receive(5s), f2 = co_await node->receive(5s);
    EXPECT_TRUE(f1 && f2);
    if (f1 && f2) {
      EXPECT_EQ(f1.value(), F("100#0A"));
      EXPECT_EQ(f2.value(), F("200#0B"));
    }
    EXPECT_TRUE(co_await node->send(F("300#0C")));
    EXPECT_EQ(frame_of(co_await a.next()), F("300#0C"));
    EXPECT_EQ(frame_of(co_await b.next()), F("300#0C"));
    // Neither client got its own frame back: the echo answer comes next.
    co_await a.write("< echo >");
    co_await b.write("< echo >");
    EXPECT_EQ(co_await a.next(), "< echo >");
    EXPECT_EQ(co_await b.next(), "< echo >");
  });
  EXPECT_EQ(server_->stats().clients_accepted, 2u);
  EXPECT_EQ(server_->stats().frames_in, 2u);
  EXPECT_EQ(server_->stats().frames_out, 4u);
}

TEST_F(SocketcandServerTest, ClientsOnDifferentChannelsAreSeparate) {
  run([&]() -> asio::awaitable<void> {
    auto a = co_await raw_client("vcan0");
    auto b = co_await raw_client("vcan1");
    auto c = co_await raw_client("vcan1");
    co_await a.write("< send 100 0 >");
    co_await b.write("< send 200 0 >");
    EXPECT_EQ(frame_of(co_await c.next()), F("200#"));
    co_await c.write("< echo >");
    co_await a.write("< echo >");
    EXPECT_EQ(co_await a.next(), "< echo >");  // nothing from vcan1 before it
  });
}

TEST_F(SocketcandServerTest, BcmModeDoesNotForwardButSends) {
  auto node = vcan0_->attach("node");
  run([&]() -> asio::awaitable<void> {
    auto peer = co_await raw_client("vcan0", false);  // BCM mode after open
    EXPECT_TRUE(co_await node->send(F("111#01")));
    co_await peer.write("< send 222 1 02 >< echo >");
    EXPECT_EQ(co_await peer.next(), "< echo >");  // the 111 frame was not forwarded
    auto f = co_await node->receive(5s);
    EXPECT_TRUE(f);
    if (f) {
      EXPECT_EQ(f.value(), F("222#02"));
    }
    // Raw mode forwards what comes after it, not what went before.
    co_await peer.write("< rawmode >");
    EXPECT_EQ(co_await peer.next(), "< ok >");
    EXPECT_TRUE(co_await node->send(F("333#03")));
    EXPECT_EQ(frame_of(co_await peer.next()), F("333#03"));
    // Back to BCM mode: forwarding stops.
    co_await peer.write("< bcmmode >");
    EXPECT_EQ(co_await peer.next(), "< ok >");
    EXPECT_TRUE(co_await node->send(F("444#04")));
    co_await peer.write("< echo >");
    EXPECT_EQ(co_await peer.next(), "< echo >");
    // And raw again.
    co_await peer.write("< rawmode >");
    EXPECT_EQ(co_await peer.next(), "< ok >");
    EXPECT_TRUE(co_await node->send(F("555#05")));
    EXPECT_EQ(frame_of(co_await peer.next()), F("555#05"));
  });
}

TEST_F(SocketcandServerTest, ControlModeReportsStatistics) {
  run([&]() -> asio::awaitable<void> {
    auto peer = co_await raw_client();
    co_await peer.write("< send 123 2 11 22 >< send 124 0 >");
    co_await peer.write("< controlmode >");
    EXPECT_EQ(co_await peer.next(), "< ok >");
    co_await peer.write("< send 125 0 >");
    EXPECT_EQ(co_await peer.next(), "< error frames cannot be sent in control mode >");
    co_await peer.write("< statistics 10 >");
    auto m = sc::parse(co_await peer.next());
    EXPECT_TRUE(m);
    if (m) {
      EXPECT_EQ(m.value(), sc::Message(sc::Stat{0, 0, 2, 2}));
    }
    co_await peer.write("< statistics 0 >< echo >");
    // Nothing but possibly one more report in flight before the echo.
    for (int i = 0; i < 3; ++i) {
      const std::string next = co_await peer.next();
      if (next == "< echo >") break;
      EXPECT_TRUE(next.starts_with("< stat ")) << next;
    }
  });
}

TEST_F(SocketcandServerTest, StopClosesEveryConnection) {
  run([&]() -> asio::awaitable<void> {
    auto a = co_await raw_client();
    auto b = co_await TextPeer::connect(io_.get_executor(), port());
    EXPECT_EQ(co_await b.next(), "< hi >");
    EXPECT_EQ(server_->stats().clients_active, 2u);
    server_->stop();
    server_->stop();
    EXPECT_EQ(server_->stats().clients_active, 0u);
    EXPECT_EQ(co_await a.next(), "");
    EXPECT_EQ(co_await b.next(), "");
  });
}

TEST_F(SocketcandServerTest, ClientHangingUpEndsItsSession) {
  run([&]() -> asio::awaitable<void> {
    {
      auto a = co_await raw_client();
      a.close();
    }
    // Another client still works, and the first one's session is gone once the server noticed.
    auto b = co_await raw_client();
    co_await b.write("< echo >");
    EXPECT_EQ(co_await b.next(), "< echo >");
    while (server_->stats().clients_active > 1) {
      asio::steady_timer t(io_, 1ms);
      co_await t.async_wait(asio::use_awaitable);
    }
    EXPECT_EQ(vcan0_->node_count(), 1u);  // only b's endpoint is left on the bus
  });
}

TEST_F(SocketcandServerTest, RefusesClientsBeyondTheLimit) {
  SocketcandServerOptions o;
  o.max_clients = 1;
  start_server(o);
  run([&]() -> asio::awaitable<void> {
    auto a = co_await raw_client();
    auto b = co_await TextPeer::connect(io_.get_executor(), port());
    EXPECT_EQ(co_await b.next(), "");  // closed without a greeting
    co_await a.write("< echo >");
    EXPECT_EQ(co_await a.next(), "< echo >");
  });
  EXPECT_EQ(server_->stats().clients_rejected, 1u);
}

}  // namespace
}  // namespace axon::can

// SocketcandBus against axon's server over a virtual bus, and against scripted fake servers that
// misbehave in chosen ways.
#include "axon/can/socketcand_client.hpp"

#include "axon/can/socketcand_server.hpp"
#include "axon/can/virtual_bus.hpp"
#include "socketcand_test_util.hpp"
#include "frame_text.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <memory>

namespace axon::can {
namespace {

using namespace std::chrono_literals;
using testing::TextPeer;

using axon::can::test::F;

class SocketcandClientTest : public ::testing::Test {
 protected:
  void SetUp() override {
    vcan0_ = registry_.add("vcan0").value();
    server_ = std::make_unique<SocketcandServer>(io_.get_executor(), registry_, net::Endpoint{"127.0.0.1", 0});
  }

  void run(std::function<asio::awaitable<void>()> body) {
    testing::run_test(io_, std::move(body), [this] { server_->stop(); });
  }

  asio::awaitable<std::unique_ptr<SocketcandBus>> connect(std::string channel = "vcan0") {
    auto r = co_await SocketcandBus::connect(io_.get_executor(), server_->local_endpoint(), std::move(channel));
    EXPECT_TRUE(r) << (r ? "" : r.error().message());
    co_return r ? std::move(r).value() : nullptr;
  }

  asio::io_context io_;
  VirtualBusRegistry registry_{io_.get_executor()};
  std::shared_ptr<VirtualBus> vcan0_;
  std::unique_ptr<SocketcandServer> server_;
};

TEST_F(SocketcandClientTest, ConnectsAndNamesTheBus) {
  run([&]() -> asio::awaitable<void> {
    auto bus = co_await connect();
    if (!bus) co_return;
    EXPECT_TRUE(bus->is_open());
    EXPECT_EQ(bus->channel(), "vcan0");
    EXPECT_EQ(bus->name(), fmt::format("socketcand://127.0.0.1:{}/vcan0", server_->local_endpoint().port));
  });
  EXPECT_EQ(server_->stats().clients_accepted, 1u);
}

TEST_F(SocketcandClientTest, TwoClientsExchangeEveryKindOfFrameInOrder) {
  const std::vector<Frame> frames = {F("123#"),          F("7FF#0102030405060708"), F("000#AA"),
                                     F("00000001#11"),   F("1FFFFFFF#DEADBEEF"),    F("12345678#0011223344556677"),
                                     F("321#R"),         F("1ABCDEF0#R8"),          F("00000100#R2")};
  auto node = vcan0_->attach("node");
  run([&]() -> asio::awaitable<void> {
    auto a = co_await connect();
    auto b = co_await connect();
    if (!a || !b) co_return;
    for (const auto& f : frames) EXPECT_TRUE(co_await a->send(f));
    for (const auto& f : frames) {
      auto got = co_await b->receive(5s);
      EXPECT_TRUE(got) << f.to_string();
      if (!got) co_return;
      EXPECT_EQ(got.value(), f) << got.value().to_string() << " vs " << f.to_string();
      EXPECT_GT(got.value().timestamp().count(), 0);
    }
    // The virtual node got them too, exactly (format included: the 8-digit ids are extended).
    for (const auto& f : frames) {
      auto got = co_await node->receive(5s);
      EXPECT_TRUE(got);
      if (got) {
        EXPECT_EQ(got.value(), f);
      }
    }
    // a does not hear itself; it hears b.
    EXPECT_TRUE(co_await b->send(F("456#01")));
    auto back = co_await a->receive(5s);
    EXPECT_TRUE(back);
    if (back) {
      EXPECT_EQ(back.value(), F("456#01"));
    }
    EXPECT_EQ(a->stats().frames_out, frames.size());
    EXPECT_EQ(a->stats().frames_in, 1u);
    EXPECT_EQ(b->stats().frames_in, frames.size());
    EXPECT_EQ(a->stats().protocol_errors + b->stats().protocol_errors, 0u);
  });
  EXPECT_EQ(server_->stats().frames_in, frames.size() + 1);
}

TEST_F(SocketcandClientTest, ManyFramesArriveCompleteAndInOrder) {
  constexpr int kFrames = 5000;
  run([&]() -> asio::awaitable<void> {
    auto a = co_await connect();
    auto b = co_await connect();
    if (!a || !b) co_return;
    for (int i = 0; i < kFrames; ++i) {
      const std::uint8_t bytes[2] = {static_cast<std::uint8_t>(i >> 8), static_cast<std::uint8_t>(i)};
      auto r = co_await a->send(Frame::extended(0x1000 + i % 7, bytes).value());
      EXPECT_TRUE(r);
      if (!r) co_return;
      if (i % 512 == 511) {  // let the writer catch up now and then (tx_capacity is 1024)
        while (a->tx_pending() > 0) {
          asio::steady_timer t(io_, 1ms);
          co_await t.async_wait(asio::use_awaitable);
        }
      }
    }
    for (int i = 0; i < kFrames; ++i) {
      auto got = co_await b->receive(10s);
      EXPECT_TRUE(got) << "frame " << i;
      if (!got) co_return;
      const auto p = got.value().payload();
      EXPECT_EQ(p.size(), 2u);
      if (p.size() != 2) co_return;
      EXPECT_EQ((p[0] << 8 | p[1]), i & 0xFFFF);
    }
  });
}

TEST_F(SocketcandClientTest, UnknownChannelIsADeviceErrorWithTheServersText) {
  run([&]() -> asio::awaitable<void> {
    auto r = co_await SocketcandBus::connect(io_.get_executor(), server_->local_endpoint(), "can7");
    EXPECT_FALSE(r);
    if (r) co_return;
    EXPECT_EQ(r.error(), CanErrc::device_error);
    EXPECT_NE(r.error().detail.find("could not open bus can7"), std::string::npos) << r.error().detail;
    EXPECT_NE(r.error().detail.find("/can7"), std::string::npos) << r.error().detail;
  });
}

TEST_F(SocketcandClientTest, RefusedConnectionIsConnectFailed) {
  std::uint16_t closed_port = 0;
  {
    auto acc = testing::loopback_acceptor(io_.get_executor());
    closed_port = acc.local_endpoint().port();
  }
  run([&]() -> asio::awaitable<void> {
    // (A named endpoint: GCC 12 destroys aggregate temporaries in co_await expressions twice.)
    const net::Endpoint nobody{"127.0.0.1", closed_port};
    auto r = co_await SocketcandBus::connect(io_.get_executor(), nobody, "vcan0");
    EXPECT_FALSE(r);
    if (!r) {
      EXPECT_EQ(r.error(), CanErrc::connect_failed);
    }
  });
}

TEST_F(SocketcandClientTest, ServerClosingTheConnectionClosesTheBus) {
  run([&]() -> asio::awaitable<void> {
    auto bus = co_await connect();
    if (!bus) co_return;
    server_->stop();
    auto r = co_await bus->receive(10s);
    EXPECT_FALSE(r);
    if (!r) {
      EXPECT_EQ(r.error(), CanErrc::closed);
    }
    EXPECT_FALSE(bus->is_open());
    auto s = co_await bus->send(F("123#00"));
    EXPECT_FALSE(s);
    if (!s) {
      EXPECT_EQ(s.error(), CanErrc::closed);
    }
  });
}

TEST_F(SocketcandClientTest, CloseIsImmediateAndFinal) {
  run([&]() -> asio::awaitable<void> {
    auto bus = co_await connect();
    if (!bus) co_return;
    bus->close();
    bus->close();
    auto r = co_await bus->receive();
    EXPECT_FALSE(r);
    EXPECT_FALSE(co_await bus->send(F("123#00")));
  });
}

// ------------------------------------------------------------------------------ fake servers

// Accepts one client and hands its socket to `script`.
class FakeServerTest : public ::testing::Test {
 protected:
  void run(std::function<asio::awaitable<void>(TextPeer&)> script,
           std::function<asio::awaitable<void>(net::Endpoint)> client) {
    auto acceptor = std::make_shared<asio::ip::tcp::acceptor>(testing::loopback_acceptor(io_.get_executor()));
    const net::Endpoint ep{"127.0.0.1", acceptor->local_endpoint().port()};
    asio::co_spawn(
        io_,
        [acceptor, script]() -> asio::awaitable<void> {
          TextPeer peer(co_await acceptor->async_accept(asio::use_awaitable));
          co_await script(peer);
        },
        [](std::exception_ptr e) {
          if (e) std::rethrow_exception(e);
        });
    testing::run_test(io_, [&]() -> asio::awaitable<void> { co_await client(ep); });
  }

  // The server side of a handshake that goes well.
  static asio::awaitable<void> greet(TextPeer& peer) {
    co_await peer.write("< hi >");
    EXPECT_EQ(co_await peer.next(), "< open vcan0 >");
    co_await peer.write("< ok >");
    EXPECT_EQ(co_await peer.next(), "< rawmode >");
    co_await peer.write("< ok >");
  }

  asio::io_context io_;
};

TEST_F(FakeServerTest, FrameTimestampsComeFromTheServer) {
  run(
      [](TextPeer& peer) -> asio::awaitable<void> {
        co_await greet(peer);
        co_await peer.write("< frame 123 1700000000.123456 11 >< rtr 00000042 1700000001.000001 2 >");
        co_await peer.next();  // until the client hangs up
      },
      [&](net::Endpoint ep) -> asio::awaitable<void> {
        auto bus = (co_await SocketcandBus::connect(io_.get_executor(), ep, "vcan0")).value();
        auto f1 = co_await bus->receive(5s);
        auto f2 = co_await bus->receive(5s);
        EXPECT_TRUE(f1 && f2);
        if (!f1 || !f2) co_return;
        EXPECT_EQ(f1.value(), F("123#11"));
        EXPECT_EQ(f1.value().timestamp(), core::WallTime(1'700'000'000'123'456'000));
        EXPECT_EQ(f2.value(), F("00000042#R2"));
        EXPECT_EQ(f2.value().timestamp(), core::WallTime(1'700'000'001'000'001'000));
      });
}

TEST_F(FakeServerTest, FramesRightBehindTheLastOkAreNotLost) {
  run(
      [](TextPeer& peer) -> asio::awaitable<void> {
        co_await peer.write("< hi >");
        co_await peer.next();
        co_await peer.write("< ok >");
        co_await peer.next();
        co_await peer.write("< ok >< frame 001 1.000000 01 >");  // one write
        co_await peer.next();
      },
      [&](net::Endpoint ep) -> asio::awaitable<void> {
        auto bus = (co_await SocketcandBus::connect(io_.get_executor(), ep, "vcan0")).value();
        auto f = co_await bus->receive(5s);
        EXPECT_TRUE(f);
        if (f) {
          EXPECT_EQ(f.value(), F("001#01"));
        }
      });
}

TEST_F(FakeServerTest, BadInputIsCountedAndTheConnectionKept) {
  run(
      [](TextPeer& peer) -> asio::awaitable<void> {
        co_await greet(peer);
        co_await peer.write("garbage< frame 123 1.0 1 >< bogus >< ok >< error unknown command >");
        co_await peer.write("< error 004 1.000000 >");
        co_await peer.write("< frame 456 2.000000 22 >");
        co_await peer.next();
      },
      [&](net::Endpoint ep) -> asio::awaitable<void> {
        auto bus = (co_await SocketcandBus::connect(io_.get_executor(), ep, "vcan0")).value();
        auto f = co_await bus->receive(5s);
        EXPECT_TRUE(f);
        if (f) {
          EXPECT_EQ(f.value(), F("456#22"));
        }
        // garbage, odd data, unknown command, unexpected ok, error answer
        EXPECT_EQ(bus->stats().protocol_errors, 5u);
        EXPECT_EQ(bus->stats().error_frames, 1u);
        EXPECT_EQ(bus->last_server_error(), "unknown command");
        EXPECT_TRUE(bus->is_open());
      });
}

TEST_F(FakeServerTest, SplitReadsAreReassembled) {
  run(
      [](TextPeer& peer) -> asio::awaitable<void> {
        co_await greet(peer);
        const std::string text = "< frame 1FFFFFFF 3.000003 0102030405060708 >\n< frame 7FF 4.000004  >";
        for (char c : text) {
          co_await peer.write(std::string(1, c));
          // Give the client a chance to read each byte on its own.
          asio::steady_timer t(peer.socket().get_executor(), 100us);
          co_await t.async_wait(asio::use_awaitable);
        }
        co_await peer.next();
      },
      [&](net::Endpoint ep) -> asio::awaitable<void> {
        auto bus = (co_await SocketcandBus::connect(io_.get_executor(), ep, "vcan0")).value();
        auto f1 = co_await bus->receive(10s);
        auto f2 = co_await bus->receive(10s);
        EXPECT_TRUE(f1 && f2);
        if (!f1 || !f2) co_return;
        EXPECT_EQ(f1.value(), F("1FFFFFFF#0102030405060708"));
        EXPECT_EQ(f2.value(), F("7FF#"));
        EXPECT_EQ(bus->stats().protocol_errors, 0u);
      });
}

TEST_F(FakeServerTest, WrongGreetingIsAProtocolError) {
  run(
      [](TextPeer& peer) -> asio::awaitable<void> {
        co_await peer.write("< ok >");
        co_await peer.next();
      },
      [&](net::Endpoint ep) -> asio::awaitable<void> {
        auto r = co_await SocketcandBus::connect(io_.get_executor(), ep, "vcan0");
        EXPECT_FALSE(r);
        if (!r) {
          EXPECT_EQ(r.error(), CanErrc::protocol_error);
          EXPECT_NE(r.error().detail.find("expected < hi >"), std::string::npos) << r.error().detail;
        }
      });
}

TEST_F(FakeServerTest, RefusedRawModeIsADeviceError) {
  run(
      [](TextPeer& peer) -> asio::awaitable<void> {
        co_await peer.write("< hi >");
        co_await peer.next();
        co_await peer.write("< ok >");
        co_await peer.next();
        co_await peer.write("< error raw mode not allowed >");
        co_await peer.next();
      },
      [&](net::Endpoint ep) -> asio::awaitable<void> {
        auto r = co_await SocketcandBus::connect(io_.get_executor(), ep, "vcan0");
        EXPECT_FALSE(r);
        if (!r) {
          EXPECT_EQ(r.error(), CanErrc::device_error);
          EXPECT_NE(r.error().detail.find("raw mode not allowed"), std::string::npos) << r.error().detail;
        }
      });
}

TEST_F(FakeServerTest, SilentServerTimesOut) {
  run(
      [](TextPeer& peer) -> asio::awaitable<void> {
        co_await peer.next();  // says nothing; waits for the client to give up
      },
      [&](net::Endpoint ep) -> asio::awaitable<void> {
        auto r = co_await SocketcandBus::connect(io_.get_executor(), ep, "vcan0", {}, 200ms);
        EXPECT_FALSE(r);
        if (!r) {
          EXPECT_EQ(r.error(), CanErrc::timeout);
        }
      });
}

TEST_F(FakeServerTest, HangUpDuringHandshakeIsClosed) {
  run(
      [](TextPeer& peer) -> asio::awaitable<void> {
        co_await peer.write("< hi >");
        co_await peer.next();
        peer.close();
      },
      [&](net::Endpoint ep) -> asio::awaitable<void> {
        auto r = co_await SocketcandBus::connect(io_.get_executor(), ep, "vcan0");
        EXPECT_FALSE(r);
        if (!r) {
          EXPECT_EQ(r.error(), CanErrc::closed);
        }
      });
}

TEST_F(FakeServerTest, SendWritesTheDaemonsSyntax) {
  run(
      [](TextPeer& peer) -> asio::awaitable<void> {
        co_await greet(peer);
        EXPECT_EQ(co_await peer.next(), "< send 123 2 DE AD >");
        EXPECT_EQ(co_await peer.next(), "< send 00000005 0 >");
        EXPECT_EQ(co_await peer.next(), "< sendrtr 1ABCDEF0 3 >");
      },
      [&](net::Endpoint ep) -> asio::awaitable<void> {
        auto bus = (co_await SocketcandBus::connect(io_.get_executor(), ep, "vcan0")).value();
        EXPECT_TRUE(co_await bus->send(F("123#DEAD")));
        EXPECT_TRUE(co_await bus->send(F("00000005#")));
        EXPECT_TRUE(co_await bus->send(F("1ABCDEF0#R3")));
        auto r = co_await bus->receive(10s);  // the fake server hangs up after reading them
        EXPECT_FALSE(r);
      });
}

}  // namespace
}  // namespace axon::can

// The socketcand server facing hostile peers (docs/reliability.md, "Hostile peers"): many
// connections, clients that never read, connections that go silent before opening a channel,
// oversized messages and garbage. What must hold: a well-behaved client keeps its round trip,
// the server's queue per client stays bounded, every rejection is counted and logged once.
#include "axon/can/socketcand_server.hpp"

#include "can/bus_bench.hpp"
#include "support/hostile_peer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace axon::can::socketcand_hostile {
namespace {

using namespace axon::can;

using hostile::RawPeer;
using hostile::WarningLog;
using hostile::wait_until;
using namespace std::chrono_literals;

// A server on can0.
struct Bench : test::BusBench {
  std::unique_ptr<SocketcandServer> server;

  explicit Bench(SocketcandServerOptions o = {}) {
    loop.call([&] { server = SocketcandServer::create(loop.executor(), *registry, {"127.0.0.1", 0}, o).value(); });
  }
  ~Bench() {
    loop.call([&] {
      server->stop();
      server.reset();
    });
  }
  [[nodiscard]] std::uint16_t port() const { return server->local_endpoint().port; }
  SocketcandServerStats stats() { return loop.call([&] { return server->stats(); }); }
};

// A client that plays by the rules: `< hi >`, then `< echo >` round trips.
struct GoodClient {
  RawPeer peer;
  explicit GoodClient(std::uint16_t port) : peer(port) { EXPECT_NE(peer.read_until("< hi >").find("< hi >"), std::string::npos); }
  // One echo round trip in microseconds, -1 when not answered within 2 s.
  double echo_us() {
    const auto t0 = std::chrono::steady_clock::now();
    if (!peer.send_all("< echo >")) return -1;
    if (peer.read_until("< echo >", 2000ms).find("< echo >") == std::string::npos) return -1;
    return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  }
  double median_echo_us() {
    return hostile::median_of(50, [&] { return echo_us(); });
  }
};

TEST(SocketcandHostile, TwoHundredConnectionsAtOnceAndAGoodClientKeepsItsRoundTrip) {
  SocketcandServerOptions o;
  o.max_clients = 256;
  Bench b(o);
  GoodClient good(b.port());
  const double alone_us = good.median_echo_us();
  const long rss_before = hostile::resident_kb();
  std::vector<std::unique_ptr<RawPeer>> peers;
  for (int i = 0; i < 200; ++i) peers.push_back(std::make_unique<RawPeer>(b.port()));
  ASSERT_TRUE(wait_until([&] { return b.stats().clients_active == 201; })) << b.stats().clients_active;
  const long rss_idle = hostile::resident_kb();
  const double crowded_us = good.median_echo_us();
  EXPECT_GT(crowded_us, 0);
  // Each of them is served as well: greeting, then an echo.
  for (auto& p : peers) {
    ASSERT_TRUE(p->send_all("< echo >"));
    EXPECT_NE(p->read_until("< echo >").find("< echo >"), std::string::npos);
  }
  std::cout << "figure: socketcand echo round trip " << alone_us << " us alone, " << crowded_us
            << " us with 200 idle connections; process RSS +" << rss_idle - rss_before << " kB for them\n";
  peers.clear();
  EXPECT_TRUE(wait_until([&] { return b.stats().clients_active == 1; }));
  EXPECT_EQ(b.stats().clients_rejected, 0u);
}

TEST(SocketcandHostile, ConnectionsBeyondTheLimitAreRefusedCountedAndLoggedOnce) {
  WarningLog log;
  SocketcandServerOptions o;
  o.max_clients = 8;
  Bench b(o);
  std::vector<std::unique_ptr<RawPeer>> peers;
  for (int i = 0; i < 8; ++i) peers.push_back(std::make_unique<RawPeer>(b.port()));
  ASSERT_TRUE(wait_until([&] { return b.stats().clients_active == 8; }));
  std::vector<std::unique_ptr<RawPeer>> extra;
  for (int i = 0; i < 20; ++i) extra.push_back(std::make_unique<RawPeer>(b.port()));
  ASSERT_TRUE(wait_until([&] { return b.stats().clients_rejected == 20; })) << b.stats().clients_rejected;
  for (auto& p : extra) EXPECT_TRUE(p->closed_by_server());
  EXPECT_EQ(log.count("refusing"), 1u);
}

TEST(SocketcandHostile, ConnectionsThatNeverOpenAChannelDoNotLockOthersOut) {
  WarningLog log;
  SocketcandServerOptions o;
  o.max_clients = 8;
  o.handshake_timeout = 300ms;
  Bench b(o);
  std::vector<std::unique_ptr<RawPeer>> silent;
  for (int i = 0; i < 8; ++i) silent.push_back(std::make_unique<RawPeer>(b.port()));
  // Half-open in the other sense too: connect, start a message and hang up.
  for (int i = 0; i < 5; ++i) RawPeer(b.port()).send_all("< open ca");
  // The silent ones are closed once their time is up; then a good client gets in and is served.
  for (auto& p : silent) EXPECT_TRUE(p->closed_by_server(3000ms));
  EXPECT_TRUE(wait_until([&] { return b.stats().clients_active == 0; }));
  EXPECT_EQ(b.stats().handshake_timeouts, 8u);
  EXPECT_EQ(log.count("no channel opened within"), 8u);
  GoodClient good(b.port());
  EXPECT_GT(good.echo_us(), 0);
  EXPECT_TRUE(good.peer.send_all("< open can0 >"));
  EXPECT_NE(good.peer.read_until("< ok >").find("< ok >"), std::string::npos);
}

TEST(SocketcandHostile, AClientThatSendsButNeverReadsHasABoundedQueue) {
  SocketcandServerOptions o;
  o.client_backlog = 64 * 1024;
  Bench b(o);
  GoodClient good(b.port());
  RawPeer flooder(b.port(), 4096);
  // Echo requests, never reading an answer.
  std::string burst;
  for (int i = 0; i < 4096; ++i) burst += "< echo >";
  // Until 8 MB went out, or the server has stopped reading it (nothing taken for 200 ms).
  std::size_t sent = 0;
  auto last_taken = std::chrono::steady_clock::now();
  while (sent < (8u << 20) && !flooder.broken() && std::chrono::steady_clock::now() - last_taken < 200ms) {
    const std::size_t n = flooder.send_some(burst);
    sent += n;
    if (n > 0) last_taken = std::chrono::steady_clock::now();
    else std::this_thread::sleep_for(1ms);
  }
  EXPECT_GT(good.echo_us(), 0) << "the good client was not answered";
  const auto s = b.stats();
  // The backlog, plus the answers to one read (4096 bytes of requests).
  EXPECT_LE(s.output_high_water, o.client_backlog + 8 * 1024) << "sent " << sent;
  std::cout << "figure: socketcand flooder sent " << sent << " bytes of requests without reading; largest queue "
            << s.output_high_water << " bytes\n";
}

TEST(SocketcandHostile, ARawModeClientThatNeverReadsHasABoundedQueueAndOthersGetEveryFrame) {
  SocketcandServerOptions o;
  o.client_backlog = 64 * 1024;
  o.raw_start_delay = 0ms;
  Bench b(o);
  RawPeer sleeper(b.port(), 4096);
  ASSERT_TRUE(sleeper.send_all("< open can0 >< rawmode >"));
  GoodClient good(b.port());
  ASSERT_TRUE(good.peer.send_all("< open can0 >< rawmode >"));
  ASSERT_NE(good.peer.read_until("< ok >< ok >").find("< ok >< ok >"), std::string::npos);
  std::thread reader([&] {
    // The good client reads everything; counts the frames.
    std::string got = good.peer.read_until("0F", 20000ms);
    (void)got;
  });
  b.flood(20000);
  const std::uint8_t last[1] = {0x0F};
  b.loop.run([&]() -> asio::awaitable<void> { (void)co_await b.tap->send(Frame::standard(0x7FF, last).value()); }, 5s);
  reader.join();
  const auto s = b.stats();
  EXPECT_LE(s.output_high_water, o.client_backlog + 32 * 1024);
  EXPECT_GT(good.echo_us(), 0);
}

TEST(SocketcandHostile, OversizedMessagesAndGarbageAreCountedAnsweredAndLoggedOncePerClient) {
  WarningLog log;
  Bench b;
  GoodClient good(b.port());
  RawPeer longer(b.port());
  RawPeer garbage(b.port());
  ASSERT_TRUE(longer.send_all("<" + std::string(1 << 20, 'a')));
  std::string noise(1 << 20, '\0');
  for (std::size_t i = 0; i < noise.size(); ++i) {  // every byte value but 0 and '<'
    const char c = static_cast<char>((i * 7919) % 251 + 1);
    noise[i] = c == '<' ? 'x' : c;
  }
  ASSERT_TRUE(garbage.send_all(noise));
  // Both still connected and answered afterwards.
  ASSERT_TRUE(longer.send_all(">< echo >"));
  ASSERT_TRUE(garbage.send_all("< echo >"));
  EXPECT_NE(longer.read_until("< echo >", 10000ms).find("< echo >"), std::string::npos);
  EXPECT_NE(garbage.read_until("< echo >", 10000ms).find("< echo >"), std::string::npos);
  EXPECT_GT(good.echo_us(), 0);
  const auto s = b.stats();
  // One for the overlong message, one per 512 bytes of garbage (whitespace between messages is not).
  EXPECT_GE(s.errors, 1 + (1u << 20) / 512 * 9 / 10);
  EXPECT_EQ(log.count("socketcand: 127.0.0.1"), 2u);  // one warning per client, the rest at debug level
  EXPECT_LE(s.output_high_water, SocketcandServerOptions{}.client_backlog + 64 * 1024);
}

}  // namespace
}  // namespace axon::can::socketcand_hostile

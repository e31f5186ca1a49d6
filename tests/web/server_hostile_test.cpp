// The web server (--http) facing hostile peers (docs/reliability.md, "Hostile peers"): more
// connections than it takes, a request that stops half-way, a client that trickles headers for
// ever, oversized and binary garbage, a WebSocket client sending broken frames, and many clients
// coming and going. What must hold: a well-behaved client is still served meanwhile, every
// rejection is counted (and a refusal logged), descriptors return and memory stays bounded.
#include "axon/web/server.hpp"
#include "http_client.hpp"
#include "support/hostile_peer.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace axon::web::hostile_test {
namespace {

using hostile::RawPeer;
using hostile::wait_until;
using namespace std::chrono_literals;

constexpr std::size_t kLimit = 16;

ServerOptions small_limits() {
  ServerOptions o;
  o.assets_dir = std::filesystem::temp_directory_path().string();
  o.push_period = 10ms;
  o.max_connections = kLimit;
  o.idle_timeout = 1s;
  return o;
}

constexpr std::string_view kGoodRequest = "GET /api/sources HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n";

// A well-behaved client on a connection of its own: answered 200?
bool served(std::uint16_t port) {
  RawPeer p(port);
  return p.send_all(kGoodRequest) && p.read_until("\r\n\r\n").starts_with("HTTP/1.1 200 ");
}

// The median time of 50 such requests, connection included [us] (-1 for one not served).
double median_request_us(std::uint16_t port) {
  return hostile::median_of(50, [&] {
    const auto t0 = std::chrono::steady_clock::now();
    if (!served(port)) return -1.0;
    return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  });
}

TEST(WebServerHostile, ConnectionsBeyondTheLimitAreAnswered503AndTheOthersStillServed) {
  Server server(small_limits());
  hostile::WarningLog log;
  std::vector<std::unique_ptr<RawPeer>> idle;
  for (std::size_t i = 0; i < kLimit; ++i) idle.push_back(std::make_unique<RawPeer>(server.port()));
  ASSERT_TRUE(wait_until([&] { return server.stats().connections == kLimit; }));
  RawPeer extra(server.port());
  EXPECT_TRUE(extra.read_until("\r\n\r\n").starts_with("HTTP/1.1 503 ")) << "the one too many is told why";
  EXPECT_TRUE(extra.closed_by_server());
  EXPECT_EQ(server.stats().refused, 1u);
  EXPECT_EQ(log.count("answered 503"), 1u);
  idle.resize(kLimit - 4);  // four leave: there is room again
  EXPECT_TRUE(wait_until([&] { return server.stats().connections == kLimit - 4; }));
  EXPECT_TRUE(served(server.port()));
}

TEST(WebServerHostile, ARequestThatStopsHalfWayIsClosedAtTheIdleTimeoutAndOthersAreServedMeanwhile) {
  ServerOptions o = small_limits();
  o.idle_timeout = 2s;  // longer than the 100 requests below take
  Server server(o);
  const double alone_us = median_request_us(server.port());
  RawPeer half(server.port());
  ASSERT_TRUE(half.send_all("GET /api/state HTTP/1.1\r\nHost:"));
  const double beside_us = median_request_us(server.port());
  EXPECT_GT(alone_us, 0);
  EXPECT_GT(beside_us, 0) << "a request was not served beside the half-open one";
  std::cout << "figures: a request alone " << alone_us << " us, beside a half-open one " << beside_us << " us\n";
  EXPECT_TRUE(half.closed_by_server(10s));
  EXPECT_EQ(server.stats().idle_closed, 1u);
  EXPECT_EQ(server.stats().requests, 100u) << "the half request is never answered as a request";
}

// One header line every 20 ms, for ever: the idle timeout bounds the whole request, not the gap
// between bytes, so the server hangs up after it.
TEST(WebServerHostile, AClientTricklingHeadersForEverIsCutAtTheIdleTimeout) {
  Server server(small_limits());
  RawPeer loris(server.port());
  ASSERT_TRUE(loris.send_all("GET /api/state HTTP/1.1\r\n"));
  bool cut = false;
  std::size_t lines = 0;
  for (const auto until = std::chrono::steady_clock::now() + 10s; !cut && std::chrono::steady_clock::now() < until;) {
    loris.send_some("X-Slow: " + std::to_string(lines++) + "\r\n");
    cut = loris.broken() || loris.closed_by_server(20ms);
  }
  EXPECT_TRUE(cut) << lines << " header lines were taken";
  EXPECT_TRUE(wait_until([&] { return server.stats().idle_closed == 1; }));
  EXPECT_TRUE(served(server.port()));
}

TEST(WebServerHostile, OversizedAndBinaryGarbageAreAnswered400ClosedAndCounted) {
  Server server(small_limits());
  {
    RawPeer big(server.port());
    big.send_all("GET /" + std::string(1 << 20, 'a'), 2000ms);  // 1 MB request line: cut off by the server
    EXPECT_TRUE(big.closed_by_server());
  }
  {
    std::mt19937 rng(7);
    std::string noise(4096, '\0');
    for (auto& c : noise) c = static_cast<char>(rng() & 0xff);
    noise[0] = '\x01';  // not a letter: no method can start here
    RawPeer garbage(server.port());
    garbage.send_all(noise, 2000ms);
    EXPECT_TRUE(garbage.closed_by_server());
  }
  EXPECT_TRUE(wait_until([&] { return server.stats().bad_requests == 2; })) << server.stats().bad_requests;
  EXPECT_TRUE(served(server.port()));
}

TEST(WebServerHostile, AWebSocketClientSendingBrokenFramesIsClosedAndCounted) {
  Server server(small_limits());
  hostile::WarningLog log;
  RawPeer ws(server.port());
  ASSERT_TRUE(ws.send_all(testing::kWebSocketUpgrade));
  ASSERT_NE(ws.read_until("\r\n\r\n").find("101 Switching Protocols"), std::string::npos);
  // An unmasked frame with a reserved opcode: two protocol errors in one (a client must mask).
  ASSERT_TRUE(ws.send_all(std::string("\x83\x05hello", 7)));
  EXPECT_TRUE(ws.closed_by_server());  // the server's close frame (1002, protocol error), then its end
  ws.close();                          // and the peer goes without the closing handshake
  EXPECT_TRUE(wait_until([&] { return server.stats().ws_bad_frames == 1 && server.stats().ws_open == 0; }));
  EXPECT_EQ(log.count("broke the protocol (The WebSocket frame contained an illegal opcode)"), 1u);
  EXPECT_TRUE(served(server.port()));
}

// 400 clients that connect and leave at once, stop half-way or finish their request, twenty at a
// time: afterwards the server holds no descriptor and no memory for any of them.
TEST(WebServerHostile, ManyClientsComingAndGoingLeaveNoDescriptorsOrMemoryBehind) {
  Server server(small_limits());
  ASSERT_TRUE(served(server.port()));  // the first request's buffers count in the baseline
  const auto fds = hostile::open_descriptors();
  const long rss = hostile::resident_kb();
  for (int round = 0; round < 20; ++round) {
    std::vector<std::unique_ptr<RawPeer>> peers;
    for (int i = 0; i < 20; ++i) {
      auto p = std::make_unique<RawPeer>(server.port());
      if (i % 3 == 1) p->send_some("GET /api/sources HTTP/1.1\r\nHo");
      if (i % 3 == 2) p->send_some(kGoodRequest);
      peers.push_back(std::move(p));
    }
  }
  EXPECT_TRUE(wait_until([&] { return server.stats().connections == 0; }, 10s)) << server.stats().connections;
  EXPECT_TRUE(wait_until([&] { return hostile::open_descriptors() <= fds; })) << hostile::open_descriptors() << " vs " << fds;
  const long grown_kb = hostile::resident_kb() - rss;
  std::cout << "figures: resident memory " << grown_kb << " kB more after 400 clients\n";
  EXPECT_LT(grown_kb, 16 * 1024);
  EXPECT_TRUE(served(server.port()));
}

}  // namespace
}  // namespace axon::web::hostile_test

// The CAN@net gateway emulator facing hostile peers (docs/reliability.md, "Hostile peers"): a
// flood of connections (the newest wins, as on the device), a client that never reads, oversized
// lines and garbage, connections closed half-way through a line. What must hold: the queue for
// the client stays bounded, replaced connections leave nothing behind, a client that comes back
// is served, every rejection is counted and logged once, nothing crashes.
#include "axon/can/cannet_server.hpp"

#include "can/bus_bench.hpp"
#include "support/hostile_peer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace axon::can::cannet_hostile {
namespace {

using namespace axon::can;

using hostile::RawPeer;
using hostile::WarningLog;
using hostile::wait_until;
using namespace std::chrono_literals;

// An emulator with one channel, can0.
struct Bench : test::BusBench {
  std::unique_ptr<CanNetGatewayEmulator> emulator;

  explicit Bench(CanNetEmulatorOptions o = {}) {
    o.port = 0;
    loop.call([&] {
      emulator = std::make_unique<CanNetGatewayEmulator>(loop.executor(), *registry, std::vector<std::string>{"can0"}, o);
      emulator->start().value();
    });
  }
  ~Bench() {
    loop.call([&] {
      emulator->stop();
      emulator.reset();
    });
  }
  [[nodiscard]] std::uint16_t port() { return loop.call([&] { return emulator->local_endpoint().port; }); }
  CanNetEmulatorStats stats() { return loop.call([&] { return emulator->stats(); }); }
  bool has_client() { return loop.call([&] { return emulator->has_client(); }); }
};

std::string loop_host(Bench& b) { return b.loop.call([&] { return b.emulator->local_endpoint().host; }); }

// Asks one command and returns the answer line (empty when none came within 2 s).
std::string ask(RawPeer& p, const std::string& command) {
  if (!p.send_all(command + "\n")) return {};
  std::string got = p.read_until("\n", 2000ms);
  return got.substr(0, got.find('\n'));
}

double status_round_trip_us(RawPeer& p) {
  const auto t0 = std::chrono::steady_clock::now();
  if (ask(p, "CAN 1 STATUS").rfind("R CAN 1", 0) != 0) return -1;
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
}

double median_round_trip_us(RawPeer& p) {
  return hostile::median_of(50, [&] { return status_round_trip_us(p); });
}

TEST(CanNetHostile, AFloodOfConnectionsLeavesNothingBehindAndTheHostCanComeBack) {
  WarningLog log;
  Bench b;
  const std::size_t fds_before = hostile::open_descriptors();
  auto host = std::make_unique<RawPeer>(b.port());
  const double alone_us = median_round_trip_us(*host);
  ASSERT_GT(alone_us, 0);
  const long rss_before = hostile::resident_kb();
  std::vector<std::unique_ptr<RawPeer>> peers;
  for (int i = 0; i < 200; ++i) peers.push_back(std::make_unique<RawPeer>(b.port()));
  ASSERT_TRUE(wait_until([&] { return b.stats().connections == 201; })) << b.stats().connections;
  const long rss_flood = hostile::resident_kb();
  // The device's rule: the newest connection wins; every older one is closed at once.
  EXPECT_TRUE(host->closed_by_server());
  for (std::size_t i = 0; i + 1 < peers.size(); ++i) EXPECT_TRUE(peers[i]->closed_by_server(1000ms)) << i;
  EXPECT_EQ(b.stats().replaced, 200u);
  // One warning: the host's takeover. The silent connections replacing each other: debug lines.
  EXPECT_EQ(log.count("takes over"), 1u);
  peers.clear();
  host = std::make_unique<RawPeer>(b.port());
  const double back_us = median_round_trip_us(*host);
  EXPECT_GT(back_us, 0);
  host.reset();
  EXPECT_TRUE(wait_until([&] { return !b.has_client() && hostile::open_descriptors() == fds_before; }))
      << hostile::open_descriptors() << " descriptors, " << fds_before << " before";
  std::cout << "figure: CAN@net status round trip " << alone_us << " us before, " << back_us
            << " us after 200 connections; process RSS +" << rss_flood - rss_before << " kB during the flood\n";
}

TEST(CanNetHostile, AClientThatSendsCommandsButNeverReadsHasABoundedQueue) {
  CanNetEmulatorOptions o;
  o.max_output_bytes = 64 * 1024;
  Bench b(o);
  RawPeer flooder(b.port(), 4096);
  std::string burst;
  for (int i = 0; i < 1024; ++i) burst += "CAN 1 STATUS\n";
  // Until 8 MB went out, or the server has stopped reading it (nothing taken for 200 ms).
  std::size_t sent = 0;
  auto last_taken = std::chrono::steady_clock::now();
  while (sent < (8u << 20) && !flooder.broken() && std::chrono::steady_clock::now() - last_taken < 200ms) {
    const std::size_t n = flooder.send_some(burst);
    sent += n;
    if (n > 0) last_taken = std::chrono::steady_clock::now();
    else std::this_thread::sleep_for(1ms);
  }
  const auto s = b.stats();
  EXPECT_LE(s.output_high_water, o.max_output_bytes + cannet::kMaxLineLength + 1) << "sent " << sent;
  std::cout << "figure: CAN@net flooder sent " << sent << " bytes of commands without reading; largest queue "
            << s.output_high_water << " bytes\n";
  // It is served again once it reads.
  std::string all = flooder.read_until("never", 300ms);
  EXPECT_NE(all.find("R CAN 1"), std::string::npos);
}

TEST(CanNetHostile, AClientThatNeverReadsBusFramesHasABoundedQueueAndTheDropsAreCounted) {
  CanNetEmulatorOptions o;
  o.max_output_bytes = 64 * 1024;
  Bench b(o);
  RawPeer sleeper(b.port(), 4096);
  EXPECT_EQ(ask(sleeper, "CAN 1 INIT STD 1000"), "R ok");
  EXPECT_EQ(ask(sleeper, "CAN 1 START"), "R ok");
  // More than the kernel's socket buffers hold (a few MB), so that the emulator's queue fills.
  b.flood(200000);
  EXPECT_TRUE(wait_until([&] { return b.stats().output_drops > 0; }));
  const auto s = b.stats();
  EXPECT_LE(s.output_high_water, o.max_output_bytes + cannet::kMaxLineLength + 1);
  EXPECT_LE(s.frames_to_client + s.output_drops, 200000u);
}

TEST(CanNetHostile, OversizedLinesAndGarbageAreAnsweredCountedAndLoggedOncePerClient) {
  WarningLog log;
  Bench b;
  RawPeer p(b.port());
  // A megabyte without a newline: one R ERR for the whole line, then the next command is answered.
  ASSERT_TRUE(p.send_all(std::string(1 << 20, 'A')));
  ASSERT_TRUE(p.send_all("\nCAN 1 STATUS\n"));
  const std::string first = p.read_until("R CAN 1");
  EXPECT_EQ(first.rfind("R ERR 3 line longer than", 0), 0u) << first.substr(0, 80);
  EXPECT_NE(first.find("\nR CAN 1"), std::string::npos);
  EXPECT_EQ(b.stats().error_replies, 1u);
  // Binary garbage cut into short lines: one R ERR per line, one warning for the client.
  std::string noise;
  for (int i = 0; i < 2000; ++i) noise += std::string("\x01\xFE\x7F garbage \xC3", 13) + "\n";
  ASSERT_TRUE(p.send_all(noise + "DEV IDENTIFY\n"));
  const std::string rest = p.read_until("CAN@net NT 420", 5000ms);
  EXPECT_NE(rest.find("CAN@net NT 420"), std::string::npos);
  EXPECT_EQ(b.stats().error_replies, 2001u);
  EXPECT_EQ(log.count("R ERR"), 1u);
}

TEST(CanNetHostile, ConnectionsClosedHalfWayThroughALineLeaveNothingBehind) {
  Bench b;
  EXPECT_EQ(loop_host(b), "127.0.0.1");  // loopback unless an address is given
  const std::size_t fds_before = hostile::open_descriptors();
  for (int i = 0; i < 50; ++i) {
    RawPeer p(b.port());
    p.send_all("CAN 1 INIT ST");
  }
  EXPECT_TRUE(wait_until([&] { return b.stats().connections == 50 && !b.has_client(); }));
  EXPECT_TRUE(wait_until([&] { return hostile::open_descriptors() == fds_before; })) << hostile::open_descriptors();
  EXPECT_EQ(b.stats().commands, 0u);
  RawPeer host(b.port());
  EXPECT_EQ(ask(host, "DEV IDENTIFY"), "R CAN@net NT 420");
}

}  // namespace
}  // namespace axon::can::cannet_hostile

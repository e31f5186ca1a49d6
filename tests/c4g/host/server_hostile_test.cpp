// The c4g server facing hostile senders (docs/reliability.md, "Hostile peers"): two hundred
// sockets sending garbage, oversized and look-alike datagrams in the middle of a session. What
// must hold: every packet of the controller is answered, no stranger gets an answer or changes
// anything, each foreign datagram is counted (the cycle thread does not log; the counts are in
// the summary), memory does not grow.
#include "axon/c4g/apps/sensor_feed.hpp"
#include "axon/c4g/host/server.hpp"
#include "axon/c4g/protocol/mode.hpp"

#include "c4g/host/controller_peer.hpp"
#include "support/hostile_peer.hpp"

#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <iostream>
#include <memory>
#include <vector>

namespace axon::c4g::host::hostile_test {
namespace {

using protocol::code;
using protocol::Mode;
using c4g::test::cyclic;
using c4g::test::make_init;
using c4g::test::Peer;
using namespace std::chrono_literals;

struct Holding : Controller {
  void on_cycle(const CycleContext&, ReplyBuilder&) override {}
};

// A server on loopback in a session with its controller (initialization packet answered).
struct Session {
  Holding law;
  std::unique_ptr<Server> server;
  Peer controller;
  Session() : server(Server::start(law, options()).value()), controller(server->local_address()) {
    controller.send(make_init());
    EXPECT_EQ(controller.answer().count, 2u);
  }
  static ServerOptions options() {
    ServerOptions o;
    o.listen = net::Endpoint{"127.0.0.1", 0};
    o.controller_budget = 1s;
    return o;
  }
};

// Round trip of one cyclic packet in microseconds; -1 when unanswered or answered wrongly.
double round_trip_us(Peer& controller, std::int32_t num) {
  const auto t0 = std::chrono::steady_clock::now();
  if (controller.ask(cyclic(num, code(Mode::mode0))).num != num) return -1;
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
}

TEST(ServerHostile, TwoHundredStrangersFloodingGarbageNeitherDelayNorDisturbTheSession) {
  Session session;
  auto& server = session.server;
  auto& controller = session.controller;
  int num = 0;
  const double alone_us = hostile::median_of(200, [&] { return round_trip_us(controller, num++); });

  std::vector<std::unique_ptr<Peer>> strangers;
  for (int i = 0; i < 200; ++i) strangers.push_back(std::make_unique<Peer>(server->local_address()));
  const std::vector<std::byte> tiny(17, std::byte{0x5A});
  const std::vector<std::byte> huge(65000, std::byte{0xA5});                                 // far beyond any packet
  const std::vector<std::byte> cyclic_sized(protocol::packet_size(2), std::byte{0xFF});      // NaN everywhere
  const std::vector<std::byte> init_sized(protocol::kInitPacketSize, std::byte{0x00});
  const long rss_before = hostile::resident_kb();
  std::vector<double> crowded;
  std::size_t sent = 0;
  for (int cycle = 0; cycle < 500; ++cycle) {
    // Four strangers a cycle, in turn; then the controller's packet, which must be answered.
    for (const auto* bytes : {&tiny, &huge, &cyclic_sized, &init_sized}) {
      strangers[sent % strangers.size()]->send_raw(*bytes);
      ++sent;
    }
    crowded.push_back(round_trip_us(controller, 1000 + cycle));
  }
  const long rss_after = hostile::resident_kb();
  EXPECT_EQ(std::count(crowded.begin(), crowded.end(), -1.0), 0) << "controller packets unanswered or wrong";
  EXPECT_EQ(server->counters().foreign.load(), sent);
  EXPECT_EQ(server->counters().protocol_errors.load(), 0u);
  EXPECT_FALSE(server->safety().faulted());
  EXPECT_EQ(server->peer(), controller.local());
  for (auto& s : strangers) EXPECT_EQ(s->answer(0ms).count, 0u);
  EXPECT_NE(server->summary().find(fmt::format("foreign datagrams ignored {}", sent)), std::string::npos);
  std::sort(crowded.begin(), crowded.end());
  std::cout << "figure: c4g cyclic round trip median " << alone_us << " us alone, "
            << crowded[crowded.size() / 2] << " us with 4 foreign datagrams (one of 65000 bytes) before each; RSS "
            << rss_after - rss_before << " kB growth\n";
}

TEST(ServerHostile, OversizedAndGarbageDatagramsFromTheControllerItselfAreCountedNotFatal) {
  Session session;
  auto& server = session.server;
  auto& controller = session.controller;
  // From the session's own address: a truncated giant and a runt, neither of a known size.
  controller.send_raw(std::vector<std::byte>(65000, std::byte{0x11}));
  controller.send_raw(std::vector<std::byte>(3, std::byte{0x22}));
  EXPECT_EQ(controller.answer(100ms).count, 0u);  // datagrams of no known size get no answer
  EXPECT_EQ(server->counters().unanswered.load(), 2u);
  EXPECT_EQ(server->counters().protocol_errors.load(), 2u);
  // The session goes on.
  EXPECT_EQ(controller.ask(cyclic(5, code(Mode::mode0))).num, 5);
  EXPECT_EQ(server->peer(), controller.local());
}

TEST(ServerHostile, TheCorrectionFeedCountsStrangersAndBadDatagramsAndKeepsTheLastGoodValues) {
  Peer sensor(net::SocketAddress{0x7f000001, 9});
  apps::SensorFeedOptions fo;
  fo.axes = 2;
  fo.source = net::Endpoint{"127.0.0.1", sensor.local().port};
  auto feed = apps::SensorFeed::open(fo).value();
  const net::SocketAddress to{0x7f000001, feed->port()};
  sensor.aim_at(to);
  auto text = [](std::string_view t) { return std::vector<std::byte>(reinterpret_cast<const std::byte*>(t.data()),
                                                                     reinterpret_cast<const std::byte*>(t.data()) + t.size()); };
  sensor.send_raw(text("0.001 -0.002\n"));
  ASSERT_TRUE(hostile::wait_until([&] { return feed->accepted() == 1; }));
  std::vector<std::unique_ptr<Peer>> strangers;
  for (int i = 0; i < 200; ++i) {
    strangers.push_back(std::make_unique<Peer>(to));
    strangers.back()->send_raw(text("0.5 0.5"));
  }
  // (Waiting here keeps the kernel from dropping any: 200 datagrams fill much of a socket's buffer.)
  ASSERT_TRUE(hostile::wait_until([&] { return feed->foreign() == 200; })) << feed->foreign();
  sensor.send_raw(std::vector<std::byte>(65000, std::byte{'7'}));  // oversized
  sensor.send_raw(text("nan 1"));
  sensor.send_raw(text("\x01\x02 garbage"));
  EXPECT_TRUE(hostile::wait_until([&] { return feed->foreign() == 200 && feed->rejected() == 3; }))
      << feed->foreign() << " foreign, " << feed->rejected() << " rejected";
  apps::SensorFeed::Reading r;
  ASSERT_TRUE(feed->latest(r));
  EXPECT_DOUBLE_EQ(r.values[0], 0.001);
  EXPECT_DOUBLE_EQ(r.values[1], -0.002);
  EXPECT_EQ(feed->accepted(), 1u);
}

}  // namespace
}  // namespace axon::c4g::host::hostile_test

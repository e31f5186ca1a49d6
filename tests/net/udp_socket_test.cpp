#include "axon/net/udp_socket.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cstring>
#include <thread>

using namespace axon;
using namespace axon::net;
using namespace std::chrono_literals;

namespace {

const SocketAddress kLoopbackAny{0x7f000001, 0};

std::span<const std::byte> bytes(const char* text) {
  return {reinterpret_cast<const std::byte*>(text), std::strlen(text)};
}

std::string text(std::span<const std::byte> b, std::size_t n) { return {reinterpret_cast<const char*>(b.data()), n}; }

UdpSocket open_loopback(UdpOptions o = {}) { return UdpSocket::open(kLoopbackAny, o).value(); }

}  // namespace

TEST(UdpSocket, BindsEphemeralPortAndReportsIt) {
  auto s = open_loopback();
  EXPECT_NE(s.local_port(), 0);
  EXPECT_EQ(s.local_address().ip, 0x7f000001u);
  EXPECT_EQ(s.local_address().to_string(), fmt::format("127.0.0.1:{}", s.local_port()));
}

TEST(UdpSocket, BoundToAnyAddressReportsTheDestinationOfEachDatagram) {
  auto server = UdpSocket::open(SocketAddress{0, 0}).value();
  EXPECT_EQ(server.local_address().ip, 0u);
  auto client = open_loopback();
  ASSERT_TRUE(client.send_to(bytes("a"), SocketAddress{0x7f000001, server.local_port()}));
  std::array<std::byte, 8> buf{};
  auto d = server.receive(buf, 2s).value();
  EXPECT_EQ(d.to, (SocketAddress{0x7f000001, server.local_port()}));
}

TEST(UdpSocket, OpensFromHostPortText) {
  auto s = UdpSocket::open(Endpoint{"127.0.0.1", 0}).value();
  EXPECT_NE(s.local_port(), 0);
}

TEST(UdpSocket, BindingAPortInUseFails) {
  auto a = open_loopback();
  auto b = UdpSocket::open(a.local_address());
  ASSERT_FALSE(b);
  EXPECT_EQ(b.error(), NetErrc::bind_failed);
}

TEST(UdpSocket, ResolveRejectsUnknownHosts) {
  auto r = resolve_ipv4(Endpoint{"no-such-host.invalid", 1000});
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), NetErrc::resolve_failed);
  EXPECT_EQ(resolve_ipv4(Endpoint{"10.2.12.149", 1000}).value(), (SocketAddress{0x0a020c95, 1000}));
  EXPECT_EQ(resolve_ipv4(Endpoint{"*", 7}).value(), (SocketAddress{0, 7}));
}

TEST(UdpSocket, RoundTripRemembersThePeerAndReplies) {
  auto server = open_loopback();
  auto client = open_loopback();
  EXPECT_FALSE(server.reply(bytes("x")));  // nobody to reply to yet
  ASSERT_TRUE(client.send_to(bytes("ping"), server.local_address()));

  std::array<std::byte, 64> buf{};
  auto d = server.receive(buf, 2s);
  ASSERT_TRUE(d) << d.error().message();
  EXPECT_EQ(text(buf, d.value().size), "ping");
  EXPECT_EQ(d.value().wire_size, 4u);
  EXPECT_FALSE(d.value().truncated());
  EXPECT_EQ(d.value().from, client.local_address());
  EXPECT_EQ(d.value().to, server.local_address());
  ASSERT_TRUE(server.peer());
  EXPECT_EQ(*server.peer(), client.local_address());

  ASSERT_TRUE(server.reply(bytes("pong")));
  auto r = client.receive(buf, 2s);
  ASSERT_TRUE(r);
  EXPECT_EQ(text(buf, r.value().size), "pong");
  EXPECT_EQ(r.value().from, server.local_address());
  EXPECT_EQ(server.counters().received.load(), 1u);
  EXPECT_EQ(server.counters().sent.load(), 1u);
}

TEST(UdpSocket, KernelTimestampIsOnTheWallClock) {
  auto server = open_loopback();
  auto client = open_loopback();
  ASSERT_TRUE(server.kernel_timestamps());
  const auto before = std::chrono::system_clock::now().time_since_epoch();
  ASSERT_TRUE(client.send_to(bytes("t"), server.local_address()));
  std::array<std::byte, 8> buf{};
  auto d = server.receive(buf, 2s).value();
  const auto after = std::chrono::system_clock::now().time_since_epoch();
  EXPECT_TRUE(d.kernel_timestamp);
  // Arrival lies between the send and the return (a behaviour check, not a timing bound).
  EXPECT_GE(d.wall_ns, std::chrono::duration_cast<std::chrono::nanoseconds>(before).count());
  EXPECT_LE(d.wall_ns, std::chrono::duration_cast<std::chrono::nanoseconds>(after).count());
  EXPECT_GE(d.wakeup_latency_ns, 0);
  EXPECT_GT(d.steady_ns, 0);
}

TEST(UdpSocket, WithoutKernelTimestampsTheClockIsUsed) {
  UdpOptions o;
  o.kernel_timestamps = false;
  auto server = open_loopback(o);
  auto client = open_loopback();
  EXPECT_FALSE(server.kernel_timestamps());
  ASSERT_TRUE(client.send_to(bytes("t"), server.local_address()));
  std::array<std::byte, 8> buf{};
  auto d = server.receive(buf, 2s).value();
  EXPECT_FALSE(d.kernel_timestamp);
  EXPECT_GT(d.wall_ns, 0);
  EXPECT_EQ(d.wakeup_latency_ns, 0);
}

TEST(UdpSocket, TimesOutWhenNothingArrives) {
  auto s = open_loopback();
  std::array<std::byte, 8> buf{};
  auto r = s.receive(buf, 5ms);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), NetErrc::timeout);
  auto now = s.receive(buf, 0ns);
  ASSERT_FALSE(now);
  EXPECT_EQ(now.error(), NetErrc::timeout);
  EXPECT_EQ(s.counters().timeouts.load(), 2u);
}

TEST(UdpSocket, BusyPollReceivesAndTimesOut) {
  UdpOptions o;
  o.busy_poll = true;
  auto server = open_loopback(o);
  auto client = open_loopback();
  std::array<std::byte, 8> buf{};
  auto r = server.receive(buf, 2ms);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), NetErrc::timeout);
  ASSERT_TRUE(client.send_to(bytes("busy"), server.local_address()));
  auto d = server.receive(buf, 2s);
  ASSERT_TRUE(d);
  EXPECT_EQ(text(buf, d.value().size), "busy");
}

TEST(UdpSocket, OversizedDatagramIsReportedTruncated) {
  auto server = open_loopback();
  auto client = open_loopback();
  ASSERT_TRUE(client.send_to(bytes("0123456789"), server.local_address()));
  std::array<std::byte, 4> buf{};
  auto d = server.receive(buf, 2s).value();
  EXPECT_TRUE(d.truncated());
  EXPECT_EQ(d.size, 4u);
  EXPECT_EQ(d.wire_size, 10u);
  EXPECT_EQ(text(buf, d.size), "0123");
  EXPECT_EQ(server.counters().truncated.load(), 1u);
}

TEST(UdpSocket, InterruptWakesABlockedReceive) {
  for (bool busy : {false, true}) {
    UdpOptions o;
    o.busy_poll = busy;
    auto s = open_loopback(o);
    std::array<std::byte, 8> buf{};
    Result<Datagram> r = Error(NetErrc::closed);
    std::thread t([&] { r = s.receive(buf, -1ns); });  // would wait for ever
    std::this_thread::sleep_for(10ms);  // let it block (the test passes either way)
    s.interrupt();
    t.join();
    ASSERT_FALSE(r);
    EXPECT_EQ(r.error(), NetErrc::interrupted);
    // Sticky until cleared.
    EXPECT_EQ(s.receive(buf, 0ns).error(), NetErrc::interrupted);
    s.clear_interrupt();
    EXPECT_EQ(s.receive(buf, 0ns).error(), NetErrc::timeout);
  }
}

TEST(UdpSocket, ClosedSocketRefusesWork) {
  auto s = open_loopback();
  s.close();
  std::array<std::byte, 8> buf{};
  EXPECT_EQ(s.receive(buf, 0ns).error(), NetErrc::closed);
  EXPECT_EQ(s.send_to(bytes("x"), SocketAddress{0x7f000001, 9}).error(), NetErrc::closed);
}

TEST(UdpSocket, MovedSocketKeepsWorking) {
  auto a = open_loopback();
  const auto addr = a.local_address();
  UdpSocket b = std::move(a);
  auto client = open_loopback();
  ASSERT_TRUE(client.send_to(bytes("m"), addr));
  std::array<std::byte, 8> buf{};
  EXPECT_TRUE(b.receive(buf, 2s));
}

#include "axon/c4g/host/cycle_thread.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <pcap/pcap.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <filesystem>

using namespace axon;
using namespace axon::c4g::host;
using namespace std::chrono_literals;
using net::SocketAddress;
using net::UdpSocket;

namespace {

const SocketAddress kLoopback{0x7f000001, 0};

// Answers every packet with its bytes reversed; packets starting with 'q' get no answer.
struct ReverseHandler : CycleHandler {
  std::atomic<int> packets{0};
  std::atomic<int> timeouts_before_first{0};
  std::atomic<int> timeouts_after_first{0};
  std::size_t on_packet(std::span<const std::byte> req, const net::Datagram&, std::span<std::byte> reply) noexcept override {
    ++packets;
    if (!req.empty() && req[0] == std::byte{'q'}) return 0;
    std::reverse_copy(req.begin(), req.end(), reply.begin());
    return req.size();
  }
  void on_timeout(bool before_first) noexcept override { ++(before_first ? timeouts_before_first : timeouts_after_first); }
};

std::span<const std::byte> bytes(const std::string& s) { return {reinterpret_cast<const std::byte*>(s.data()), s.size()}; }

std::string ask(UdpSocket& client, const SocketAddress& server, const std::string& text) {
  EXPECT_TRUE(client.send_to(bytes(text), server));
  std::array<std::byte, 256> buf{};
  auto r = client.receive(buf, 2s);
  if (!r) return "<" + r.error().message() + ">";
  return {reinterpret_cast<const char*>(buf.data()), r.value().size};
}

}  // namespace

TEST(CycleThread, AnswersEveryPacketAndTimesEachCycle) {
  ReverseHandler h;
  CycleThread cycle(UdpSocket::open(kLoopback).value(), h);
  const auto report = cycle.start();
  EXPECT_TRUE(report.steps.empty());  // nothing real-time was asked for
  EXPECT_TRUE(cycle.running());
  auto client = UdpSocket::open(kLoopback).value();
  for (int i = 0; i < 20; ++i) {
    std::string text = fmt::format("abc{}", i);
    std::string reversed(text.rbegin(), text.rend());
    EXPECT_EQ(ask(client, cycle.local_address(), text), reversed);
  }
  cycle.stop();
  EXPECT_FALSE(cycle.running());
  EXPECT_EQ(h.packets.load(), 20);
  EXPECT_EQ(cycle.counters().cycles.load(), 20u);
  EXPECT_EQ(cycle.counters().replies.load(), 20u);
  EXPECT_EQ(cycle.timing().cycles(), 20u);
  EXPECT_EQ(cycle.timing().inter_steps(), 19u);
  EXPECT_GE(cycle.timing().worst_cycle_time_ns(), 0);
  EXPECT_EQ(cycle.reply_latency().count(), 20u);
  EXPECT_EQ(cycle.wakeup_latency().count(), 20u);  // kernel stamps on by default
  EXPECT_NE(cycle.summary().find("Packets 20 answered 20"), std::string::npos) << cycle.summary();
}

TEST(CycleThread, HandlerMayLeaveAPacketUnanswered) {
  ReverseHandler h;
  CycleThread cycle(UdpSocket::open(kLoopback).value(), h);
  cycle.start();
  auto client = UdpSocket::open(kLoopback).value();
  ASSERT_TRUE(client.send_to(bytes("quiet"), cycle.local_address()));
  EXPECT_EQ(ask(client, cycle.local_address(), "xy"), "yx");  // the first got no answer
  cycle.stop();
  EXPECT_EQ(cycle.counters().silent.load(), 1u);
  EXPECT_EQ(cycle.counters().replies.load(), 1u);
}

TEST(CycleThread, TimeoutsAreReportedBeforeAndAfterTheFirstPacket) {
  ReverseHandler h;
  CycleOptions o;
  o.first_packet_timeout = 5ms;
  o.cycle_timeout = 5ms;
  CycleThread cycle(UdpSocket::open(kLoopback).value(), h, o);
  cycle.start();
  while (h.timeouts_before_first.load() == 0) std::this_thread::sleep_for(1ms);
  auto client = UdpSocket::open(kLoopback).value();
  EXPECT_EQ(ask(client, cycle.local_address(), "ab"), "ba");
  while (h.timeouts_after_first.load() == 0) std::this_thread::sleep_for(1ms);
  cycle.stop();
  EXPECT_GE(cycle.counters().timeouts.load(), 2u);
}

TEST(CycleThread, StopReturnsWhileWaitingForAFirstPacketThatNeverComes) {
  for (bool busy : {false, true}) {
    ReverseHandler h;
    CycleOptions o;
    o.first_packet_timeout = std::chrono::hours(1);
    net::UdpOptions uo;
    uo.busy_poll = busy;
    CycleThread cycle(UdpSocket::open(kLoopback, uo).value(), h, o);
    cycle.start();
    cycle.stop();  // would hang for an hour if the wait were not interrupted
    EXPECT_FALSE(cycle.running());
    // And it can start again.
    cycle.start();
    auto client = UdpSocket::open(kLoopback).value();
    EXPECT_EQ(ask(client, cycle.local_address(), "12"), "21");
    cycle.stop();
  }
}

TEST(CycleThread, RealtimeRefusalsAreReportedNotFatal) {
  ReverseHandler h;
  CycleOptions o;
  o.realtime.cpus = {100000};  // no such CPU: always refused
  CycleThread cycle(UdpSocket::open(kLoopback).value(), h, o);
  const auto report = cycle.start();
  ASSERT_EQ(report.steps.size(), 1u);
  EXPECT_FALSE(report.steps[0].granted);
  auto client = UdpSocket::open(kLoopback).value();
  EXPECT_EQ(ask(client, cycle.local_address(), "ok"), "ko");
  cycle.stop();
}

TEST(CycleThread, RecordsBothDirectionsIntoPcap) {
  const auto path = (std::filesystem::temp_directory_path() / fmt::format("axon_cycle_{}.pcap", ::getpid())).string();
  auto rec = PcapRecorder::open(path).value();
  ReverseHandler h;
  CycleThread cycle(UdpSocket::open(kLoopback).value(), h, {}, rec.get());
  cycle.start();
  auto client = UdpSocket::open(kLoopback).value();
  for (int i = 0; i < 3; ++i) ask(client, cycle.local_address(), "hello");
  cycle.stop();
  rec->close();
  EXPECT_EQ(rec->written(), 6u);

  char err[PCAP_ERRBUF_SIZE];
  pcap_t* p = pcap_open_offline_with_tstamp_precision(path.c_str(), PCAP_TSTAMP_PRECISION_NANO, err);
  ASSERT_NE(p, nullptr) << err;
  pcap_pkthdr* hdr;
  const u_char* data;
  int n = 0;
  std::int64_t last = 0;
  while (pcap_next_ex(p, &hdr, &data) == 1) {
    const u_char* udp = data + 34;
    const int sport = (udp[0] << 8) | udp[1], dport = (udp[2] << 8) | udp[3];
    const bool request = n % 2 == 0;
    EXPECT_EQ(sport, request ? client.local_port() : cycle.local_address().port);
    EXPECT_EQ(dport, request ? cycle.local_address().port : client.local_port());
    const std::string payload(reinterpret_cast<const char*>(udp + 8), 5);
    EXPECT_EQ(payload, request ? "hello" : "olleh");
    const std::int64_t ns = static_cast<std::int64_t>(hdr->ts.tv_sec) * 1'000'000'000 + hdr->ts.tv_usec;
    EXPECT_GE(ns, last);  // answers are stamped after their requests
    last = ns;
    ++n;
  }
  pcap_close(p);
  EXPECT_EQ(n, 6);
  std::filesystem::remove(path);
}

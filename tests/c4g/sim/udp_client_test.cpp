// The simulator over real UDP on loopback against a minimal echo PC (a thread in the test).
#include "axon/c4g/protocol/packet.hpp"
#include "axon/c4g/sim/client_runner.hpp"
#include "pc_responder.hpp"

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <atomic>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <thread>
#include <unistd.h>

namespace axon::c4g::sim::test {
namespace {

// Binds 127.0.0.1:0 and answers every cyclic or init datagram with its number, modes echoed, while
// `answer` is set.
class EchoPc {
 public:
  EchoPc() {
    fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    socklen_t len = sizeof a;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
    thread_ = std::thread([this] { loop(); });
  }
  ~EchoPc() {
    stop_ = true;
    thread_.join();
    ::close(fd_);
  }
  std::uint16_t port() const { return port_; }
  std::atomic<bool> answer{true};
  std::atomic<int> inits{0};
  std::atomic<int> packets{0};

 private:
  void loop() {
    std::array<std::byte, 2048> buf{};
    while (!stop_) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 20) <= 0) continue;
      sockaddr_in from{};
      socklen_t len = sizeof from;
      const ssize_t n = ::recvfrom(fd_, buf.data(), buf.size(), 0, reinterpret_cast<sockaddr*>(&from), &len);
      if (n <= 0) continue;
      ++packets;
      P::Packet r;
      const std::span<const std::byte> d(buf.data(), static_cast<std::size_t>(n));
      if (P::classify(d.size()) == P::DatagramKind::init) {
        ++inits;
        auto init = P::decode_init(d);
        if (!init) continue;
        r.num = init.value().protocol_number;
        r.count = static_cast<std::size_t>(init.value().open_axes);
      } else {
        P::Packet req;
        if (!P::decode_packet(d, req).ok()) continue;
        r.num = req.num;
        r.count = req.count;
        for (std::size_t i = 0; i < r.count; ++i) r.axes[i].mode = req.axes[i].mode;
      }
      if (!answer) continue;
      std::array<std::byte, P::kMaxPacketSize> out{};
      if (!P::encode_packet(r, out).ok()) continue;
      ::sendto(fd_, out.data(), P::packet_size(r.count), 0, reinterpret_cast<sockaddr*>(&from), len);
    }
  }
  int fd_ = -1;
  std::uint16_t port_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

TEST(C4gSimUdp, RunsAScenarioAgainstAnEchoPcAndMeasuresRoundTrips) {
  EchoPc pc;
  auto c = make_controller("steps:\n  - drive_on\n  - delay: 0.1\n");
  auto udp = UdpClient::open(net::Endpoint{"127.0.0.1", pc.port()});
  ASSERT_TRUE(udp.has_value());
  std::vector<Event> events;
  RunOptions o;
  o.reply_deadline = std::chrono::milliseconds(50);  // generous: the test machine is shared
  o.duration_s = 30;
  o.on_event = [&](const Event& e) { events.push_back(e); };
  const auto report = run_client(c, udp.value(), o);
  EXPECT_TRUE(c.scenario_done()) << c.scenario_error();
  EXPECT_FALSE(c.communication_error());
  EXPECT_FALSE(report.stopped);
  EXPECT_EQ(pc.inits.load(), 1);
  EXPECT_EQ(report.rtt.count(), c.stats().replies_ok + c.stats().init_answers);
  EXPECT_GT(report.rtt.count(), 50u);
  EXPECT_GT(report.rtt.max(), 0);
  EXPECT_LE(report.rtt.percentile(50), report.rtt.percentile(99));
  bool drives_on_event = false;
  for (const auto& e : events) drives_on_event |= e.name == event::kDrivesOn;
  EXPECT_TRUE(drives_on_event);
}

TEST(C4gSimUdp, ASilentPcEndsInTheCommunicationError) {
  EchoPc pc;
  auto c = make_controller("steps:\n  - run\n");
  auto udp = UdpClient::open(net::Endpoint{"127.0.0.1", pc.port()});
  ASSERT_TRUE(udp.has_value());
  RunOptions o;
  o.reply_deadline = std::chrono::milliseconds(50);
  o.duration_s = 60;
  std::atomic<bool> silenced{false};
  o.on_event = [&](const Event& e) {
    if (e.name == event::kInitSent) {
      pc.answer = false;
      silenced = true;
    }
  };
  run_client(c, udp.value(), o);
  EXPECT_TRUE(silenced.load());
  EXPECT_TRUE(c.communication_error());
  EXPECT_EQ(c.stats().max_consecutive_misses, 10u);
}

}  // namespace
}  // namespace axon::c4g::sim::test

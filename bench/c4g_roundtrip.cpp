// c4g reply round trip on loopback: the Server (decode, safe reply, controller, safety, encode,
// timing) against a minimal echo server on the same kind of socket, measured in the same run.
// Prints `BENCH c4g_roundtrip ... ratio=` (server p50 / echo p50).
#include "axon/c4g/host/server.hpp"
#include "axon/net/udp_echo.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <vector>

using namespace axon;
using namespace axon::c4g;

namespace {

constexpr int kRounds = 5000;
constexpr std::size_t kAxes = 6;

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Sends kRounds six-axis packets one at a time and returns the round-trip times.
std::vector<std::int64_t> drive(const net::SocketAddress& server) {
  auto client = net::UdpSocket::open(net::SocketAddress{0x7f000001, 0}).value();
  protocol::Packet p;
  p.count = kAxes;
  std::array<std::byte, protocol::kMaxPacketSize> tx{}, rx{};
  std::vector<std::int64_t> rtt;
  rtt.reserve(kRounds);
  for (int i = 0; i < kRounds; ++i) {
    p.num = i & 0x7FFF;
    (void)protocol::encode_packet(p, tx);
    const auto t0 = now_ns();
    if (!client.send_to({tx.data(), protocol::packet_size(kAxes)}, server)) break;
    if (!client.receive(rx, std::chrono::seconds(1))) break;
    rtt.push_back(now_ns() - t0);
  }
  std::sort(rtt.begin(), rtt.end());
  return rtt;
}

std::int64_t pct(const std::vector<std::int64_t>& v, double p) {
  if (v.empty()) return 0;
  return v[std::min(v.size() - 1, static_cast<std::size_t>(p / 100.0 * static_cast<double>(v.size())))];
}

struct Hold : host::Controller {
  void on_cycle(const host::CycleContext&, host::ReplyBuilder&) override {}
};

}  // namespace

int main() {
  // Baseline: a plain blocking echo loop on the same kind of socket.
  auto echo = net::UdpEchoServer::start().value();
  const auto base = drive(echo->address());
  echo->stop();

  Hold hold;
  host::ServerOptions o;
  o.listen = net::Endpoint{"127.0.0.1", 0};
  auto server = host::Server::start(hold, o).value();
  const auto srv = drive(server->local_address());
  std::printf("%s", server->cycle().summary().c_str());
  server->stop();

  const double b50 = static_cast<double>(pct(base, 50)) * 1e-3, s50 = static_cast<double>(pct(srv, 50)) * 1e-3;
  std::printf("echo   round trip us: p50 %.1f p99 %.1f max %.1f (n %zu)\n", b50, static_cast<double>(pct(base, 99)) * 1e-3,
              static_cast<double>(base.empty() ? 0 : base.back()) * 1e-3, base.size());
  std::printf("server round trip us: p50 %.1f p99 %.1f max %.1f (n %zu)\n", s50, static_cast<double>(pct(srv, 99)) * 1e-3,
              static_cast<double>(srv.empty() ? 0 : srv.back()) * 1e-3, srv.size());
  std::printf("BENCH c4g_roundtrip rounds=%d axes=%zu echo_p50_us=%.1f server_p50_us=%.1f echo_p99_us=%.1f server_p99_us=%.1f ratio=%.2f\n",
              kRounds, kAxes, b50, s50, static_cast<double>(pct(base, 99)) * 1e-3, static_cast<double>(pct(srv, 99)) * 1e-3,
              b50 > 0 ? s50 / b50 : 0.0);
  return 0;
}

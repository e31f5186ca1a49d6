// c4g latency at 1 kHz with six axes: the Server running the `pid` application in mode 1 (the
// heaviest built-in law: transforms, six PI loops, safety checks) against a minimal C UDP echo
// server, both driven in the same run by one paced controller-side client that alternates between
// them every tick (so both see the same machine load).
//
// Figures: server processing time (packet received -> reply sent, the server's own TimingStats)
// and the echo server's (recvfrom returned -> sendto returned), p50/p99/p99.9/max; the client's
// round trip to each; missed deadlines (above 500 us, the manual's T_CYCLE1) for both. Ratios are
// server / echo. `--seconds N` (default 5; 60 for the full run).
// Last line: `BENCH c4g_latency ... ratio=` (round-trip p50 ratio).
#include "c4g/apps/pid.hpp"
#include "c4g/host/server.hpp"
#include "c4g/protocol/init_packet.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

using namespace axon;
using namespace axon::c4g;

namespace {

constexpr std::size_t kAxes = 6;
constexpr std::int64_t kPeriodNs = 1'000'000;
constexpr std::int64_t kDeadlineNs = 500'000;

std::int64_t mono_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

struct Stats {
  std::vector<std::int64_t> v;
  void sort() { std::sort(v.begin(), v.end()); }
  [[nodiscard]] double us(double p) const {
    if (v.empty()) return 0;
    const auto i = std::min(v.size() - 1, static_cast<std::size_t>(p / 100.0 * static_cast<double>(v.size())));
    return static_cast<double>(v[i]) * 1e-3;
  }
  [[nodiscard]] double max_us() const { return v.empty() ? 0 : static_cast<double>(v.back()) * 1e-3; }
  [[nodiscard]] std::size_t over(std::int64_t ns) const {
    return static_cast<std::size_t>(v.end() - std::upper_bound(v.begin(), v.end(), ns));
  }
};

// The baseline: the plainest possible UDP echo, in C style.
struct EchoServer {
  int fd = -1;
  std::uint16_t port = 0;
  std::atomic<bool> stop{false};
  Stats processing;
  std::thread thread;

  EchoServer() {
    fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in sa{};
    sa.sin_family = AF_INET;
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof sa;
    if (::bind(fd, reinterpret_cast<sockaddr*>(&sa), sizeof sa) != 0) std::abort();
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&sa), &len);
    port = ntohs(sa.sin_port);
    processing.v.reserve(1 << 20);
    thread = std::thread([this] {
      char buf[2048];
      while (!stop.load(std::memory_order_relaxed)) {
        pollfd pf{fd, POLLIN, 0};
        if (::poll(&pf, 1, 50) <= 0) continue;
        sockaddr_in from{};
        socklen_t fl = sizeof from;
        const auto n = ::recvfrom(fd, buf, sizeof buf, 0, reinterpret_cast<sockaddr*>(&from), &fl);
        const std::int64_t t1 = mono_ns();
        if (n > 0) ::sendto(fd, buf, static_cast<std::size_t>(n), 0, reinterpret_cast<sockaddr*>(&from), fl);
        processing.v.push_back(mono_ns() - t1);
      }
    });
  }
  void finish() {
    stop = true;
    if (thread.joinable()) thread.join();
  }
  ~EchoServer() {
    finish();
    ::close(fd);
  }
};

// The controller side: one socket, one request in flight at a time.
struct Client {
  net::UdpSocket socket = net::UdpSocket::open(net::SocketAddress{0x7f000001, 0}).value();
  std::array<std::byte, 2048> rx{};
  // Sends and waits for the answer; the round trip in ns, or -1 when none came within 20 ms.
  std::int64_t exchange(std::span<const std::byte> tx, const net::SocketAddress& to) {
    const std::int64_t t0 = mono_ns();
    if (!socket.send_to(tx, to)) return -1;
    auto r = socket.receive(rx, std::chrono::milliseconds(20));
    if (!r) return -1;
    return mono_ns() - t0;
  }
};

protocol::InitPacket bench_init() {
  protocol::InitPacket p;
  p.protocol_number = 1;
  p.open_axes = kAxes;
  p.period_ms = 1;
  p.open_axis_list[0] = {1, 2, 3, 4, 5, 6, 0, 0, 0, 0};
  p.calibration[0] = {0.14f, 0.17f, 0.22f, 0.41f, 0.04f, 0.36f, 0, 0, 0, 0};
  p.current_limit[0] = {24.5f, 24.5f, 24.5f, 9.5f, 9.5f, 9.5f, 0, 0, 0, 0};
  p.transmission_ratio[0] = {-181.6f, 159.3f, 162.5f, 72.6f, 78.75f, -50.0f, 0, 0, 0, 0};
  p.influence[0] = {0, 0, 0, -0.02f, 0.0204f, 0.02f, 0, 0, 0, 0};
  p.following_error[0] = {7.5f, 7.5f, 7.5f, 7.5f, 7.5f, 0, 0, 0, 0, 0};
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 5;
  for (int i = 1; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--seconds") seconds = std::atof(argv[i + 1]);
  const auto rounds = static_cast<std::size_t>(seconds * 1e9 / static_cast<double>(kPeriodNs));

  EchoServer echo;
  const net::SocketAddress echo_addr{0x7f000001, echo.port};

  apps::PidApp app(apps::PidOptions{});
  host::ServerOptions o;
  o.listen = net::Endpoint{"127.0.0.1", 0};
  o.safety.check_following_error = true;
  o.max_late_cycles = 0;  // a loaded machine must not end the run
  auto server = host::Server::start(app, o).value();
  const auto server_addr = server->local_address();

  Client client;
  std::array<std::byte, protocol::kInitPacketSize> init_bytes{};
  if (!protocol::encode_init(bench_init(), init_bytes)) return 1;
  if (client.exchange(init_bytes, server_addr) < 0) {
    std::fprintf(stderr, "c4g_latency: no answer to the initialization packet\n");
    return 1;
  }

  protocol::Packet p;
  p.count = kAxes;
  p.infpar = protocol::kDrivesOn;
  for (std::size_t i = 0; i < kAxes; ++i) {
    p.axes[i].mode = 1;  // the PC closes the loops: the pid app holds the position
    p.axes[i].d1 = p.axes[i].d3 = 0.5f * static_cast<float>(i);
    p.axes[i].ext1 = 0.1f;
  }
  std::array<std::byte, protocol::kMaxPacketSize> tx{};
  Stats rtt_server, rtt_echo;
  rtt_server.v.reserve(rounds);
  rtt_echo.v.reserve(rounds);
  std::size_t lost_server = 0, lost_echo = 0;
  std::int64_t next = mono_ns() + kPeriodNs;
  for (std::size_t k = 0; k < rounds; ++k) {
    const timespec wake{static_cast<time_t>(next / 1'000'000'000), static_cast<long>(next % 1'000'000'000)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &wake, nullptr);
    next += kPeriodNs;
    p.num = static_cast<std::int32_t>(k & 0x7FFF);
    // Small motion so the loops have work to do.
    for (std::size_t i = 0; i < kAxes; ++i) p.axes[i].d3 = 0.5f * static_cast<float>(i) + 1e-4f * static_cast<float>(k % 100);
    (void)protocol::encode_packet(p, tx);
    const std::span<const std::byte> bytes(tx.data(), protocol::packet_size(kAxes));
    for (int side = 0; side < 2; ++side) {
      const bool to_server = (side == 0) == (k % 2 == 0);
      const std::int64_t r = client.exchange(bytes, to_server ? server_addr : echo_addr);
      if (r < 0) ++(to_server ? lost_server : lost_echo);
      else (to_server ? rtt_server : rtt_echo).v.push_back(r);
    }
  }
  server->stop();
  echo.finish();

  rtt_server.sort();
  rtt_echo.sort();
  echo.processing.sort();
  const auto& h = server->cycle().timing().cycle_times();
  const double sp50 = static_cast<double>(h.percentile(50)) * 1e-3, sp99 = static_cast<double>(h.percentile(99)) * 1e-3,
               sp999 = static_cast<double>(h.percentile(99.9)) * 1e-3, spmax = static_cast<double>(h.max()) * 1e-3;
  const auto& ep = echo.processing;
  auto ratio = [](double a, double b) { return b > 0 ? a / b : 0.0; };

  std::printf("%s", server->summary().c_str());
  std::printf("c4g_latency: %.0f s at 1 kHz, %zu axes, server app pid (mode 1), deadline %lld us\n", seconds, kAxes,
              static_cast<long long>(kDeadlineNs / 1000));
  std::printf("processing us   server p50 %.1f p99 %.1f p99.9 %.1f max %.1f | echo p50 %.1f p99 %.1f p99.9 %.1f max %.1f\n",
              sp50, sp99, sp999, spmax, ep.us(50), ep.us(99), ep.us(99.9), ep.max_us());
  std::printf("round trip us   server p50 %.1f p99 %.1f p99.9 %.1f max %.1f | echo p50 %.1f p99 %.1f p99.9 %.1f max %.1f\n",
              rtt_server.us(50), rtt_server.us(99), rtt_server.us(99.9), rtt_server.max_us(), rtt_echo.us(50),
              rtt_echo.us(99), rtt_echo.us(99.9), rtt_echo.max_us());
  std::printf("missed (> 500 us): server processing %llu, echo processing %zu; round trips server %zu echo %zu; lost server %zu echo %zu\n",
              static_cast<unsigned long long>(server->cycle().timing().missed_deadlines()), ep.over(kDeadlineNs),
              rtt_server.over(kDeadlineNs), rtt_echo.over(kDeadlineNs), lost_server, lost_echo);
  std::printf(
      "BENCH c4g_latency seconds=%.0f axes=%zu rounds=%zu server_proc_p50_us=%.1f server_proc_p99_us=%.1f "
      "server_proc_p999_us=%.1f server_proc_max_us=%.1f echo_proc_p50_us=%.1f echo_proc_p99_us=%.1f "
      "echo_proc_p999_us=%.1f echo_proc_max_us=%.1f rtt_server_p50_us=%.1f rtt_echo_p50_us=%.1f rtt_server_p99_us=%.1f "
      "rtt_echo_p99_us=%.1f rtt_server_p999_us=%.1f rtt_echo_p999_us=%.1f missed_server=%zu missed_echo=%zu "
      "proc_ratio_p50=%.2f proc_ratio_p99=%.2f rtt_ratio_p99=%.2f rtt_ratio_p999=%.2f ratio=%.2f\n",
      seconds, kAxes, rounds, sp50, sp99, sp999, spmax, ep.us(50), ep.us(99), ep.us(99.9), ep.max_us(), rtt_server.us(50),
      rtt_echo.us(50), rtt_server.us(99), rtt_echo.us(99), rtt_server.us(99.9), rtt_echo.us(99.9),
      rtt_server.over(kDeadlineNs), rtt_echo.over(kDeadlineNs), ratio(sp50, ep.us(50)), ratio(sp99, ep.us(99)),
      ratio(rtt_server.us(99), rtt_echo.us(99)), ratio(rtt_server.us(99.9), rtt_echo.us(99.9)),
      ratio(rtt_server.us(50), rtt_echo.us(50)));
  return 0;
}

// c4g latency at 1 kHz with six axes, measured by the controller simulator: two simulated
// controllers (src/axon/c4g/sim, the paced client loop `axon sim c4g` runs) side by side in one process,
// one against the c4g Server running the `pid` application in mode 1 (the heaviest built-in law:
// transforms, six PI loops, safety checks), the other against a minimal C UDP echo server, so both
// see the same machine load.
//
// Figures: server processing time (packet received -> reply sent, the server's own TimingStats)
// and the echo server's (recvfrom returned -> sendto returned), p50/p99/p99.9/max; the simulators'
// round trips (send -> accepted reply, waited for up to 20 ms so the tail is measured); processing
// times and round trips over 500 us (the manual's T_CYCLE1) and round trips over the 1 ms period, for
// both.
// Ratios are server / echo. `--seconds N` (default 5; 60 for the full run).
// Last line: `BENCH c4g_latency ... ratio=` (round-trip p50 ratio).
#include "axon/c4g/apps/pid.hpp"
#include "axon/c4g/host/server.hpp"
#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/c4g/sim/client_runner.hpp"
#include "axon/c4g/sim/controller.hpp"
#include "axon/c4g/sim/robots.hpp"
#include "axon/c4g/sim/scenario.hpp"
#include "axon/c4g/sim/udp_client.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <array>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <thread>
#include <vector>

using namespace axon;
using namespace axon::c4g;

namespace {

constexpr std::size_t kAxes = 6;
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

// One simulated controller (six-axis robot at 1 ms) playing `yaml` against `port` for `seconds`.
struct SimSide {
  std::optional<sim::Controller> controller;
  sim::RunReport report;
  std::string error;

  void run(std::uint16_t port, const char* yaml, double seconds) {
    auto scenario = sim::Scenario::parse(yaml);
    sim::ControllerOptions co;
    co.period_ms = 1;
    // A benchmark reports stalls instead of ending on them: the manual's communication error (10
    // misses in a row) is off, and replies are waited for up to 20 ms so that the round-trip tail is
    // measured rather than cut at the period.
    co.max_misses = 1 << 30;
    auto c = sim::Controller::create(sim::six_axis_robot(), scenario.value(), co);
    auto udp = sim::UdpClient::open(net::Endpoint{"127.0.0.1", port});
    if (!c || !udp) {
      error = "cannot start the simulator";
      return;
    }
    controller.emplace(std::move(c).value());
    sim::RunOptions ro;
    ro.duration_s = seconds;
    ro.reply_deadline = std::chrono::milliseconds(20);
    report = sim::run_client(*controller, udp.value(), ro);
    if (controller->communication_error()) error = "communication error";
    else if (controller->scenario_failed()) error = controller->scenario_error();
  }
};

}  // namespace

int main(int argc, char** argv) {
  double seconds = 5;
  for (int i = 1; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--seconds") seconds = std::atof(argv[i + 1]);

  EchoServer echo;

  apps::PidOptions pid;  // a 0.5 deg / 1 Hz sine on every joint, so the loops have work to do
  pid.amplitude_rad = {0.5 * 3.14159265358979 / 180.0};
  pid.frequency_hz = {1.0};
  apps::PidApp app(pid);
  host::ServerOptions o;
  o.listen = net::Endpoint{"127.0.0.1", 0};
  o.safety.check_following_error = true;
  o.max_late_cycles = 0;  // a loaded machine must not end the run
  auto server = host::Server::start(app, o).value();

  // The server side holds the robot in mode 1 (the PC closes the loops); the echo side stays in
  // mode 0, where an echoed packet is a valid answer the controller ignores.
  SimSide to_server, to_echo;
  std::thread t([&] {
    to_server.run(server->local_address().port, "steps:\n  - drive_on\n  - go_open: {type: A, mode: 1}\n  - run\n", seconds);
  });
  to_echo.run(echo.port, "steps:\n  - drive_on\n  - run\n", seconds);
  t.join();
  server->stop();
  echo.finish();
  for (const SimSide* s : {&to_server, &to_echo})
    if (!s->error.empty() || !s->controller) {
      std::fprintf(stderr, "c4g_latency: simulator against the %s: %s\n", s == &to_server ? "server" : "echo",
                   s->error.empty() ? "did not start" : s->error.c_str());
      return 1;
    }

  echo.processing.sort();
  const auto& h = server->cycle().timing().cycle_times();
  const double sp50 = static_cast<double>(h.percentile(50)) * 1e-3, sp99 = static_cast<double>(h.percentile(99)) * 1e-3,
               sp999 = static_cast<double>(h.percentile(99.9)) * 1e-3, spmax = static_cast<double>(h.max()) * 1e-3;
  const auto& ep = echo.processing;
  const auto& rs = to_server.report.rtt;
  const auto& re = to_echo.report.rtt;
  auto us = [](const core::LatencyHistogram& r, double p) { return static_cast<double>(r.percentile(p * 100.0)) * 1e-3; };
  auto ull = [](std::uint64_t v) { return static_cast<unsigned long long>(v); };
  auto ratio = [](double a, double b) { return b > 0 ? a / b : 0.0; };

  std::printf("%s", server->summary().c_str());
  std::printf("%s", app.summary().c_str());
  std::printf("c4g_latency: %.0f s at 1 kHz, %zu axes, server app pid (mode 1, 0.5 deg sine), deadline %lld us, round trips measured "
              "by the controller simulator\n",
              seconds, kAxes, static_cast<long long>(kDeadlineNs / 1000));
  std::printf("processing us   server p50 %.1f p99 %.1f p99.9 %.1f max %.1f | echo p50 %.1f p99 %.1f p99.9 %.1f max %.1f\n",
              sp50, sp99, sp999, spmax, ep.us(50), ep.us(99), ep.us(99.9), ep.max_us());
  std::printf("round trip us   server p50 %.1f p99 %.1f p99.9 %.1f max %.1f (n %llu) | echo p50 %.1f p99 %.1f p99.9 %.1f "
              "max %.1f (n %llu)\n",
              us(rs, 0.5), us(rs, 0.99), us(rs, 0.999), static_cast<double>(rs.max()) * 1e-3, ull(rs.count()), us(re, 0.5),
              us(re, 0.99), us(re, 0.999), static_cast<double>(re.max()) * 1e-3, ull(re.count()));
  std::printf("over 500 us: server processing %llu, echo processing %zu; round trips server %llu echo %llu; round trips "
              "over 1 ms server %llu echo %llu; schedule overruns %llu / %llu; pid max following error %.5f turns\n",
              ull(server->cycle().timing().missed_deadlines()), ep.over(kDeadlineNs), ull(rs.count_above(kDeadlineNs)),
              ull(re.count_above(kDeadlineNs)), ull(rs.count_above(1'000'000)), ull(re.count_above(1'000'000)), ull(to_server.report.overruns),
              ull(to_echo.report.overruns), app.max_following_error());
  std::printf(
      "BENCH c4g_latency seconds=%.0f axes=%zu rounds_server=%llu rounds_echo=%llu server_proc_p50_us=%.1f "
      "server_proc_p99_us=%.1f server_proc_p999_us=%.1f server_proc_max_us=%.1f echo_proc_p50_us=%.1f "
      "echo_proc_p99_us=%.1f echo_proc_p999_us=%.1f echo_proc_max_us=%.1f rtt_server_p50_us=%.1f rtt_echo_p50_us=%.1f "
      "rtt_server_p99_us=%.1f rtt_echo_p99_us=%.1f rtt_server_p999_us=%.1f rtt_echo_p999_us=%.1f missed_server=%llu "
      "missed_echo=%llu over_period_server=%llu over_period_echo=%llu proc_ratio_p50=%.2f proc_ratio_p99=%.2f "
      "rtt_ratio_p99=%.2f rtt_ratio_p999=%.2f ratio=%.2f\n",
      seconds, kAxes, ull(rs.count()), ull(re.count()), sp50, sp99, sp999, spmax, ep.us(50), ep.us(99), ep.us(99.9),
      ep.max_us(), us(rs, 0.5), us(re, 0.5), us(rs, 0.99), us(re, 0.99), us(rs, 0.999), us(re, 0.999),
      ull(rs.count_above(kDeadlineNs)), ull(re.count_above(kDeadlineNs)), ull(rs.count_above(1'000'000)),
      ull(re.count_above(1'000'000)),
      ratio(sp50, ep.us(50)), ratio(sp99, ep.us(99)), ratio(us(rs, 0.99), us(re, 0.99)),
      ratio(us(rs, 0.999), us(re, 0.999)), ratio(us(rs, 0.5), us(re, 0.5)));
  return 0;
}

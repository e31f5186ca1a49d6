// `axon demo`, c4g part: the controller simulator runs a robot program (drives on, opens arm 1 in
// mode 4, waits for the PC, closes) against the PC server playing a short joint trajectory, both in
// this process over UDP on loopback; then the reply round trip is set beside a plain UDP echo on
// the same kind of socket, measured in the same run.
#include "axon/c4g/apps/stream.hpp"
#include "axon/c4g/host/server.hpp"
#include "axon/c4g/sim/simulated_controller.hpp"
#include "axon/core/text.hpp"
#include "demo_parts.hpp"
#include "axon/net/udp_echo.hpp"
#include "run.hpp"

#include <fmt/format.h>

#include <array>
#include <numbers>
#include <vector>

namespace axon::app {
namespace {

namespace c4g = axon::c4g;

constexpr std::string_view kProgram = R"(name: demo
steps:
  - drive_on
  - go_open: {type: A, mode: 4, arms: [1]}
  - wait_for_pc: {timeout: 20}
  - exit_open
)";

// Offsets from where the arm stands: out and back on every axis in 0.8 s.
std::shared_ptr<const c4g::apps::Trajectory> demo_trajectory() {
  const double d = std::numbers::pi / 180.0;
  std::vector<std::vector<double>> rows{{0, 0, 0, 0, 0, 0}, {4 * d, -2 * d, 1 * d, 0, 5 * d, 0}, {0, 0, 0, 0, 0, 0}};
  return std::make_shared<const c4g::apps::Trajectory>(need(c4g::apps::Trajectory::from_rows({0, 0.4, 0.8}, rows)));
}

// Round trips of six-axis-sized datagrams to `to`, p50 in us (0 when nothing came back).
double demo_echo_p50_us(const net::SocketAddress& to, int rounds) {
  auto client = need(net::UdpSocket::open(net::SocketAddress{0x7f000001, 0}));
  std::array<std::byte, 12 + 36 * 6> tx{}, rx{};
  std::vector<double> rtt;
  for (int i = 0; i < rounds; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    if (!client.send_to(tx, to) || !client.receive(rx, std::chrono::seconds(1))) continue;
    rtt.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }
  if (rtt.empty()) return 0;
  std::sort(rtt.begin(), rtt.end());
  return rtt[rtt.size() / 2];
}

}  // namespace

int demo_c4g() {
  fmt::print("\naxon demo: c4g, a robot controller's open interface (the PC is the server)\n\n");
  c4g::apps::StreamOptions so;
  so.trajectory = demo_trajectory();
  so.mode = 4;
  so.relative = true;
  c4g::apps::StreamApp app(so);
  c4g::host::ServerOptions options;
  options.listen = net::Endpoint{"127.0.0.1", 0};
  auto server = need(c4g::host::Server::start(app, options));
  fmt::print("1. PC server on {} running `stream` (mode 4: a 0.8 s joint trajectory, relative)\n",
             server->local_address().to_string());

  c4g::sim::SimulatedControllerOptions co;
  co.server = server->local_address().to_string();
  co.scenario_yaml = std::string(kProgram);
  co.duration_s = 30;  // a bound; the program ends long before
  auto controller = c4g::sim::SimulatedController::start(co);
  fmt::print("2. controller simulator: six-axis robot, program: drive on, open mode 4, wait for PC, close\n");
  const auto report = controller.wait();
  server->stop();

  const auto& s = report.stats;
  const bool ok = report.exit_code() == 0 && !app.has_error();
  fmt::print("   program {} after {:.2f} s ({} ms period); modes seen:\n", ok ? "completed" : "FAILED", report.elapsed_s,
             report.period_ms);
  for (const auto& e : report.events)
    if (e.name == c4g::sim::event::kModeChange) fmt::print("     {:.3f} s {}\n", e.time_s, e.text);
  const std::string summary = app.summary();
  for (const auto line : core::split_fields(summary, '\n'))
    if (!line.empty()) fmt::print("   {}\n", line);

  auto echo = need(net::UdpEchoServer::start());
  const double echo_us = demo_echo_p50_us(echo->address(), 2000);
  echo->stop();
  fmt::print("\n3. the exchange, as the controller saw it\n");
  fmt::print("   {:<34} {:>10}\n", "cycles", s.ticks);
  fmt::print("   {:<34} {:>10}\n", "replies in time", s.replies_ok);
  fmt::print("   {:<34} {:>10}\n", "missed or late", s.misses);
  fmt::print("   {:<34} {:>10.1f}\n", "round trip p50 [us]", report.rtt_p50_us);
  fmt::print("   {:<34} {:>10.1f}\n", "round trip p99 [us]", report.rtt_p99_us);
  fmt::print("   {:<34} {:>10.1f}\n", "plain UDP echo p50 [us]", echo_us);
  if (echo_us > 0) fmt::print("   {:<34} {:>10.2f}\n", "server / echo (p50)", report.rtt_p50_us / echo_us);
  return ok ? exit_code_value::ok : exit_code_value::failed;
}

}  // namespace axon::app

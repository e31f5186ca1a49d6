// c4g joint trajectory: a mode 4 server that streams a joint trajectory to a C4G controller (arm 1,
// axes 1-3 move 10, -5 and 5 degrees and back over 3 s, relative to where the arm starts), then
// checks that every cycle was answered (no communication error: late replies are counted, not
// failed) and that the robot followed each target within 0.05 motor turns.
//
//   c4g_joint_trajectory                  # an in-process simulated controller plays the program
//   c4g_joint_trajectory 10.2.12.149:1000 # serve a real controller on this address; its program
//                                         # must DRIVE ON, GO OPEN TYPE A in mode 4, WAIT FOR PC
#include <axon/c4g/apps/serve.hpp>
#include <axon/c4g/apps/stream.hpp>
#include <axon/c4g/apps/trajectory.hpp>
#include <axon/c4g/sim/simulated_controller.hpp>
#include <axon/net/endpoint.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>

using namespace axon::c4g;

int main(int argc, char** argv) {
  // The trajectory: a raised-cosine out and back, one row per 10 ms (the app samples it per cycle).
  std::vector<double> times;
  std::vector<std::vector<double>> rows;
  for (int k = 0; k <= 300; ++k) {
    const double t = k * 0.01, s = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * t / 3.0), deg = std::numbers::pi / 180;
    times.push_back(t);
    rows.push_back({10 * deg * s, -5 * deg * s, 5 * deg * s, 0, 0, 0});
  }
  apps::StreamOptions options;
  options.trajectory = std::make_shared<apps::Trajectory>(apps::Trajectory::from_rows(times, rows).value());
  options.mode = 4;
  options.relative = true;
  apps::StreamApp app(options);
  app.record_samples(4096);

  apps::ServeOptions serve;
  serve.server.listen = argc > 1 ? axon::net::parse_endpoint(argv[1], 1000).value() : axon::net::Endpoint{"127.0.0.1", 0};
  serve.until_controller_ends = true;  // answer the program to its end, not only our part of it
  serve.duration_s = 60;               // a bound, should the controller never end
  apps::ServeSession session(app, serve);
  session.start();
  std::printf("serving mode 4 on %s\n", session.local_address().c_str());

  std::optional<sim::SimulatedController> controller;
  if (argc <= 1)
    controller = sim::SimulatedController::start({.server = session.local_address(), .scenario_yaml = R"(steps:
  - drive_on
  - go_open: {type: A, mode: 4, arms: [1]}
  - wait_for_pc: {timeout: 10}
  - delay: 0.2
  - exit_open)"});

  // Following error: the actual position (D3) against the target sent the cycle before (D1).
  double worst = 0;
  protocol::Packet previous{};
  apps::ServeSession::Hooks hooks;
  hooks.on_poll = [&] {
    app.drain_samples([&](const apps::Sample& s) {
      for (std::size_t i = 0; i < 6; ++i)
        if (s.request.axes[i].mode == 4 && previous.axes[i].mode == 4)
          worst = std::max(worst, double(std::fabs(s.request.axes[i].d3 - previous.axes[i].d1)));
      previous = s.reply;
    });
  };
  const auto served = session.run(hooks);
  std::printf("%s", served.text().c_str());

  bool ok = served.finished && served.stats.safety_fault == "none" && worst < 0.05;
  std::printf("trajectory played: %s; worst following error %.4f motor turns (bound 0.05)\n",
              served.finished ? "yes" : "no", worst);
  if (controller) {
    const auto seen = controller->wait();
    const auto& q = seen.joint_degrees[1];
    std::printf("controller: %s, %llu packets sent, %llu answered, %llu late; arm 1 back at %.3f %.3f %.3f deg\n",
                seen.outcome_text.c_str(), static_cast<unsigned long long>(seen.stats.packets_sent),
                static_cast<unsigned long long>(served.stats.packets),
                static_cast<unsigned long long>(seen.stats.misses), q[0], q[1], q[2]);
    ok = ok && seen.exit_code() == 0 && served.stats.packets == seen.stats.packets_sent && std::fabs(q[0]) < 0.05 &&
         std::fabs(q[1]) < 0.05;
  }
  std::printf("%s\n", ok ? "OK" : "FAILED");
  return ok ? 0 : 1;
}

// c4g control law: mode 1, where the PC closes the position and velocity loops of arm 1 and sends
// the motor currents. The law is user code in the real-time callback: hold the position found when
// the mode starts, swing axis 1 by 0.02 motor turns at 1 Hz (faded in and out), a P-P cascade plus
// the controller's dynamic-model current as feed-forward. After 2 s the PC leaves mode 1. It checks
// the following error stayed within 0.01 motor turns, no safety fault, every cycle answered.
//
//   c4g_control_law                    # an in-process simulated controller plays the program
//   c4g_control_law 10.2.12.149:1000   # serve a real controller on this address; its program must
//                                      # DRIVE ON, GO OPEN TYPE A in mode 1, WAIT FOR PC
#include <axon/c4g/apps/law_app.hpp>
#include <axon/c4g/apps/serve.hpp>
#include <axon/c4g/sim/simulated_controller.hpp>
#include <axon/net/endpoint.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>

using namespace axon::c4g;

int main(int argc, char** argv) {
  // Shared with the cycle thread: written there, read here once the run ended.
  std::array<double, 6> hold{}, last{};
  std::atomic<double> worst{0};

  // The law runs once per controller packet: no allocation, no locks, no I/O in here.
  auto law = [&](const apps::LawCycle& c, host::ReplyBuilder& reply) {
    double w = worst.load(std::memory_order_relaxed);
    for (std::size_t j = 0; j < c.arm.count && j < 6; ++j) {
      const auto& axis = c.ctx.request.axes[c.arm.first + j];  // D3 position [turns], D4 per cycle, EXT1 [A]
      if (c.first) hold[j] = last[j] = axis.d3;
      const double target = hold[j] + (j == 0 ? c.envelope * 0.02 * std::sin(2 * std::numbers::pi * c.t) : 0.0);
      const double v_target = (target - last[j]) / c.arm.period_s, v = axis.d4 / c.arm.period_s;
      const double current = 0.5 * (v_target + 20.0 * (target - axis.d3) - v) + axis.ext1;
      auto& r = reply.axis(c.arm.first + j);
      r.d1 = static_cast<float>(target);
      r.d2 = static_cast<float>(target - last[j]);
      r.d5 = static_cast<float>(current);
      last[j] = target;
      w = std::max(w, std::fabs(target - axis.d3));
    }
    worst.store(w, std::memory_order_relaxed);
  };
  apps::LawApp app({.arm = 1, .mode = 1, .open_time_s = 2.0, .ramp_s = 0.3}, law, "swing");

  apps::ServeOptions serve;
  serve.server.listen = argc > 1 ? axon::net::parse_endpoint(argv[1], 1000).value() : axon::net::Endpoint{"127.0.0.1", 0};
  serve.until_controller_ends = true;  // answer the program to its end, not only our part of it
  serve.duration_s = 60;               // a bound, should the controller never end
  apps::ServeSession session(app, serve);
  session.start();
  std::printf("serving mode 1 on %s\n", session.local_address().c_str());

  std::optional<sim::SimulatedController> controller;
  if (argc <= 1)
    controller = sim::SimulatedController::start({.server = session.local_address(), .scenario_yaml = R"(steps:
  - drive_on
  - go_open: {type: A, mode: 1, arms: [1]}
  - wait_for_pc: {timeout: 10}
  - delay: 0.2
  - exit_open)"});

  const auto served = session.run();
  std::printf("%s", served.text().c_str());
  bool ok = served.finished && served.stats.safety_fault == "none" && worst.load() < 0.01;
  std::printf("law ran %.2f s; worst following error %.5f motor turns (bound 0.01)\n", app.elapsed_s(), worst.load());
  if (controller) {
    const auto seen = controller->wait();
    bool moved = false;  // the controller's check that the robot kept still while control switched
    for (const auto& e : seen.events) moved = moved || e.name == sim::event::kSoftSwitchMotion;
    std::printf("controller: %s, %llu packets sent, %llu answered, %llu late, robot still while switching: %s\n",
                seen.outcome_text.c_str(), static_cast<unsigned long long>(seen.stats.packets_sent),
                static_cast<unsigned long long>(served.stats.packets),
                static_cast<unsigned long long>(seen.stats.misses), moved ? "no" : "yes");
    ok = ok && seen.exit_code() == 0 && served.stats.packets == seen.stats.packets_sent && !moved;
  }
  std::printf("%s\n", ok ? "OK" : "FAILED");
  return ok ? 0 : 1;
}

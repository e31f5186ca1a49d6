// The blocking faces together in one process over real UDP on loopback: a ServeSession (server +
// application) on the test thread and a SimulatedController playing a robot program on its own.
#include "axon/c4g/apps/law_app.hpp"
#include "axon/c4g/apps/serve.hpp"
#include "axon/c4g/apps/stream.hpp"
#include "axon/c4g/apps/trajectory.hpp"
#include "axon/c4g/protocol/mode.hpp"
#include "axon/c4g/sim/simulated_controller.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>

namespace axon::c4g::test {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

apps::ServeOptions loopback() {
  apps::ServeOptions o;
  o.server.listen = net::Endpoint{"127.0.0.1", 0};
  o.server.max_late_cycles = 0;  // a loaded test machine must not trip the lateness check
  o.server.verify_reply_fields = true;  // no reply may carry data in a field its mode does not use
  o.stop_timeout_s = 2;
  o.until_controller_ends = true;  // answer the program's last cycles too
  return o;
}

sim::SimulatedControllerOptions program(const apps::ServeSession& session, std::string yaml) {
  sim::SimulatedControllerOptions o;
  o.server = session.local_address();
  o.scenario_yaml = std::move(yaml);
  o.duration_s = 20;  // a bound on a broken run
  return o;
}

// The program that opens `mode` on arm 1, waits for the PC and ends the exchange.
std::string open_mode_program(int mode) {
  return "steps:\n  - drive_on\n  - go_open: {type: A, mode: " + std::to_string(mode) +
         ", arms: [1]}\n  - wait_for_pc: {timeout: 10}\n  - delay: 0.2\n  - exit_open\n";
}

struct Served {
  apps::ServeReport served;
  sim::SimulatedControllerReport seen;
};

// Serves `app` to a simulated controller playing `yaml` until both ended; every packet the
// controller sent was answered (though not necessarily in time on a loaded machine: no timing).
Served serve_program(apps::App& app, std::string yaml) {
  apps::ServeSession session(app, loopback());
  session.start();
  auto controller = sim::SimulatedController::start(program(session, std::move(yaml)));
  Served r{session.run(), controller.wait()};
  EXPECT_EQ(r.seen.outcome, sim::SimulatedControllerReport::Outcome::completed) << r.seen.outcome_text;
  EXPECT_EQ(r.seen.exit_code(), 0);
  EXPECT_EQ(r.served.stats.packets, r.seen.stats.packets_sent);
  EXPECT_TRUE(r.served.finished) << r.served.text();
  EXPECT_EQ(r.served.stats.safety_fault, "none");
  return r;
}

TEST(SimulatedController, PlaysAMode4TrajectoryAgainstAServeSession) {
  apps::StreamOptions so;
  so.trajectory = std::make_shared<apps::Trajectory>(
      apps::Trajectory::from_rows({0.0, 0.5}, {{0, 0, 0, 0, 0, 0}, {3 * kDeg, -2 * kDeg, 0, 0, 0, 0}}).value());
  so.relative = true;
  apps::StreamApp app(so);
  const auto [served, seen] = serve_program(app, open_mode_program(4));
  EXPECT_EQ(served.reason, "controller ended the exchange (504)");
  EXPECT_EQ(served.exit_code(), 0);
  EXPECT_GE(served.stats.cyclic_packets, 250u);  // 0.5 s at 2 ms, plus the way in and out
  ASSERT_EQ(seen.joint_degrees[1].size(), 6u);
  // The relative trajectory moved the arm by its last row from where it started (0).
  EXPECT_NEAR(seen.joint_degrees[1][0], 3.0, 0.05);
  EXPECT_NEAR(seen.joint_degrees[1][1], -2.0, 0.05);
  EXPECT_NE(served.json().find("\"cyclic_packets\""), std::string::npos);
}

TEST(SimulatedController, AStreamPastAStrokeEndEndsTheSessionInASafetyStopWithDriveOff) {
  // The trajectory goes 8 deg on axis 1; its stroke ends are +-5 deg. The server refuses the first
  // command beyond (drive off, 505), the controller reports the PC's drive off, the session ends in
  // a safety stop once the controller has obeyed, and the joint never passed the stroke end.
  apps::StreamOptions so;
  so.trajectory = std::make_shared<apps::Trajectory>(
      apps::Trajectory::from_rows({0.0, 0.5}, {{0, 0, 0, 0, 0, 0}, {8 * kDeg, 0, 0, 0, 0, 0}}).value());
  so.relative = true;
  apps::StreamApp app(so);
  auto options = loopback();
  options.until_controller_ends = false;
  ASSERT_TRUE(host::parse_stroke_end("1=-5:5", 1, options.server.safety));
  apps::ServeSession session(app, options);
  session.start();
  auto controller = sim::SimulatedController::start(program(session, open_mode_program(4)));
  const auto served = session.run();
  const auto seen = controller.stop();
  EXPECT_EQ(served.reason, "safety stop: commanded position beyond a stroke end") << served.text();
  EXPECT_EQ(served.exit_code(), 4);
  EXPECT_FALSE(served.finished);
  const bool drive_off = std::any_of(seen.events.begin(), seen.events.end(),
                                     [](const sim::Event& e) { return e.name == sim::event::kDriveOffFromPc; });
  EXPECT_TRUE(drive_off);
  ASSERT_EQ(seen.joint_degrees[1].size(), 6u);
  // No command beyond 5 deg went out; the axis follows the last one within a few thousandths. A
  // reply the controller missed (late on a loaded machine, seen once under ASan: 5.032 deg) lets the
  // drives run one more cycle on the last velocity, 16 deg/s x 2 ms = 0.032 deg: what the PC did not
  // answer in time it cannot stop, so each miss widens the bound by one cycle of travel.
  const double coast = 0.032 * static_cast<double>(seen.stats.misses);
  EXPECT_LT(seen.joint_degrees[1][0], 5.01 + coast) << seen.stats.misses << " replies missed";
  EXPECT_GT(seen.joint_degrees[1][0], 4.0);  // it did move up to the stroke end
}

TEST(SimulatedController, StopEndsAProgramThatRunsForeverAndReportsIt) {
  apps::StreamOptions so;
  so.trajectory = std::make_shared<apps::Trajectory>(apps::Trajectory::from_rows({0.0, 0.1}, {{0, 0, 0, 0, 0, 0}, {0, 0, 0, 0, 0, 0}}).value());
  apps::StreamApp app(so);
  apps::ServeSession session(app, loopback());
  session.start();
  auto controller = sim::SimulatedController::start(program(session, "steps:\n  - run\n"));
  EXPECT_FALSE(controller.wait_for(std::chrono::milliseconds(300)));
  EXPECT_TRUE(controller.running());
  const auto seen = controller.stop();
  EXPECT_FALSE(controller.running());
  EXPECT_TRUE(seen.stopped);
  EXPECT_EQ(seen.outcome, sim::SimulatedControllerReport::Outcome::completed);  // `run` ends by a stop
  EXPECT_GT(seen.stats.cyclic_sent, 0u);
  session.stop();
  const auto served = session.run();
  EXPECT_EQ(served.reason, "stopped");
  EXPECT_FALSE(served.finished);
}

TEST(SimulatedController, BadProgramsAndAddressesThrowAxonExceptions) {
  sim::SimulatedControllerOptions o;
  o.scenario_yaml = "steps:\n  - fly\n";
  EXPECT_THROW(sim::SimulatedController::start(o), Exception);
  o.scenario_yaml.clear();
  o.robot = "no-such-robot";
  EXPECT_THROW(sim::SimulatedController::start(o), Exception);
  o.robot = "six-axis";
  o.server = "not an address";
  EXPECT_THROW(sim::SimulatedController::start(o), Exception);
}

// A mode-1 control law written as user code (a LawApp): the PC closes the loops of arm 1 and holds
// it where it was, then leaves; the controller saw every cycle answered and no following error.
TEST(SimulatedController, ALawAppClosesTheLoopsInMode1) {
  std::atomic<double> worst{0};
  std::array<double, protocol::kAxesPerArm> hold{};
  apps::LawOptions lo;
  lo.mode = 1;
  lo.open_time_s = 0.3;
  apps::LawApp app(lo, [&](const apps::LawCycle& c, host::ReplyBuilder& reply) {
    double w = worst.load(std::memory_order_relaxed);
    for (std::size_t j = 0; j < c.arm.count; ++j) {
      const auto& q = c.ctx.request.axes[c.arm.first + j];
      if (c.first) hold[j] = q.d3;
      const double v = q.d4 / c.arm.period_s;
      auto& r = reply.axis(c.arm.first + j);
      r.d1 = static_cast<float>(hold[j]);
      r.d2 = 0;
      r.d5 = static_cast<float>(0.5 * (20.0 * (hold[j] - q.d3) - v) + q.ext1);
      w = std::max(w, std::fabs(hold[j] - q.d3));
    }
    worst.store(w, std::memory_order_relaxed);
  });
  const auto [served, seen] = serve_program(app, open_mode_program(1));
  EXPECT_LT(worst.load(), 0.01);  // motor turns
  for (const auto& e : seen.events) EXPECT_NE(e.name, sim::event::kSoftSwitchMotion) << e.text;
}

}  // namespace
}  // namespace axon::c4g::test

// Soft control switching with the pid application (modes 1 and 2):
//   - the reducer's factor the PC sees follows eta entering and rho leaving (SwitchTracker);
//   - the velocity loop's integrator holds while the factor is 0 and advances at the factor's share
//     of its rate (anti-windup against the reduced output);
//   - the first packet of mode 1 already carries the mode's data (drive-on chapter);
//   - on the simulated six-axis robot, tick by tick, switching into and out of modes 1 and 2 keeps
//     every axis within kStillBound motor turns of where the switch started and every reference
//     current within kCurrentBound, with the reducer in the controller (default) or in the PC.
#include "axon/c4g/apps/pid.hpp"
#include "axon/c4g/host/safety.hpp"
#include "axon/c4g/host/switch_tracker.hpp"
#include "axon/c4g/protocol/mode.hpp"
#include "axon/c4g/sim/controller.hpp"
#include "axon/c4g/sim/robots.hpp"
#include "harness.hpp"
#include "sim_loop.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace axon::c4g::apps::test {
namespace {

namespace P = protocol;
using P::code;
using P::Mode;
using P::SwitchInterval;

constexpr double kStillBound = 0.001;  // [motor turns] excursion during T1..T3 (watchdog: 0.02)
constexpr double kCurrentBound = 0.1;  // [A] reference current during T1..T3 (limits 9.5 / 24.5 A)

TEST(PidSoftSwitch, TheReducerFactorFollowsEtaInAndRhoOut) {
  host::SwitchTracker tracker(P::SwitchTimes{0.01, 0.02, 0.01});  // 5 + 10 + 5 packets at 2 ms
  P::Packet p;
  p.count = 2;
  auto feed = [&](std::int32_t mode) {
    p.axes[0].mode = p.axes[1].mode = mode;
    tracker.update(p, 0.002);
    return tracker.axis(1);
  };
  EXPECT_EQ(feed(0).interval, SwitchInterval::none);
  EXPECT_EQ(tracker.pc_gain(1), 0.0);
  for (int k = 0; k < 20; ++k) {
    const auto s = feed(2);
    const double chi = k < 5 ? 0.0 : (k < 15 ? (k - 5) / 10.0 : 1.0);
    EXPECT_NEAR(s.chi, chi, 1e-9) << k;
    EXPECT_NEAR(tracker.pc_gain(1), chi, 1e-9) << k;  // eta
    EXPECT_EQ(s.direction, P::SwitchDirection::to_pc);
  }
  EXPECT_EQ(feed(2).interval, SwitchInterval::done);
  EXPECT_EQ(tracker.pc_gain(1), 1.0);
  for (int k = 0; k < 20; ++k) {
    const auto s = feed(12);
    const double chi = k < 5 ? 0.0 : (k < 15 ? (k - 5) / 10.0 : 1.0);
    EXPECT_NEAR(tracker.pc_gain(1), 1.0 - chi, 1e-9) << k;  // rho
    EXPECT_EQ(s.direction, P::SwitchDirection::to_drive);
  }
  EXPECT_EQ(feed(0).pc_gain(), 0.0);
}

TEST(PidSoftSwitch, AntiWindupHoldsTheIntegratorWhileTheOutputIsReduced) {
  const PidGains g{20.0, 0.5, 10.0};
  AxisPid held, half, full;
  held.reset(0.3);
  half.reset(0.3);
  full.reset(0.3);
  for (int k = 0; k < 100; ++k) {  // a constant velocity error of 1 turn/s (target ahead of the axis)
    held.update(g, 0, 1, 0, 0, 0, 10, 0.002, 0.0);
    half.update(g, 0, 1, 0, 0, 0, 10, 0.002, 0.5);
    full.update(g, 0, 1, 0, 0, 0, 10, 0.002, 1.0);
  }
  EXPECT_EQ(held.integral(), 0.3);                             // held exactly
  EXPECT_NEAR(full.integral(), 0.3 + 0.5 * 10 * 1 * 0.2, 1e-9);  // kv ki e t
  EXPECT_NEAR(half.integral() - 0.3, 0.5 * (full.integral() - 0.3), 1e-9);
  // Saturation still stops it (the conditional integration), whatever the factor.
  AxisPid sat;
  for (int k = 0; k < 1000; ++k) sat.update(g, 0, 100, 0, 0, 0, 1.0, 0.002, 1.0);
  EXPECT_TRUE(sat.saturated());
  EXPECT_LE(std::fabs(sat.integral()), 1.0);
}

TEST(PidSoftSwitch, TheFirstPacketOfMode1CarriesTheCurrentAndTheTargets) {
  for (const bool in_pc : {false, true}) {
    PidOptions o;
    o.reduce_in_pc = in_pc;
    PidApp app(o);
    Harness h;
    host::SwitchTracker tracker;
    h.tracker = &tracker;
    h.start(app);
    h.place_at_link({0, 0, 0, 0, 0, 0});
    h.set_modes(code(Mode::mode0));
    h.run(app);
    h.set_modes(code(Mode::mode1));
    for (std::size_t i = 0; i < 6; ++i) h.req.axes[i].ext1 = 0.7f;  // the dynamic model's current
    const auto& rep = h.run(app);
    EXPECT_EQ(tracker.axis(0).interval, SwitchInterval::pre);
    EXPECT_FLOAT_EQ(rep.axes[0].d1, h.req.axes[0].d3);  // hold where the robot stands
    EXPECT_FLOAT_EQ(rep.axes[0].d2, 0.0f);
    // The controller applies the reducer (eta = 0 in T1): the PC sends its full current. With the
    // reducer in the PC, the PC sends eta x current = 0.
    EXPECT_FLOAT_EQ(rep.axes[0].d5, in_pc ? 0.0f : 0.7f) << "reduce_in_pc " << in_pc;
    EXPECT_EQ(app.reducer_factor(), 0.0);
  }
}

struct Figures {
  double still = 0;    // max |D3 - D3 at the switch's start| during T1..T3 [turns]
  double current = 0;  // max |reference current| (the controller's D5) during T1..T3 [A]
  double pc_current = 0;  // max |PC's D5| during T1..T3 [A]
  int switch_packets = 0;
  bool scenario_done = false;
  bool app_finished = false;
  std::string errors;
};

Figures run_switching(PidOptions o, bool controller_reduces, std::string_view yaml, double max_s) {
  Figures f;
  sim::RobotConfig robot = sim::six_axis_robot();
  robot.scs.reduce_pc_current = controller_reduces;
  auto c = sim::Controller::create(robot, sim::Scenario::parse(yaml).value()).value();
  PidApp app(std::move(o));
  host::SwitchTracker tracker(robot.scs.times);
  SimLoop loop(c, app, tracker);
  std::array<double, P::kMaxAxes> anchor{};
  loop.run(max_s, [&] {
    const auto& req = loop.req;
    for (std::size_t i = 0; i < req.count; ++i) {
      const auto& s = tracker.axis(i);
      if (s.elapsed_s == 0 && s.interval == SwitchInterval::pre) anchor[i] = req.axes[i].d3;
      if (!s.robot_must_be_still()) continue;
      f.switch_packets += i == 0;
      f.still = std::max(f.still, std::fabs(req.axes[i].d3 - anchor[i]));
      f.current = std::max(f.current, static_cast<double>(std::fabs(req.axes[i].d5)));
      f.pc_current = std::max(f.pc_current, static_cast<double>(std::fabs(loop.rep.axes[i].d5)));
    }
  });
  f.errors = loop.errors;
  f.scenario_done = c.scenario_done();
  f.app_finished = app.finished();
  f.errors += app.error();
  EXPECT_EQ(loop.safety.reason(), host::FaultReason::none);
  return f;
}

constexpr std::string_view kMode1 = "steps:\n  - drive_on\n  - go_open: {type: A, mode: 1}\n  - wait_for_pc: {timeout: 5}\n  - exit_open\n";
constexpr std::string_view kMode2 = R"(steps:
  - drive_on
  - move: {arm: 1, deg: [5, -5, 5, 5, 5, 5], duration: 0.5}
  - delay: 0.2
  - go_open: {type: B, mode: 2}
  - delay: 0.25
  - move: {arm: 1, deg: [2, -2, 2, 2, 2, 2], duration: 0.5}
  - delay: 0.2
  - go_open: {type: A, mode: 12}
  - exit_open
)";

TEST(PidSoftSwitch, Mode1InAndOutOnTheSimulatedRobotStaysStill) {
  for (const bool controller_reduces : {true, false}) {
    PidOptions o;
    o.open_time_s = 0.6;
    o.amplitude_rad = {0.5 * 3.14159265358979 / 180};
    o.frequency_hz = {1.0};
    o.reduce_in_pc = !controller_reduces;
    const auto f = run_switching(o, controller_reduces, kMode1, 10);
    EXPECT_TRUE(f.scenario_done) << f.errors;
    EXPECT_TRUE(f.app_finished) << f.errors;
    EXPECT_TRUE(f.errors.empty()) << f.errors;
    EXPECT_EQ(f.switch_packets, 200);  // 100 in, 100 out at 2 ms
    EXPECT_LT(f.still, kStillBound);
    EXPECT_LT(f.current, kCurrentBound);
    std::printf("mode 1 switching (reducer in the %s): max excursion %.6f turns, max current %.4f A, PC %.4f A\n",
                controller_reduces ? "controller" : "PC", f.still, f.current, f.pc_current);
  }
}

TEST(PidSoftSwitch, Mode2InAndOutOnTheSimulatedRobotStaysStill) {
  for (const bool controller_reduces : {true, false}) {
    PidOptions o;
    o.reduce_in_pc = !controller_reduces;
    const auto f = run_switching(o, controller_reduces, kMode2, 10);
    EXPECT_TRUE(f.scenario_done) << f.errors;
    EXPECT_TRUE(f.app_finished) << f.errors;
    EXPECT_TRUE(f.errors.empty()) << f.errors;
    EXPECT_EQ(f.switch_packets, 200);
    EXPECT_LT(f.still, kStillBound);
    EXPECT_LT(f.current, kCurrentBound);
    std::printf("mode 2 switching (reducer in the %s): max excursion %.6f turns, max current %.4f A, PC %.4f A\n",
                controller_reduces ? "controller" : "PC", f.still, f.current, f.pc_current);
  }
}

}  // namespace
}  // namespace axon::c4g::apps::test

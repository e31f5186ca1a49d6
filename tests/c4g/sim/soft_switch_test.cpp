// Soft control switching on the controller's side: the per-axis object against hand-computed
// values, and the simulated controller tick by tick (intervals packet for packet as the PC infers
// them, the still-robot watchdog, a switch refused while the robot moves).
#include "axon/c4g/host/switch_tracker.hpp"
#include "axon/c4g/sim/soft_switch.hpp"
#include "pc_responder.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace axon::c4g::sim::test {
namespace {

using P::SwitchDirection;
using P::SwitchInterval;

SoftSwitchConfig config(bool reduce = true) {
  SoftSwitchConfig c;
  c.times = {0.05, 0.10, 0.05};
  c.reduce_pc_current = reduce;
  return c;
}

TEST(C4gSimSoftSwitch, TheFirstSampleFixesTheOriginAndTheCommandFollowsTheModel) {
  SoftSwitch sw;
  EXPECT_FALSE(sw.active());
  sw.start(SwitchDirection::to_pc, 1.0);
  const auto cfg = config();
  EXPECT_EQ(sw.sample(cfg, 3.0).interval, SwitchInterval::pre);  // t0 = 3.0
  AxisCommand c;
  sw.command(cfg, 3.075, 8.0, 24.5, c);  // chi = 0.25
  EXPECT_NEAR(sw.last().chi, 0.25, 1e-9);
  EXPECT_TRUE(c.loops);
  EXPECT_NEAR(c.loop_limit, 0.75, 1e-9);    // drive limiter rho (Imax - Imin)
  EXPECT_NEAR(c.dynamic_gain, 0.75, 1e-9);  // dynamic model faded by rho
  EXPECT_NEAR(c.current_add, 2.0, 1e-9);    // PC current by eta
  sw.command(cfg, 3.075, 100.0, 24.5, c);   // saturated to Imax before the reducer
  EXPECT_NEAR(c.current_add, 0.25 * 24.5, 1e-9);
  sw.command(config(false), 3.075, 8.0, 24.5, c);  // the PC reduces its own current: applied as sent
  EXPECT_NEAR(c.current_add, 8.0, 1e-9);
  // The watchdog: 0.02 turns from where the switch started.
  EXPECT_FALSE(sw.moved(cfg, 1.019));
  EXPECT_TRUE(sw.moved(cfg, 0.979));
  // After T3 the PC has the axis alone: drive loops off, no dynamic model, full PC current.
  sw.command(cfg, 3.21, 8.0, 24.5, c);
  EXPECT_EQ(sw.last().interval, SwitchInterval::done);
  EXPECT_FALSE(c.loops);
  EXPECT_EQ(c.current_add, 8.0);
  EXPECT_FALSE(sw.moved(cfg, 5.0));  // no longer watched
}

TEST(C4gSimSoftSwitch, TheInverseSwitchHandsTheAxisBackToTheDrive) {
  SoftSwitch sw;
  sw.start(SwitchDirection::to_drive, 0.0);
  const auto cfg = config();
  AxisCommand c;
  sw.command(cfg, 0.0, 4.0, 9.5, c);  // T1: the PC still has it all
  EXPECT_FALSE(c.loops);
  EXPECT_EQ(c.current_add, 4.0);
  sw.command(cfg, 0.125, 4.0, 9.5, c);  // chi = 0.75
  EXPECT_NEAR(c.loop_limit, 0.75, 1e-9);    // limiter at eta
  EXPECT_NEAR(c.dynamic_gain, 0.75, 1e-9);  // dynamic model back by eta
  EXPECT_NEAR(c.current_add, 1.0, 1e-9);    // PC current by rho
  sw.command(cfg, 0.16, 4.0, 9.5, c);       // T3
  EXPECT_EQ(c.current_add, 0.0);
  EXPECT_EQ(c.loop_limit, 1.0);
}

RobotConfig switching_robot() {
  RobotConfig r = quick_robot();
  r.scs.times = {0.05, 0.10, 0.05};
  return r;
}

TEST(C4gSimSoftSwitch, ControllerAndPcAgreeOnTheIntervalsPacketForPacket) {
  auto c = make_controller(
      "steps:\n  - drive_on\n  - go_open: {type: B, mode: 2}\n  - delay: 0.3\n  - go_open: {type: A, mode: 12}\n  - run\n",
      switching_robot());
  PcResponder pc;  // no current from the PC: the robot has no load, the drive holds it until it hands over
  host::SwitchTracker tracker(P::SwitchTimes{0.05, 0.10, 0.05});
  std::array<int, 5> in{}, out{};
  int packets12 = 0;
  for (int k = 0; k < 1000; ++k) {
    const Sent s = pc.tick(c);
    if (!s.cyclic) continue;
    tracker.update(s.packet, c.period_s());
    const auto& pcs = tracker.axis(0);
    const auto& ctl = c.axis_switch(0);
    const std::int32_t m = s.packet.axes[0].mode;
    if (m == 2 || m == 12) {
      ASSERT_EQ(pcs.interval, ctl.interval) << "packet " << k << " mode " << m;
      ASSERT_NEAR(pcs.chi, ctl.chi, 1e-9) << "packet " << k;
      ASSERT_EQ(pcs.direction, ctl.direction);
      (m == 2 ? in : out)[static_cast<int>(pcs.interval)]++;
      packets12 += m == 12;
    }
    if (m == 0 && packets12 > 0) break;
  }
  // 2 ms packets: T1 25, T2 50, T3 25 on the way in; the way out lasts exactly T1 + T2 + T3.
  EXPECT_EQ(in[static_cast<int>(SwitchInterval::pre)], 25);
  EXPECT_EQ(in[static_cast<int>(SwitchInterval::switching)], 50);
  EXPECT_EQ(in[static_cast<int>(SwitchInterval::post)], 25);
  EXPECT_EQ(packets12, 100);
  EXPECT_EQ(out[static_cast<int>(SwitchInterval::pre)], 25);
  EXPECT_EQ(out[static_cast<int>(SwitchInterval::switching)], 50);
  EXPECT_EQ(out[static_cast<int>(SwitchInterval::post)], 25);
  EXPECT_EQ(c.axis_mode(0), 0);
  EXPECT_TRUE(c.drives_on(1));
  EXPECT_EQ(pc.count_events(event::kSoftSwitchMotion), 0u);
}

TEST(C4gSimSoftSwitch, AMoveWithoutTheDelayMovesTheRobotDuringTheSwitch) {
  // The manual: a DELAY of T1 + T2 + T3 must precede the first motion after the switch.
  auto c = make_controller("steps:\n  - drive_on\n  - go_open: {type: B, mode: 2}\n  - move: {deg: [5], duration: 0.3}\n  - run\n",
                           switching_robot());
  PcResponder pc;
  ASSERT_TRUE(pc.run_until(c, [&] { return pc.count_events(event::kSoftSwitchMotion) > 0; }, 400));
  EXPECT_NE(pc.find_event(event::kSoftSwitchMotion)->text.find("arm 1 axis 1: moved"), std::string::npos);
  EXPECT_FALSE(c.drives_on(1));
  pc.run(c, 5);
  EXPECT_TRUE(c.scenario_failed());  // the move was aborted by the drive off
}

TEST(C4gSimSoftSwitch, APcCurrentThatMovesTheRobotDuringTheSwitchIsAFault) {
  auto c = make_controller("steps:\n  - drive_on\n  - go_open: {type: A, mode: 1}\n  - wait_for_pc\n  - run\n", switching_robot());
  PcResponder pc;
  pc.fill = [&](const P::Packet& req, P::Packet& r) {
    if (req.axes[0].mode == 1) r.axes[0].d5 = 3.0f;  // no position loop: pushes until the drive lets go
  };
  ASSERT_TRUE(pc.run_until(c, [&] { return pc.count_events(event::kSoftSwitchMotion) > 0; }, 400));
  const auto* e = pc.find_event(event::kSoftSwitchMotion);
  EXPECT_NE(e->text.find("drive->pc"), std::string::npos) << e->text;
  EXPECT_FALSE(c.drives_on(1));
}

TEST(C4gSimSoftSwitch, TheProgramCannotSwitchWhileTheRobotMoves) {
  // In 0' the PC's echoed targets drive the robot: a PC running ahead moves it; GO OPEN into mode 1
  // is then refused (the state machine allows a switch only from the still state).
  auto c = make_controller("steps:\n  - drive_on\n  - go_open: {type: A, mode: \"0'\"}\n  - delay: 0.1\n  - go_open: {type: A, mode: 1}\n  - run\n",
                           switching_robot());
  PcResponder pc;
  pc.fill = [&](const P::Packet& req, P::Packet& r) {
    for (std::size_t i = 0; i < r.count; ++i) {
      r.axes[i].d1 = req.axes[i].d1;
      r.axes[i].d2 = req.axes[i].d2;
    }
    if (req.axes[0].mode == 10) r.axes[0].d1 = req.axes[0].d3 + 0.05f;  // 2 turns/s at kp 40
  };
  ASSERT_TRUE(pc.run_until(c, [&] { return c.scenario_failed(); }, 400));
  EXPECT_NE(c.scenario_error().find("the robot moves"), std::string::npos) << c.scenario_error();
  EXPECT_EQ(c.axis_mode(0), 10);
  EXPECT_TRUE(c.drives_on(1));
}

}  // namespace
}  // namespace axon::c4g::sim::test

// Drive on, the open modes and the PC's special requests, against the simulated physics.
#include "axon/c4g/sim/controller.hpp"
#include "pc_responder.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace axon::c4g::sim::test {
namespace {

bool all_modes(const Controller& c, std::int32_t m) {
  for (std::size_t i = 0; i < c.axis_count(); ++i)
    if (c.axis_mode(i) != m) return false;
  return true;
}

TEST(C4gSimModes, DriveOnShows501AndThenTheInfparDrivesOnByte) {
  auto c = make_controller("steps:\n  - drive_on\n  - run\n");
  PcResponder pc;
  ASSERT_TRUE(pc.run_until(c, [&] { return c.axis_mode(0) == 501; }));
  pc.tick(c);
  const auto& during = pc.sent.back().packet;
  for (std::size_t i = 0; i < 6; ++i) EXPECT_EQ(during.axes[i].mode, 501);
  EXPECT_EQ(P::arm_byte(during.infpar, 1), 0);
  // The PC's requests are ignored while driving on.
  pc.fill = [](const P::Packet&, P::Packet& r) { r.axes[0].mode = 505; };
  pc.tick(c);
  EXPECT_EQ(c.axis_mode(0), 501);
  EXPECT_GE(c.stats().refused_requests, 1u);
  pc.fill = nullptr;
  ASSERT_TRUE(pc.run_until(c, [&] { return c.drives_on(1); }, 100));
  pc.tick(c);
  const auto& after = pc.sent.back().packet;
  EXPECT_TRUE(P::drives_on(after.infpar, 1));
  EXPECT_EQ(after.axes[0].mode, 0);
  EXPECT_EQ(pc.count_events(event::kDrivesOn), 1u);
}

TEST(C4gSimModes, Mode1CurrentFromThePcAcceleratesTheAxisAsThePhysicsSays) {
  RobotConfig robot = quick_robot();
  robot.scs.times = {0, 0, 0};  // switch to the PC at once
  auto c = make_controller("steps:\n  - drive_on\n  - go_open: {type: A, mode: 1}\n  - wait_for_pc\n  - run\n", robot);
  PcResponder pc;
  const float amps = 2.0f;
  pc.fill = [&](const P::Packet& req, P::Packet& r) {
    if (req.axes[0].mode == 1) r.axes[0].d5 = amps;
    for (std::size_t i = 0; i < r.count; ++i) r.axes[i].d1 = req.axes[i].d3;
  };
  ASSERT_TRUE(pc.run_until(c, [&] { return c.axis_mode(0) == 1; }));
  const double p0 = c.axis_position(0);
  const int n = 100;  // 0.2 s
  pc.run(c, n);
  // J dw/dt = kt I - b w (w in rad/s): w(t) = (kt I / b) (1 - exp(-b t / J)).
  const AxisParams& p = c.axis_model(0).params();
  const double J = c.axis_model(0).inertia(), b = p.viscous_friction, kt = p.torque_constant;
  const double t = n * c.period_s();
  const double w = kt * amps / b * (1 - std::exp(-b * t / J));
  const double turns = kt * amps / b * (t - J / b * (1 - std::exp(-b * t / J))) / (2 * std::numbers::pi);
  EXPECT_NEAR(c.axis_velocity(0), w / (2 * std::numbers::pi), 0.01 * w / (2 * std::numbers::pi));
  EXPECT_NEAR(c.axis_position(0) - p0, turns, 0.01 * turns);
  EXPECT_NEAR(c.axis_current(0), amps, 1e-6);
  // The other axes got no current and did not move; the controller does not check mode 1's error.
  EXPECT_NEAR(c.axis_velocity(1), 0.0, 1e-9);
  EXPECT_TRUE(c.drives_on(1));
}

TEST(C4gSimModes, Mode1CurrentIsSaturatedToTheLimit) {
  RobotConfig robot = quick_robot();
  robot.scs.times = {0, 0, 0};
  auto c = make_controller("steps:\n  - drive_on\n  - go_open: {type: A, mode: 1}\n  - run\n", robot);
  PcResponder pc;
  pc.fill = [&](const P::Packet& req, P::Packet& r) {
    if (req.axes[3].mode == 1) r.axes[3].d5 = 500.0f;
  };
  ASSERT_TRUE(pc.run_until(c, [&] { return c.axis_mode(3) == 1; }));
  pc.run(c, 3);
  EXPECT_NEAR(c.axis_current(3), 9.5, 1e-9);
  EXPECT_GT(c.stats().saturated_cycles, 0u);
}

TEST(C4gSimModes, Mode4TracksThePcTargetsAndLeavesThrough14) {
  auto c = make_controller("steps:\n  - drive_on\n  - go_open: {type: A, mode: 4}\n  - wait_for_pc\n");
  PcResponder pc;
  ASSERT_TRUE(pc.run_until(c, [&] { return c.drives_on(1); }));
  const double start = c.axis_position(1);
  int k = 0;
  bool exit_sent = false;
  const double speed = 0.5;  // motor turns per second on axis 2
  pc.fill = [&](const P::Packet& req, P::Packet& r) {
    for (std::size_t i = 0; i < r.count; ++i) {
      r.axes[i].d1 = req.axes[i].d1;  // hold the others where the controller has them
      if (req.axes[i].mode == 4 || req.axes[i].mode == 14) r.axes[i].d1 = req.axes[i].d3 == 0 ? 0 : req.axes[i].d1;
    }
    if (req.axes[1].mode == 4) {
      ++k;
      const double dt = 0.002;
      r.axes[1].d1 = static_cast<float>(start + speed * std::min(k * dt, 0.4));
      r.axes[1].d2 = static_cast<float>(k * dt < 0.4 ? speed * dt : 0.0);
      if (k == 300) {
        r.infpar = P::request_exit_from_open(0, 1);
        exit_sent = true;
      }
    }
  };
  ASSERT_TRUE(pc.run_until(c, [&] { return c.axis_mode(1) == 4; }));
  pc.run(c, 100);  // 0.2 s into the ramp
  EXPECT_NEAR(c.axis_position(1), start + speed * 0.2, 0.02);
  EXPECT_TRUE(c.drives_on(1));
  bool saw14 = false;
  ASSERT_TRUE(pc.run_until(c, [&] {
    saw14 |= c.axis_mode(1) == 14;
    return c.scenario_done();
  }, 2000));
  EXPECT_TRUE(exit_sent);
  EXPECT_TRUE(saw14);
  EXPECT_TRUE(all_modes(c, 0));
  EXPECT_NEAR(c.axis_position(1), start + speed * 0.4, 0.01);
  // Back in mode 0 the controller holds where the PC left the axis.
  pc.run(c, 50);
  EXPECT_NEAR(c.axis_position(1), start + speed * 0.4, 0.01);
}

TEST(C4gSimModes, Mode7CorrectionsAddUpOnTheControllersMove) {
  auto c = make_controller(
      "steps:\n  - drive_on\n  - go_open: {type: B, mode: 7}\n  - move: {arm: 1, deg: [5], duration: 0.2}\n"
      "  - wait_for_pc\n");
  PcResponder pc;
  ASSERT_TRUE(pc.run_until(c, [&] { return c.drives_on(1); }));
  const double q0 = c.axis_position(0);
  int corrections = 0;
  pc.fill = [&](const P::Packet& req, P::Packet& r) {
    if (req.axes[0].mode == 7 && corrections < 50) {
      r.axes[0].d1 = 0.01f;  // 0.5 turns in all
      ++corrections;
    } else if (req.axes[0].mode == 7) {
      r.infpar = P::request_exit_from_open(0, 1);
    }
  };
  ASSERT_TRUE(pc.run_until(c, [&] { return c.scenario_done() || c.scenario_failed(); }, 3000));
  EXPECT_FALSE(c.scenario_failed()) << c.scenario_error();
  pc.run(c, 200);
  const double move = -181.587296 * 5.0 / 360.0;  // motor turns for 5 deg at the link (ratio K_r)
  EXPECT_NEAR(c.axis_position(0) - q0, move + 0.5, 0.01);
}

TEST(C4gSimModes, ActiveFreezing500StopsCheckingUntilExitFromOpen) {
  auto c = make_controller("steps:\n  - drive_on\n  - run\n");
  PcResponder pc;
  ASSERT_TRUE(pc.run_until(c, [&] { return c.drives_on(1); }));
  pc.fill = [](const P::Packet&, P::Packet& r) {
    for (std::size_t i = 0; i < r.count; ++i) r.axes[i].mode = 500;
  };
  pc.tick(c);
  EXPECT_TRUE(all_modes(c, 500));
  pc.answer = false;
  pc.run(c, 50);  // far more than 10 misses
  EXPECT_FALSE(c.communication_error());
  EXPECT_EQ(c.stats().misses, 0u);
  EXPECT_EQ(pc.sent.back().packet.axes[0].mode, 500);
  pc.answer = true;
  pc.fill = [](const P::Packet&, P::Packet& r) { r.infpar = P::request_exit_from_open(0, 1); };
  pc.tick(c);
  EXPECT_TRUE(all_modes(c, 0));
  pc.fill = nullptr;
  pc.answer = false;
  pc.run(c, 10);
  EXPECT_TRUE(c.communication_error());  // checked again
}

TEST(C4gSimModes, DriveOffRequest505) {
  auto c = make_controller("steps:\n  - drive_on\n  - run\n");
  PcResponder pc;
  ASSERT_TRUE(pc.run_until(c, [&] { return c.drives_on(1); }));
  pc.fill = [](const P::Packet&, P::Packet& r) { r.axes[2].mode = 505; };
  pc.tick(c);
  pc.fill = nullptr;
  EXPECT_FALSE(c.drives_on(1));
  ASSERT_EQ(pc.count_events(event::kDriveOffFromPc), 1u);
  EXPECT_NE(pc.find_event(event::kDriveOffFromPc)->text.find("C4GOpen: Drive Off from Pc"), std::string::npos);
  pc.tick(c);
  EXPECT_EQ(pc.sent.back().packet.axes[0].mode, 505);
  EXPECT_EQ(P::arm_byte(pc.sent.back().packet.infpar, 1), 0);
  ASSERT_TRUE(pc.run_until(c, [&] { return all_modes(c, 0); }, 100));
  EXPECT_FALSE(c.communication_error());
}

TEST(C4gSimModes, FollowingErrorFromThePc508NamesTheAxisAndDrivesOff) {
  auto c = make_controller("steps:\n  - drive_on\n  - go_open: {type: A, mode: 2}\n  - wait_for_pc\n");
  PcResponder pc;
  ASSERT_TRUE(pc.run_until(c, [&] { return c.axis_mode(0) == 2; }));
  pc.fill = [](const P::Packet&, P::Packet& r) { r.axes[2].mode = 508; };
  pc.tick(c);
  pc.fill = nullptr;
  ASSERT_EQ(pc.count_events(event::kFollowErrorFromPc), 1u);
  EXPECT_NE(pc.find_event(event::kFollowErrorFromPc)->text.find("arm 1 axis 3 Following error out of range"), std::string::npos);
  EXPECT_FALSE(c.drives_on(1));
  pc.tick(c);
  EXPECT_EQ(pc.sent.back().packet.axes[2].mode, 508);
  // The open ended with the drive off: WAIT FOR PC returns.
  ASSERT_TRUE(pc.run_until(c, [&] { return c.scenario_done(); }, 100));
}

TEST(C4gSimModes, ControllerFollowingErrorWhenThePcSendsNoTargetInMode4) {
  // 30 deg at the link is about 15 motor turns on axis 1, twice its threshold of 7.5.
  auto c = make_controller(
      "steps:\n  - drive_on\n  - move: {deg: [30], duration: 0.3}\n  - go_open: {type: A, mode: 4}\n  - wait_for_pc\n");
  PcResponder pc;  // replies zero targets: the axes are pulled towards 0 turns
  ASSERT_TRUE(pc.run_until(c, [&] { return c.axis_mode(0) == 4; }, 2000));
  ASSERT_TRUE(pc.run_until(c, [&] { return !c.drives_on(1); }, 200));
  ASSERT_GE(pc.count_events(event::kFollowErrorController), 1u);
  EXPECT_NE(pc.find_event(event::kFollowErrorController)->text.find("arm 1 axis 1"), std::string::npos);
  EXPECT_TRUE(pc.run_until(c, [&] { return c.scenario_done(); }, 100));  // the open ended with the drives
}

TEST(C4gSimModes, RestartSendsTheInitializationPacketAgainWithoutSyncPackets) {
  auto c = make_controller("steps:\n  - drive_on\n  - restart\n  - run\n");
  PcResponder pc;
  ASSERT_TRUE(pc.run_until(c, [&] { return c.stats().init_sent == 2; }, 200));
  const std::size_t n = pc.sent.size();
  ASSERT_TRUE(pc.sent[n - 1].init);
  ASSERT_TRUE(pc.sent[n - 2].cyclic);
  EXPECT_EQ(pc.sent[n - 2].packet.axes[0].mode, 506);
  EXPECT_EQ(c.stats().sync_sent, 3u);
  pc.run(c, 3);
  EXPECT_TRUE(pc.sent.back().cyclic);
  EXPECT_EQ(pc.sent.back().packet.axes[0].mode, 0);
  EXPECT_TRUE(c.drives_on(1));
  EXPECT_EQ(c.phase(), Phase::cycle);
}

TEST(C4gSimModes, RestartAskedByThePc) {
  auto c = make_controller("steps:\n  - run\n");
  PcResponder pc;
  pc.run(c, 8);
  pc.fill = [](const P::Packet& req, P::Packet& r) {
    if (req.axes[0].mode == 0) r.axes[0].mode = 506;
  };
  pc.run(c, 3);
  EXPECT_EQ(c.stats().init_sent, 2u);
}

TEST(C4gSimModes, PassiveFreezingAndExitOpen) {
  auto c = make_controller("steps:\n  - freeze_passive: 0.1\n  - exit_open\n");
  PcResponder pc;
  ASSERT_TRUE(pc.run_until(c, [&] { return c.finished(); }, 500));
  EXPECT_FALSE(c.communication_error());
  EXPECT_TRUE(c.scenario_done());
  EXPECT_EQ(c.phase(), Phase::ended);
  std::vector<std::int32_t> codes;
  std::size_t silent = 0;
  for (const auto& s : pc.sent) {
    if (s.bytes.empty()) ++silent;
    else if (s.cyclic && (codes.empty() || codes.back() != s.packet.axes[0].mode)) codes.push_back(s.packet.axes[0].mode);
  }
  // 503 ends in mode 0, which one packet shows before the program's 504 goes out.
  EXPECT_EQ(codes, (std::vector<std::int32_t>{0, 502, 503, 0, 504}));
  EXPECT_EQ(silent, 50u);  // 0.1 s at 2 ms without packets
}

TEST(C4gSimModes, ThePcSetsAModeFromMode0OnlyWithDrivesOnAndTheArmAtRest) {
  // Chapter 11 (second phase) and 15.2: once driven on, the mode is the one the PC or the program
  // set; chapter 13: only between two moves. The PC's mode 4 holds the actual position.
  auto c = make_controller("steps:\n  - delay: 0.1\n  - drive_on\n  - move: {deg: [5], duration: 0.5}\n  - run\n");
  PcResponder pc;
  pc.fill = [](const P::Packet& q, P::Packet& r) {
    for (std::size_t i = 0; i < r.count; ++i) {
      r.axes[i].mode = 4;
      r.axes[i].d1 = q.axes[i].d3;
    }
  };
  pc.run(c, 10);  // drives off: refused, once per change of the request
  EXPECT_TRUE(all_modes(c, 0));
  EXPECT_GE(c.stats().refused_requests, 1u);
  ASSERT_TRUE(pc.run_until(c, [&] { return c.drives_on(1); }, 500));
  pc.run(c, 20);  // the move runs: still refused
  EXPECT_TRUE(all_modes(c, 0));
  const auto refused_before = c.stats().refused_requests;
  EXPECT_GE(pc.count_events(event::kRequestRefused), 1u);
  ASSERT_TRUE(pc.run_until(c, [&] { return all_modes(c, 4); }, 1000));  // taken once the move ended
  EXPECT_EQ(c.stats().refused_requests, refused_before);
  // The PC's exit-from-open ends it (4' then 0); its SM meanwhile is no request.
  pc.fill = [](const P::Packet& q, P::Packet& r) {
    r.infpar = P::request_exit_from_open(0, 1);
    for (std::size_t i = 0; i < r.count; ++i) r.axes[i].d1 = q.axes[i].d3;
  };
  ASSERT_TRUE(pc.run_until(c, [&] { return all_modes(c, 0); }, 200));
  EXPECT_EQ(c.stats().refused_requests, refused_before);
}

TEST(C4gSimModes, ThePcCannotIssueTheControllersCodes) {
  auto c = make_controller("steps:\n  - drive_on\n  - run\n");
  PcResponder pc;
  ASSERT_TRUE(pc.run_until(c, [&] { return c.drives_on(1); }));
  pc.fill = [](const P::Packet&, P::Packet& r) { r.axes[0].mode = 14; };  // a standby code
  pc.run(c, 5);
  EXPECT_EQ(c.axis_mode(0), 0);
  EXPECT_EQ(c.stats().refused_requests, 1u);  // reported once per change of the request
  EXPECT_EQ(pc.count_events(event::kRequestRefused), 1u);
}

TEST(C4gSimModes, MoveInOpenTypeAFailsTheScenario) {
  auto c = make_controller("steps:\n  - drive_on\n  - go_open: {type: A, mode: 9}\n  - move: {deg: [1], duration: 1}\n");
  PcResponder pc;
  ASSERT_TRUE(pc.run_until(c, [&] { return c.finished(); }, 200));
  EXPECT_TRUE(c.scenario_failed());
  EXPECT_NE(c.scenario_error().find("test.yaml:4:5"), std::string::npos) << c.scenario_error();
}

TEST(C4gSimModes, DefaultScenarioMovesOutAndBack) {
  auto sc = Scenario::default_scenario();
  auto c = Controller::create(quick_robot(), sc).value();
  PcResponder pc;
  double max_deg = 0;
  pc.run_until(c, [&] {
    const auto q = c.joint_degrees(1);
    if (!q.empty()) max_deg = std::max(max_deg, q[3]);
    return c.scenario_running_forever() && c.stats().ticks > 1700;
  }, 3000);
  EXPECT_TRUE(c.scenario_running_forever());
  EXPECT_FALSE(c.scenario_failed()) << c.scenario_error();
  EXPECT_NEAR(max_deg, 20.0, 0.5);
  const auto q = c.joint_degrees(1);
  for (double v : q) EXPECT_NEAR(v, 0.0, 0.05);
}

}  // namespace
}  // namespace axon::c4g::sim::test

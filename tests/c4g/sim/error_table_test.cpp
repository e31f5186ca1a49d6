// The manual's error table (chapter 17) where the simulator raises an error the PC cannot see:
// one missed reply (Rx Debug), a failed send, a configuration with too many axes; and the scenario
// steps that raise the selector's forced mode 0 and set the general override.
#include "axon/c4g/sim/controller.hpp"
#include "pc_responder.hpp"

#include <gtest/gtest.h>

namespace axon::c4g::sim::test {
namespace {

TEST(C4gSimErrorTable, OneMissedReplyIsRxDebugAndTheNextGoodOneEndsTheStreak) {
  auto c = make_controller("steps:\n  - drive_on\n  - run\n");
  PcResponder pc;
  ASSERT_TRUE(pc.run_until(c, [&] { return c.drives_on(1); }));
  pc.answer = false;
  pc.tick(c);
  pc.answer = true;
  pc.tick(c);
  ASSERT_EQ(pc.count_events(event::kReceiveDebug), 2u);  // the miss, then "answers again"
  EXPECT_NE(pc.find_event(event::kReceiveDebug)->text.find("C4GOpen: Rx Debug"), std::string::npos);
  EXPECT_FALSE(c.communication_error());
}

TEST(C4gSimErrorTable, AFailedSendIsTxUdpAndCountsAsAMiss) {
  auto c = make_controller("steps:\n  - drive_on\n  - run\n");
  PcResponder pc;
  ASSERT_TRUE(pc.run_until(c, [&] { return c.drives_on(1); }));
  const auto misses = c.stats().misses;
  ASSERT_FALSE(c.begin_cycle().empty());
  c.on_send_failed("network unreachable");
  c.end_cycle();
  EXPECT_EQ(c.stats().misses, misses + 1);
  bool tx = false;
  for (const auto& e : c.take_events())
    tx |= e.name == event::kTransmitError && e.text.find("C4GOpen: error in socket UDP transmission") != std::string::npos;
  EXPECT_TRUE(tx);
}

TEST(C4gSimErrorTable, TooManyOpenAxesIsTheConfigurationError) {
  auto robot = quick_robot();
  robot.init.open_axes = 7;  // the lists name 6
  const auto c = Controller::create(robot, Scenario::default_scenario());
  ASSERT_FALSE(c);
  EXPECT_NE(c.error().detail.find("ERR_C4GOPEN: C4GOpen: configuration error"), std::string::npos) << c.error().detail;
}

TEST(C4gSimErrorTable, TheSelectorForcesMode0AndTheOverrideStepsParse) {
  auto c = make_controller("steps:\n  - drive_on\n  - override: 40\n  - go_open: {type: A, mode: 4}\n  - delay: 0.02\n"
                           "  - selector: prog\n  - delay: 0.02\n  - selector: auto\n  - exit_open\n");
  PcResponder pc;
  pc.fill = [](const P::Packet& q, P::Packet& r) {
    for (std::size_t i = 0; i < q.count; ++i)
      if (q.axes[i].mode == 4) r.axes[i].d1 = q.axes[i].d3;  // hold where the robot is
  };
  ASSERT_TRUE(pc.run_until(c, [&] { return c.finished(); }, 2000));
  EXPECT_TRUE(c.scenario_done()) << c.scenario_error();
  EXPECT_EQ(pc.count_events(event::kForcedMode0), 1u);  // PROG forced it; back to AUTO found mode 0
  EXPECT_EQ(pc.count_events(event::kPositionJump), 0u);  // mode 4 held where the trajectory stood
  for (std::string_view bad : {"steps:\n  - selector: manual\n  - run\n", "steps:\n  - override: 0\n  - run\n",
                               "steps:\n  - override: 101\n  - run\n"})
    EXPECT_FALSE(Scenario::parse(bad)) << bad;
}

}  // namespace
}  // namespace axon::c4g::sim::test

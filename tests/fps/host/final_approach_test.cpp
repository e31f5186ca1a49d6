// The final approach after a trajectory move (interface document 7.3): GO_TO_RELATIVE_POSITION
// (0, 0) to every robot that arrived, so that the firmware's 0.9 deg back-and-forth leaves its
// arms outside the backlash before correction iterations.
#include "plane_rig.hpp"

#include <gtest/gtest.h>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::host;
using namespace axon::fps::host::testing;

namespace {

// Robots 1-6 (sextant 1) from the fold to `to` in 4 s.
std::map<std::uint16_t, protocol::Trajectory> sextant_one_to(ArmAngles to) {
  std::map<std::uint16_t, protocol::Trajectory> t;
  std::vector<protocol::ArmPoint> a{{to.alpha, 4.0}}, b{{to.beta, 4.0}};
  for (std::uint16_t id = 1; id <= 6; ++id) t.emplace(id, protocol::Trajectory::from_physical(a, b).value());
  return t;
}

TrajectoryOptions with_approach() {
  TrajectoryOptions o;
  o.final_approach = true;
  return o;
}

}  // namespace

TEST(FinalApproach, EveryRobotThatArrivedApproachesItsTargetAgain) {
  PlaneRig rig;
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    std::vector<std::string> phases;
    auto o = with_approach();
    o.on_phase = [&phases](std::string_view p) { phases.emplace_back(p); };
    auto r = co_await rig.fpa->run_trajectories(sextant_one_to({25, 170}), o);
    EXPECT_TRUE(r.has_value());
    if (!r) co_return;
    EXPECT_TRUE(r.value().completed) << r.value().summary();
    for (const auto& rr : r.value().robots) {
      EXPECT_TRUE(rr.approached) << rr.id << " " << rr.detail;
      EXPECT_TRUE(rr.reached.has_value());
      if (!rr.reached) continue;
      EXPECT_NEAR(rr.reached->alpha, 25, 0.01) << rr.id;
      EXPECT_NEAR(rr.reached->beta, 170, 0.01) << rr.id;
      const auto* m = rig.sim->simulator().find(rr.id);
      EXPECT_FALSE(m->moving());
      EXPECT_NEAR(m->physical_deg(sim::Arm::alpha), 25, 0.01) << rr.id;
      EXPECT_NEAR(m->physical_deg(sim::Arm::beta), 170, 0.01) << rr.id;
    }
    EXPECT_EQ(phases.back(), "approached");
    // Robots outside the run were not touched.
    EXPECT_NEAR(rig.sim->simulator().find(7)->physical_deg(sim::Arm::beta), 180, 1e-6);
  });
}

// The approach is really sent, to each robot: one whose answer to it is lost leaves the run with
// the reason, the others approach; without the option the same loss changes nothing.
TEST(FinalApproach, ARobotWhoseApproachIsNotAnsweredLeavesTheRun) {
  for (const bool approach : {true, false}) {
    auto so = plane_sim_options();
    so.simulator.reply_faults.rules.push_back(drop_rule(replies_of(4, protocol::CommandId::go_to_relative_position)));
    PlaneRig rig(std::move(so));
    rig.runner.run([&]() -> asio::awaitable<void> {
      co_await rig.connect();
      if (!rig.fpa) co_return;
      TrajectoryOptions o;
      o.final_approach = approach;
      auto r = co_await rig.fpa->run_trajectories(sextant_one_to({10, 175}), o);
      EXPECT_TRUE(r.has_value());
      if (!r) co_return;
      const auto& rep = r.value();
      EXPECT_EQ(rep.completed, !approach) << rep.summary();
      for (const auto& rr : rep.robots) {
        if (approach && rr.id == 4) {
          EXPECT_EQ(rr.state, RobotState::timeout) << rr.detail;
          EXPECT_NE(rr.detail.find("final approach (7.3)"), std::string::npos) << rr.detail;
          EXPECT_FALSE(rr.approached);
        } else {
          EXPECT_EQ(rr.state, RobotState::completed) << rr.id << " " << rr.detail;
          EXPECT_EQ(rr.approached, approach) << rr.id;
        }
      }
    });
  }
}

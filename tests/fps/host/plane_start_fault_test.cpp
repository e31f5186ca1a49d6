// A robot that never acknowledges the trajectory start, on the simulated plane over TCP: every
// robot on every bus is stopped and the report says which robot failed to start.
#include "plane_rig.hpp"

#include <gtest/gtest.h>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::host;
using namespace axon::fps::host::testing;

namespace {

protocol::Trajectory slow_to(ArmAngles to) {
  std::vector<protocol::ArmPoint> a, b;
  for (int i = 1; i <= 10; ++i) {
    const double f = i / 10.0;
    a.push_back({to.alpha * f, 40.0 * f});
    b.push_back({180.0 + (to.beta - 180.0) * f, 40.0 * f});
  }
  return protocol::Trajectory::from_physical(a, b).value();
}

}  // namespace

TEST(PlaneStartFault, ARobotThatNeverAcknowledgesTheStartStopsEveryone) {
  auto so = plane_sim_options();
  // Robot 10 (gateway 2, bus 2) starts but its acknowledgement never reaches the host.
  so.simulator.reply_faults.rules.push_back(drop_rule(replies_of(10, protocol::CommandId::start_trajectory)));
  PlaneRig rig(so);
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    std::map<std::uint16_t, protocol::Trajectory> t;
    for (auto id : rig.fpa->array().ids()) t.emplace(id, slow_to({90, 120}));
    auto r = co_await rig.fpa->run_trajectories(std::move(t));
    EXPECT_TRUE(r.has_value());
    if (!r) co_return;
    const auto& rep = r.value();
    EXPECT_FALSE(rep.completed) << rep.summary();
    EXPECT_EQ(rep.find(10)->state, RobotState::not_started) << rep.summary();
    for (const auto& rr : rep.robots) {
      if (rr.id == 10) continue;
      EXPECT_EQ(rr.state, RobotState::stopped) << rr.id << " " << to_string(rr.state) << " " << rr.detail;
    }
    EXPECT_EQ(rig.fpa->array().counters().start_failures, 1u);
    EXPECT_FALSE(rig.fpa->array().locked());  // nothing collided
    EXPECT_NE(rep.summary().find("10"), std::string::npos);
    // Every robot, robot 10 included (it did start), stands still far from its target.
    EXPECT_TRUE(co_await eventually([&] {
      for (auto* m : rig.sim->simulator().robots())
        if (m->moving()) return false;
      return true;
    }));
    for (auto* m : rig.sim->simulator().robots()) EXPECT_LT(m->physical_deg(sim::Arm::alpha), 45.0) << m->id();
  });
}

// web::FpsHostView against a simulated plane in this process (12 robots on 4 buses behind two
// gateway emulators), driven by a FocalPlaneArray over loopback TCP.
#include "fps/host/plane_rig.hpp"

#include "axon/web/fps_host_view.hpp"

#include <gtest/gtest.h>

#include <span>
#include <string>
#include <vector>

namespace axon::web {
namespace {

using namespace axon::fps::host::testing;
namespace sim = fps::sim;

// The robot's object in a state message ("{\"id\":N,..." up to its closing brace).
std::string robot_json(const std::string& state, std::uint16_t id) {
  const auto at = state.find(fmt::format("{{\"id\":{},", id));
  if (at == std::string::npos) return {};
  return state.substr(at, state.find('}', at) - at + 1);
}

TEST(FpsHostView, AfterDiscoveryEveryRobotIsReadyAtTheSimulatorsAngles) {
  PlaneRig rig;
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    auto found = co_await rig.fpa->discover();
    EXPECT_TRUE(found.has_value());
    FpsHostView view(*rig.fpa);
    EXPECT_NE(view.info_json().find("\"view\":\"host\""), std::string::npos);
    EXPECT_NE(view.info_json().find("\"bus\":\"gw2/2\",\"sextant\":2}"), std::string::npos) << view.info_json();
    co_await view.read();
    view.update();
    const auto state = view.state_json();
    EXPECT_NE(state.find("\"states\":{\"ready\":12,\"moving\":0,"), std::string::npos) << state;
    EXPECT_NE(state.find("\"lock\":{\"locked\":false,\"robot\":0,"), std::string::npos) << state;
    for (auto* m : rig.sim->simulator().robots()) {
      const auto r = robot_json(state, m->id());
      EXPECT_FALSE(r.empty()) << m->id();
      EXPECT_NE(r.find(fmt::format("\"a\":{:.3f},\"b\":{:.3f},\"s\":\"ready\"", m->physical_deg(sim::Arm::alpha),
                                   m->physical_deg(sim::Arm::beta))),
                std::string::npos)
          << r;
      EXPECT_NE(r.find("\"fw\":\"04.01.13\""), std::string::npos) << r;
    }
    const auto metrics = view.metrics();
    EXPECT_NE(metrics.find("\naxon_fps_host_robots{state=\"ready\"} 12\n"), std::string::npos) << metrics;
    EXPECT_NE(metrics.find("# TYPE axon_fps_host_bus_timeouts_total counter\naxon_fps_host_bus_timeouts_total{bus=\"gw1/1\"} 0\n"),
              std::string::npos)
        << metrics;
    EXPECT_NE(metrics.find("axon_fps_host_bus_receive_overflows_total{bus=\"gw2/2\"} 0\n"), std::string::npos) << metrics;
  });
}

TEST(FpsHostView, ARobotThatStopsAnsweringIsOffline) {
  PlaneRig rig;
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    FpsHostView view(*rig.fpa);
    co_await view.read();
    view.update();
    EXPECT_NE(view.state_json().find("\"ready\":12,"), std::string::npos) << view.state_json();
    const std::vector<std::uint16_t> off{5};
    EXPECT_TRUE(rig.sim->simulator().power_off(std::span<const std::uint16_t>(off)).has_value());
    co_await view.read();
    view.update();
    const auto state = view.state_json();
    EXPECT_NE(state.find("\"ready\":11,"), std::string::npos) << state;
    EXPECT_NE(state.find("\"offline\":1,"), std::string::npos) << state;
    const auto r = robot_json(state, 5);
    EXPECT_NE(r.find("\"s\":\"offline\""), std::string::npos) << r;
    EXPECT_EQ(r.find("\"err\":\"\""), std::string::npos) << r;  // why the read failed
    const auto metrics = view.metrics();
    EXPECT_NE(metrics.find("axon_fps_host_robot_read_failures_total{robot=\"5\",bus=\"gw1/2\"} 1\n"), std::string::npos) << metrics;
    EXPECT_EQ(metrics.find("axon_fps_host_bus_timeouts_total{bus=\"gw1/2\"} 0\n"), std::string::npos) << metrics;
  });
}

TEST(FpsHostView, ACollisionShowsTheLockAndTheRobot) {
  PlaneRig rig;
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    FpsHostView view(*rig.fpa);
    EXPECT_TRUE(rig.sim->simulator().force_collision(8, sim::Arm::beta).has_value());
    EXPECT_TRUE(co_await eventually([&] { return rig.fpa->array().locked(); }));
    co_await view.read();
    view.update();
    const auto& lock = view.lock();
    EXPECT_TRUE(lock.locked);
    EXPECT_EQ(lock.robot, 8);
    EXPECT_EQ(lock.bus, "gw2/1");
    EXPECT_EQ(lock.arm, "beta");
    EXPECT_EQ(lock.count, 1u);
    EXPECT_FALSE(lock.reason.empty());
    const auto state = view.state_json();
    EXPECT_NE(state.find("\"lock\":{\"locked\":true,\"robot\":8,\"bus\":\"gw2/1\",\"arm\":\"beta\",\"count\":1,\"collided\":[8]"),
              std::string::npos)
        << state;
    const auto r = robot_json(state, 8);
    EXPECT_NE(r.find("\"s\":\"collided\""), std::string::npos) << r;
    EXPECT_NE(r.find("\"col\":1"), std::string::npos) << r;
    const auto metrics = view.metrics();
    EXPECT_NE(metrics.find("\naxon_fps_host_locked 1\n"), std::string::npos) << metrics;
    EXPECT_NE(metrics.find("\naxon_fps_host_collision_locks_total 1\n"), std::string::npos) << metrics;
    EXPECT_NE(metrics.find("axon_fps_host_robot_collision_reports_total{robot=\"8\",bus=\"gw2/1\"} 1\n"), std::string::npos)
        << metrics;
  });
}

}  // namespace
}  // namespace axon::web

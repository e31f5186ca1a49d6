// A planned reconfiguration of the default focal plane played by the fps simulator: every robot
// model gets its planned trajectory through the firmware's own upload commands, the sync line
// starts them all at once, and the simulator's geometric collision check (the planner's capsules,
// but its own robots' configs, fiducial sizes and stepping in time, independent of the planner's
// checker) watches the whole move. Nobody may touch, and every
// robot must end at its target.
//
// 500 robots in a Release build (a few seconds); under sanitizers the robots within 70 mm of the
// plane's centre (about 37), so the test stays quick there too.
#include "axon/fps/layout/layout_generator.hpp"
#include "axon/fps/plan/layout_model.hpp"
#include "axon/fps/plan/planner.hpp"
#include "axon/fps/plan/problems.hpp"
#include "axon/fps/protocol/commands.hpp"
#include "axon/fps/protocol/message.hpp"
#include "axon/fps/protocol/payloads.hpp"
#include "axon/fps/sim/simulator.hpp"
#include "axon/fps/sim/simulator_config.hpp"

#include "axon/can/virtual_bus.hpp"
#include "axon/core/clock.hpp"

#include <boost/asio/io_context.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <fmt/format.h>

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define AXON_PLAN_SIM_SMALL 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(undefined_behavior_sanitizer)
#define AXON_PLAN_SIM_SMALL 1
#endif
#endif

namespace axon::fps::plan {
namespace {

using protocol::CommandId;
using protocol::ResponseCode;
using namespace std::chrono_literals;

protocol::Payload point(double deg, double seconds) {
  return protocol::TrajectoryPoint{protocol::Angle::from_degrees(deg).value(),
                                   protocol::Time::from_seconds(seconds).value()}
      .encode();
}

// One request to one robot model, as the host would send it; the reply's response code.
ResponseCode ask(sim::PositionerModel& m, sim::SimTime now, CommandId c, const protocol::Payload& payload) {
  const protocol::Message req{protocol::Identifier{m.id(), protocol::number(c), 1, ResponseCode::accepted}, payload};
  const auto out = m.handle(req, now);
  for (const auto& r : out)
    if (r.id.command == protocol::number(c) && r.id.positioner == m.id()) return r.id.response;
  return ResponseCode::invalid_trajectory;  // no reply at all: a failure either way
}

TEST(PlannedMoveInSimulator, NoCollisionAndEveryRobotAtItsTarget) {
  const auto layout = generate_layout().value();

  // The robots taking part (all of them, or a patch around the centre under sanitizers).
  std::vector<RobotSpec> specs;
  for (const auto& r : layout.robots()) {
#ifdef AXON_PLAN_SIM_SMALL
    if (std::hypot(r.x_mm, r.y_mm) > 70.0) continue;
#endif
    RobotSpec s;
    s.id = r.id;
    s.centre = {r.x_mm, r.y_mm};
    specs.push_back(s);
  }
  std::vector<FiducialSpec> fids;
  for (const auto& f : layout.fiducials()) fids.push_back({f.id, {f.x_mm, f.y_mm}, 3.0});
  const auto model = CollisionModel::build(specs, ArmDesign{}, fids).value();
  ASSERT_GT(model.size(), 20u);

  PlanRequest req;
  req.current = folded_poses(model);
  req.target = random_poses(model, 1002);
  PlannerOptions po;
  po.seed = 1002;
  auto planned = plan_moves(model, req, po);
  ASSERT_TRUE(planned) << planned.error().message();
  const Plan& plan = planned.value();
  ASSERT_TRUE(plan.ok()) << plan.summary(model);
  ASSERT_TRUE(plan.verified);

  // The simulator: the same robots on one virtual bus, fiducials as obstacles, a manual clock.
  boost::asio::io_context io;
  can::VirtualBusRegistry registry(io.get_executor());
  ASSERT_TRUE(registry.add("plane"));
  core::ManualClock clock;
  sim::SimulatorConfig sc;
  sc.options.clock = &clock;
  sc.options.collision_step = 20ms;
  for (std::size_t i = 0; i < model.size(); ++i) {
    const auto& r = model.robot(i);
    sim::RobotPlacement p;
    p.config.id = static_cast<std::uint16_t>(r.id());
    p.config.x_mm = r.centre().x;
    p.config.y_mm = r.centre().y;
    p.config.start_position_deg = sim::PerArm<double>{{req.current[i].alpha_deg, req.current[i].beta_deg}};
    p.channel = "plane";
    sc.robots.push_back(std::move(p));
  }
  for (const auto& f : layout.fiducials()) {
    const sim::Vec2 at{f.x_mm, f.y_mm};
    sc.obstacles.push_back(sim::Obstacle{fmt::format("fiducial {}", f.id), sim::Segment{at, at}, 1.5});
  }
  auto made = sim::make_simulator(io.get_executor(), sc, registry);
  ASSERT_TRUE(made) << made.error().message();
  auto& simulator = *made.value();

  // Upload through the firmware's commands (the start pose is the firmware's own first point).
  std::size_t moving = 0;
  for (std::size_t i = 0; i < model.size(); ++i) {
    const RobotTrajectory& t = plan.trajectories[i];
    if (t.alpha.size() < 2 && t.beta.size() < 2) continue;
    auto* m = simulator.find(static_cast<std::uint16_t>(model.robot(i).id()));
    ASSERT_NE(m, nullptr);
    // An arm that stays gets one point at its angle.
    auto arm = [](const std::vector<TimedAngle>& pts) {
      std::vector<TimedAngle> out(pts.begin() + 1, pts.end());
      if (out.empty()) out.push_back({0.5, pts.front().deg});
      return out;
    };
    const auto a = arm(t.alpha), b = arm(t.beta);
    const auto now = simulator.now();
    ASSERT_EQ(ask(*m, now, CommandId::send_new_trajectory,
                  protocol::Payload().put_u32(static_cast<std::uint32_t>(a.size())).put_u32(static_cast<std::uint32_t>(b.size()))),
              ResponseCode::accepted);
    for (const auto* pts : {&a, &b})
      for (const auto& p : *pts)
        ASSERT_EQ(ask(*m, now, CommandId::send_trajectory_data, point(p.deg, p.t_s)), ResponseCode::accepted)
            << "robot " << m->id() << " point " << p.deg << " deg at " << p.t_s << " s";
    ASSERT_EQ(ask(*m, now, CommandId::trajectory_data_end, {}), ResponseCode::accepted) << "robot " << m->id();
    ++moving;
  }
  ASSERT_GT(moving, model.size() / 2);

  simulator.set_sync_line(true);  // held: every robot starts at its second look
  const auto total = std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(plan.stats.duration_s + 2.0));
  for (core::Duration t{}; t < total; t += 20ms) {
    clock.advance(20ms);
    simulator.step();
  }
  EXPECT_EQ(simulator.stats().neighbour_collisions, 0u);
  EXPECT_EQ(simulator.stats().obstacle_collisions, 0u);
  for (std::size_t i = 0; i < model.size(); ++i) {
    const auto* m = simulator.find(static_cast<std::uint16_t>(model.robot(i).id()));
    EXPECT_NEAR(m->physical_deg(sim::Arm::alpha), req.target[i].alpha_deg, 1e-3) << "robot " << m->id();
    EXPECT_NEAR(m->physical_deg(sim::Arm::beta), req.target[i].beta_deg, 1e-3) << "robot " << m->id();
    EXPECT_FALSE(m->status().collided()) << "robot " << m->id();
  }
}

}  // namespace
}  // namespace axon::fps::plan

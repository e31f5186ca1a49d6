// The controller's documented errors and checks (manual chapters 14.8, 14.17.1, 17), raised by the
// simulator and recognised by the Server from its packets (host::ControllerWatch), over loopback
// UDP. The simulator takes the lenient reply window: the subject is the errors, not the latency.
#include "c4g/host/sim_events.hpp"
#include "axon/c4g/host/server.hpp"
#include "axon/c4g/protocol/mode.hpp"
#include "axon/c4g/sim/client_runner.hpp"
#include "axon/c4g/sim/controller.hpp"
#include "axon/c4g/sim/robots.hpp"
#include "axon/c4g/sim/scenario.hpp"
#include "axon/c4g/sim/udp_client.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <thread>

namespace axon::c4g::controller_errors_test {
namespace {

namespace P = protocol;
namespace H = host;
namespace S = sim;
using E = H::ControllerError;

class Pc : public H::Controller {
 public:
  std::function<void(const H::CycleContext&, H::ReplyBuilder&)> cycle;
  void on_cycle(const H::CycleContext& ctx, H::ReplyBuilder& reply) override {
    if (cycle) cycle(ctx, reply);
  }
};

std::unique_ptr<H::Server> serve(Pc& pc, H::ServerOptions o = {}) {
  o.listen = net::Endpoint{"127.0.0.1", 0};
  o.max_late_cycles = 0;
  o.verify_reply_fields = true;
  auto s = H::Server::start(pc, o);
  if (!s) ADD_FAILURE() << s.error().detail;
  return std::move(s).value();
}

struct Run {
  std::optional<S::Controller> c;
  std::vector<S::Event> events;
  [[nodiscard]] bool has(std::string_view name, std::string_view text = {}) const {
    return test::has_event(events, name, text);
  }
  [[nodiscard]] std::string log() const { return test::event_log(events); }
};

Run play(const H::Server& server, std::string_view yaml, S::RobotConfig robot = S::six_axis_robot(), double max_s = 10) {
  Run r;
  auto scenario = S::Scenario::parse(yaml);
  EXPECT_TRUE(scenario) << scenario.error().detail;
  auto c = S::Controller::create(std::move(robot), scenario.value());
  EXPECT_TRUE(c) << c.error().detail;
  r.c.emplace(std::move(c).value());
  r.events = r.c->take_events();  // what the controller said at start-up
  auto udp = S::UdpClient::open(net::Endpoint{"127.0.0.1", server.local_address().port});
  EXPECT_TRUE(udp);
  S::RunOptions ro;
  ro.duration_s = max_s;
  ro.window = S::ReplyWindow::period;
  ro.on_event = [&](const S::Event& e) { r.events.push_back(e); };
  S::run_client(*r.c, udp.value(), ro);
  return r;
}

// Mode 5: `step` motor turns per cycle on axis 1 for `cycles` cycles, then exit-from-open.
void increments(Pc& pc, float step, int cycles) {
  auto k = std::make_shared<int>(0);
  pc.cycle = [k, step, cycles](const H::CycleContext& ctx, H::ReplyBuilder& r) {
    if (ctx.request.axes[0].mode != 5) return;
    if (++*k <= cycles) r.axis(0).d2 = step;
    else r.exit_from_open(1);
  };
}

TEST(ControllerErrorsAgainstSim, TheStateSelectorForcesMode0AndTheServerNamesSet0ModalityAndTheJump) {
  Pc pc;
  increments(pc, 0.01f, 100000);  // never exits by itself
  auto server = serve(pc);
  const auto run = play(*server, R"(steps:
  - drive_on
  - go_open: {type: A, mode: 5, arms: [1]}
  - delay: 0.3
  - selector: prog
  - delay: 0.1
  - selector: auto
  - exit_open)");
  server->stop();
  EXPECT_TRUE(run.c->scenario_done()) << run.log();
  EXPECT_TRUE(run.has(S::event::kForcedMode0, "C4GOpen: arm 1 , forced 0 modality")) << run.log();
  EXPECT_TRUE(run.has(S::event::kPositionJump, "arm 1 axis 1")) << run.log();
  const auto& w = server->controller_errors();
  EXPECT_EQ(w.count(E::forced_mode0), 1u) << server->summary();
  EXPECT_GE(w.count(E::position_jump), 1u) << server->summary();
  EXPECT_GT(w.jump_turns(), 1.0);  // about 150 cycles of 0.01 turns were dropped
  EXPECT_EQ(w.last_arm(), 1);
  EXPECT_EQ(w.count(E::communication), 0u);
  EXPECT_NE(server->summary().find("ERR_C4GOPEN_SET_0_MODALITY x1"), std::string::npos) << server->summary();
}

TEST(ControllerErrorsAgainstSim, OpenModesNeedAutoThePcsRequestInProgIsRefused) {
  Pc pc;
  pc.cycle = [](const H::CycleContext& ctx, H::ReplyBuilder& r) {
    if (ctx.request.axes[0].mode == 0 && P::arm_byte(ctx.request.infpar, 1) == P::kDrivesOn) r.set_mode(0, 4);
  };
  auto server = serve(pc);
  const auto run = play(*server, "steps:\n  - selector: prog\n  - drive_on\n  - delay: 0.2\n  - exit_open\n");
  server->stop();
  EXPECT_TRUE(run.c->scenario_done()) << run.log();
  EXPECT_TRUE(run.has(S::event::kRequestRefused, "PROG")) << run.log();
  EXPECT_EQ(run.c->axis_mode(0), 0);
  // The program's own GO OPEN in PROG fails the program.
  Pc idle;
  auto server2 = serve(idle);
  const auto refused = play(*server2, "steps:\n  - selector: prog\n  - drive_on\n  - go_open: {mode: 4}\n  - run\n",
                            S::six_axis_robot(), 2);
  server2->stop();
  EXPECT_NE(refused.c->scenario_error().find("AUTO only"), std::string::npos) << refused.log();
}

TEST(ControllerErrorsAgainstSim, TheGeneralOverrideScalesMode5AndTheServerReportsThePercentage) {
  Pc pc;
  increments(pc, 0.01f, 100);
  auto server = serve(pc);
  const auto run = play(*server, R"(steps:
  - drive_on
  - override: 50
  - go_open: {type: A, mode: 5, arms: [1]}
  - wait_for_pc: {timeout: 5}
  - exit_open)");
  server->stop();
  EXPECT_TRUE(run.c->scenario_done()) << run.log();
  const auto& w = server->controller_errors();
  EXPECT_EQ(w.count(E::override_scaled), 1u) << server->summary();
  EXPECT_NEAR(w.applied_percent(), 50.0, 1.0);
  EXPECT_EQ(w.count(E::forced_mode0), 0u);
  // Without the override every increment is applied and nothing is reported.
  Pc full;
  increments(full, 0.01f, 100);
  auto server2 = serve(full);
  play(*server2, "steps:\n  - drive_on\n  - go_open: {type: A, mode: 5}\n  - wait_for_pc: {timeout: 5}\n  - exit_open\n");
  server2->stop();
  EXPECT_EQ(server2->controller_errors().count(E::override_scaled), 0u) << server2->summary();
  EXPECT_NEAR(server2->controller_errors().applied_percent(), 100.0, 1.0);
}

// Mode 7: one correction of 0.5 motor turns at cycle 20 (the controller's limit is 150 turns/s x 2 ms).
void big_correction(Pc& pc) {
  auto k = std::make_shared<int>(0);
  pc.cycle = [k](const H::CycleContext& ctx, H::ReplyBuilder& r) {
    if (ctx.request.axes[0].mode != 7) return;
    if (++*k == 20) r.axis(0).d1 = 0.5f;
  };
}
constexpr std::string_view kMode7 = "steps:\n  - drive_on\n  - go_open: {type: B, mode: 7}\n  - delay: 0.3\n  - run\n";

TEST(ControllerErrorsAgainstSim, TheOffsetLimitOfMode7StopsTheRobotAndTheServerNamesTheControllersStop) {
  Pc pc;
  big_correction(pc);
  H::ServerOptions o;
  o.safety.check_continuity = false;  // let the jump through: the controller's own check must catch it
  auto server = serve(pc, o);
  const auto run = play(*server, kMode7, S::six_axis_robot(), 0.6);
  server->stop();
  EXPECT_TRUE(run.has(S::event::kOffsetLimit, "arm 1 axis 1")) << run.log();
  EXPECT_FALSE(run.c->drives_on(1));
  EXPECT_EQ(server->controller_errors().count(E::controller_stop), 1u) << server->summary();
  EXPECT_EQ(server->controller_errors().count(E::drive_off_server), 0u);
}

TEST(ControllerErrorsAgainstSim, WithItsContinuityCheckThePcRefusesFirstAndTheServerNamesDriveOffFromPc) {
  Pc pc;
  big_correction(pc);
  auto server = serve(pc);
  const auto run = play(*server, kMode7, S::six_axis_robot(), 0.6);
  server->stop();
  EXPECT_FALSE(run.has(S::event::kOffsetLimit)) << run.log();
  EXPECT_TRUE(run.has(S::event::kDriveOffFromPc, "C4GOpen: Drive Off from Pc")) << run.log();
  EXPECT_EQ(server->controller_errors().count(E::drive_off_server), 1u) << server->summary();
  EXPECT_EQ(server->controller_errors().count(E::controller_stop), 0u) << server->summary();
}

TEST(ControllerErrorsAgainstSim, AFollowingErrorFromThePcIsNamedFollowError) {
  Pc pc;
  auto k = std::make_shared<int>(0);
  pc.cycle = [k](const H::CycleContext& ctx, H::ReplyBuilder& r) {
    if (P::arm_byte(ctx.request.infpar, 1) == P::kDrivesOn && ++*k == 30) r.set_mode(2, 508);
  };
  auto server = serve(pc);
  const auto run = play(*server, "steps:\n  - drive_on\n  - run\n", S::six_axis_robot(), 0.6);
  server->stop();
  EXPECT_TRUE(run.has(S::event::kFollowErrorFromPc, "arm 1 axis 3 Following error out of range")) << run.log();
  EXPECT_EQ(server->controller_errors().count(E::follow_error), 1u) << server->summary();
}

TEST(ControllerErrorsAgainstSim, AStartUpModeOnAnAxisThatIsNotOpenIsConfigurationAx) {
  auto robot = S::six_axis_robot();
  robot.init.modes[0][7] = 4;  // arm 1 logical axis 8: not in the open-axis list
  Pc pc;
  auto server = serve(pc);
  const auto run = play(*server, "steps:\n  - drive_on\n  - exit_open\n", robot);
  server->stop();
  EXPECT_TRUE(run.c->scenario_done()) << run.log();  // the controller ignores the axis and goes on
  EXPECT_TRUE(run.has(S::event::kAxisNotPresent, "C4GOpen: Arm 1 Axis 8 not present")) << run.log();
  const auto& w = server->controller_errors();
  EXPECT_EQ(w.count(E::configuration_ax), 1u) << server->summary();
  EXPECT_EQ(w.last_axis(), 8);
}

TEST(ControllerErrorsAgainstSim, RepliesThatComeTooLateEndInTheCommunicationErrorAndTheServerNamesIt) {
  Pc pc;
  std::atomic<int> cycles{0};
  pc.cycle = [&](const H::CycleContext&, H::ReplyBuilder&) {
    if (++cycles > 100) std::this_thread::sleep_for(std::chrono::milliseconds(6));  // 3 periods late
  };
  H::ServerOptions o;
  o.cycle.cycle_timeout = std::chrono::milliseconds(150);
  auto server = serve(pc, o);
  const auto run = play(*server, "steps:\n  - drive_on\n  - run\n", S::six_axis_robot(), 5);
  EXPECT_TRUE(run.c->communication_error()) << run.log();
  EXPECT_TRUE(run.has(S::event::kCommunicationError, "C4GOpen: communication error"));
  for (int i = 0; i < 200 && server->state() != H::ServerState::silent; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  server->stop();
  EXPECT_EQ(server->controller_errors().count(E::communication), 1u) << server->summary();
  EXPECT_EQ(server->controller_errors().last(), E::communication);
}

// Modes 1xx (not available on the controller, manual 14.13): the PC's measure reaches the controller
// in D3 and, with no processing documented, moves nothing.
TEST(ControllerErrorsAgainstSim, SensorModesCarryThePcsMeasureToTheController) {
  for (int mode : {101, 102, 103}) {
    Pc pc;
    auto k = std::make_shared<int>(0);
    pc.cycle = [k, mode](const H::CycleContext& ctx, H::ReplyBuilder& r) {
      if (ctx.request.axes[0].mode != mode) return;
      for (std::size_t i = 0; i < r.axis_count(); ++i) r.set_measure(i, 0.25f + 0.01f * static_cast<float>(i));
      if (++*k > 50) r.exit_from_open(1);
    };
    auto server = serve(pc);
    const auto run = play(*server, "steps:\n  - drive_on\n  - go_open: {type: B, mode: " + std::to_string(mode) +
                                       "}\n  - wait_for_pc: {timeout: 5}\n  - exit_open\n");
    server->stop();
    EXPECT_TRUE(run.c->scenario_done()) << run.log();
    EXPECT_EQ(run.c->stats().refused_requests, 0u) << run.log();
    EXPECT_FLOAT_EQ(run.c->axis_measure(0), 0.25f) << "mode " << mode;
    EXPECT_FLOAT_EQ(run.c->axis_measure(5), 0.30f) << "mode " << mode;
    EXPECT_EQ(server->safety().reason(), H::FaultReason::none) << server->summary();
    EXPECT_EQ(server->counters().unused_fields.load(), 0u);
    const auto joints = run.c->joint_degrees(1);
    ASSERT_EQ(joints.size(), 6u);
    for (double j : joints) EXPECT_NEAR(j, 0.0, 1e-3) << "mode " << mode;  // a measure moves nothing
  }
}

TEST(ControllerErrorsAgainstSim, ANormalEndIsNoError) {
  Pc pc;
  increments(pc, 0.005f, 50);
  auto server = serve(pc);
  const auto run = play(*server, "steps:\n  - drive_on\n  - go_open: {mode: 5}\n  - wait_for_pc: {timeout: 5}\n  - exit_open\n");
  for (int i = 0; i < 100 && server->state() != H::ServerState::silent; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  server->stop();
  EXPECT_TRUE(run.c->scenario_done()) << run.log();
  EXPECT_EQ(server->controller_errors().names(), "none") << server->summary();
}

}  // namespace
}  // namespace axon::c4g::controller_errors_test

// The manual's robot program per mode (chapter 24, the figure of the program's commands per mode),
// shipped as simulator scenarios in data/c4g/programs/, each played by the simulated controller
// against a ServeSession running the application that serves that mode, over loopback UDP. The
// simulator takes the lenient reply window (the subject is the sequence, not the latency).
#include "axon/c4g/apps/app_factory.hpp"
#include "axon/c4g/apps/serve.hpp"
#include "axon/c4g/apps/trajectory.hpp"
#include "axon/c4g/sim/simulated_controller.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <numbers>
#include <string>
#include <vector>

namespace axon::c4g::manual_programs_test {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

struct Played {
  apps::ServeReport served;
  sim::SimulatedControllerReport seen;
  std::vector<std::int32_t> modes;  // axis 1's modes as the application saw them change
  [[nodiscard]] std::string log() const {
    std::string out = served.text() + "\n";
    for (const auto& e : seen.events) out += e.name + ": " + e.text + "\n";
    return out;
  }
};

Played play(const std::string& program, const apps::AppConfig& config) {
  Played p;
  auto app = apps::make_app(config);
  apps::ServeOptions o;
  o.server.listen = net::Endpoint{"127.0.0.1", 0};
  o.server.max_late_cycles = 0;          // a loaded test machine must not trip the lateness check
  o.server.verify_reply_fields = true;   // every reply carries only the fields its mode uses
  o.stop_timeout_s = 2;
  o.until_controller_ends = true;
  apps::ServeSession session(*app, o);
  session.start();
  sim::SimulatedControllerOptions so;
  so.server = session.local_address();
  so.scenario_file = std::string(AXON_TESTS_DIR) + "/../data/c4g/programs/" + program;
  so.reply_window = sim::ReplyWindow::period;
  so.duration_s = 20;
  auto controller = sim::SimulatedController::start(so);
  apps::ServeSession::Hooks hooks;
  hooks.on_event = [&](const apps::Event& e, const std::string&) {
    if (e.kind == apps::EventKind::mode_change && e.axis == 0) p.modes.push_back(e.aux);
  };
  p.served = session.run(hooks);
  p.seen = controller.wait();
  EXPECT_EQ(p.seen.outcome, sim::SimulatedControllerReport::Outcome::completed) << p.log();
  EXPECT_EQ(p.served.reason, "controller ended the exchange (504)") << p.log();
  EXPECT_EQ(p.served.stats.safety_fault, "none") << p.log();
  EXPECT_TRUE(p.served.error.empty()) << p.log();
  EXPECT_EQ(p.seen.stats.refused_requests, 0u) << p.log();
  for (const auto& e : p.seen.events) EXPECT_NE(e.level, sim::EventLevel::error) << e.name << ": " << e.text;
  return p;
}

apps::AppConfig app(std::string name, int mode = 4) {
  apps::AppConfig c;
  c.app = std::move(name);
  c.mode = mode;
  return c;
}

double joint(const Played& p, std::size_t axis) {
  return p.seen.joint_degrees.size() > 1 && p.seen.joint_degrees[1].size() > axis ? p.seen.joint_degrees[1][axis] : 1e9;
}

TEST(ManualPrograms, Mode0TheControllerMovesAloneAndThePcAnswers) {
  const auto p = play("mode0.yaml", app("monitor"));
  EXPECT_EQ(p.modes, (std::vector<std::int32_t>{501, 0, 504})) << p.log();
  EXPECT_NEAR(joint(p, 0), 0.0, 0.01);
}

TEST(ManualPrograms, Mode0PrimeTheEchoedTargetsMoveTheRobot) {
  const auto p = play("mode0p.yaml", app("echo"));
  EXPECT_EQ(p.modes, (std::vector<std::int32_t>{501, 10, 0, 504})) << p.log();
  EXPECT_NEAR(joint(p, 0), 4.0, 0.05);  // the echoed move arrived
  EXPECT_NEAR(joint(p, 2), -3.0, 0.05);
}

TEST(ManualPrograms, Mode1ThePcHoldsThroughTheSwitchRunsAndExits) {
  auto c = app("pid");
  c.amplitude = {0.5};
  c.frequency_hz = {1};
  c.open_time_s = 0.4;
  const auto p = play("mode1.yaml", c);
  EXPECT_EQ(p.modes, (std::vector<std::int32_t>{501, 0, 1, 11, 0, 504})) << p.log();
  EXPECT_TRUE(p.served.finished) << p.log();
}

TEST(ManualPrograms, Mode2ThePcClosesTheLoopsOnTheProgramsMoveAndTheProgramEndsIt) {
  const auto p = play("mode2.yaml", app("pid"));
  EXPECT_EQ(p.modes, (std::vector<std::int32_t>{501, 2, 12, 0, 504})) << p.log();
  EXPECT_NEAR(joint(p, 0), 3.0, 0.05);
}

TEST(ManualPrograms, Mode4ThePcPlaysItsTrajectoryFromTheApproachPoint) {
  auto c = app("stream", 4);
  c.trajectory = std::make_shared<apps::Trajectory>(
      apps::Trajectory::from_rows({0.0, 0.4}, {{0, 0, 0, 0, 0, 0}, {0, 2 * kDeg, 0, 0, 0, 0}}).value());
  c.relative = true;
  const auto p = play("mode4.yaml", c);
  EXPECT_EQ(p.modes, (std::vector<std::int32_t>{501, 0, 4, 14, 0, 504})) << p.log();
  EXPECT_TRUE(p.served.finished) << p.log();
  EXPECT_NEAR(joint(p, 0), 2.0, 0.05);  // the approach
  EXPECT_NEAR(joint(p, 1), 2.0, 0.05);  // the PC's trajectory
}

TEST(ManualPrograms, Mode5ThePcsIncrementsBecomeTheTrajectory) {
  auto c = app("stream", 5);
  c.trajectory = std::make_shared<apps::Trajectory>(
      apps::Trajectory::from_rows({0.0, 0.4}, {{0, 0, 0, 0, 0, 0}, {3 * kDeg, 0, 0, 0, 0, 0}}).value());
  c.relative = true;
  const auto p = play("mode5.yaml", c);
  EXPECT_EQ(p.modes, (std::vector<std::int32_t>{501, 5, 15, 0, 504})) << p.log();
  EXPECT_TRUE(p.served.finished) << p.log();
  EXPECT_NEAR(joint(p, 0), 3.0, 0.05);
}

TEST(ManualPrograms, Mode7ThePcCorrectsTheProgramsMove) {
  auto c = app("correct");
  c.amplitude = {0.3};
  c.frequency_hz = {2};
  c.open_time_s = 0.3;
  c.ramp_s = 0.1;
  const auto p = play("mode7.yaml", c);
  ASSERT_GE(p.modes.size(), 4u) << p.log();
  EXPECT_EQ(p.modes[1], 7) << p.log();
  EXPECT_TRUE(std::find(p.modes.begin(), p.modes.end(), 170) != p.modes.end()) << p.log();  // 7'' on the way out
  EXPECT_EQ(p.modes.back(), 504);
  EXPECT_TRUE(p.served.finished) << p.log();
}

TEST(ManualPrograms, Mode8And9ThePcAddsToTheControllersLoopsDuringTheMove) {
  for (int mode : {8, 9}) {
    auto c = app("contribute", mode);
    c.amplitude = {mode == 9 ? 2.0 : 0.3};
    c.frequency_hz = {2};
    c.open_time_s = 0.3;
    c.ramp_s = 0.1;
    const auto p = play("mode" + std::to_string(mode) + ".yaml", c);
    EXPECT_EQ(p.modes, (std::vector<std::int32_t>{501, mode, 0, 504})) << p.log();
    EXPECT_TRUE(p.served.finished) << p.log();
    EXPECT_NEAR(joint(p, 0), 3.0, 0.1) << "mode " << mode;  // the program's move still arrives
  }
}

}  // namespace
}  // namespace axon::c4g::manual_programs_test

// AppSwitch: applications put in force and taken out between cycles while the server goes on.
// First with synthetic packets (the test thread plays the cycle thread), then against the
// controller simulator over UDP: a stream that finishes by itself, a correction stopped by request.
#include "axon/c4g/apps/app_switch.hpp"
#include "axon/c4g/apps/correct.hpp"
#include "axon/c4g/apps/stream.hpp"
#include "axon/c4g/apps/trajectory.hpp"
#include "axon/c4g/host/server.hpp"
#include "axon/c4g/protocol/mode.hpp"
#include "axon/c4g/sim/simulated_controller.hpp"
#include "harness.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <thread>

namespace axon::c4g::apps::switch_test {
namespace {

using protocol::code;
using protocol::Mode;

// Counts its cycles, remembers the initialization packet it was set up with, notes its first
// cycle and finishes after `finish_after` cycles (0: never).
class CountingApp final : public App {
 public:
  explicit CountingApp(std::uint64_t finish_after = 0) : finish_after_(finish_after) {}
  [[nodiscard]] std::string_view name() const noexcept override { return "counting"; }
  [[nodiscard]] bool finished() const noexcept override { return finish_after_ > 0 && cycles() >= finish_after_; }
  std::atomic<int> set_up_axes{-1};

 protected:
  void setup(const protocol::InitPacket& init, const protocol::AxisMap&) override { set_up_axes = init.open_axes; }
  void step(const host::CycleContext&, host::ReplyBuilder&) override {
    if (cycles() == 1) note(7);
  }
  [[nodiscard]] std::string note_text(std::int32_t c) const override { return "counting: note " + std::to_string(c); }

 private:
  std::uint64_t finish_after_;
};

// A server that receives nothing: poll() and stop() need one; here it only says "no controller".
std::unique_ptr<host::Server> idle_server(AppSwitch& sw) {
  host::ServerOptions o;
  o.listen = net::Endpoint{"127.0.0.1", 0};
  return host::Server::start(sw, o).value();
}

bool has_text(const std::vector<AppSwitch::Described>& events, std::string_view app, std::string_view needle) {
  return std::any_of(events.begin(), events.end(),
                     [&](const auto& d) { return d.app == app && d.text.find(needle) != std::string::npos; });
}

TEST(AppSwitch, HandsTheCycleToTheInstalledAppAndBackToTheMonitor) {
  AppSwitch sw;
  auto server = idle_server(sw);
  test::Harness h;
  h.start(sw);
  h.set_modes(code(Mode::mode0));
  h.run(sw);
  EXPECT_FALSE(sw.has_app());
  EXPECT_EQ(sw.in_force().app, "monitor");

  auto app = std::make_unique<CountingApp>();
  auto* counting = app.get();
  ASSERT_TRUE(sw.install(std::move(app)));
  EXPECT_EQ(counting->set_up_axes.load(), 6);  // set up at install with the packet the switch had
  EXPECT_EQ(counting->cycles(), 0u);
  h.set_modes(code(Mode::mode4));
  h.run(sw);
  h.run(sw);
  EXPECT_EQ(counting->cycles(), 2u);
  EXPECT_EQ(sw.in_force().app, "counting");
  EXPECT_TRUE(sw.in_force().installed);

  const auto refused = sw.install(std::make_unique<CountingApp>());
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().detail.find("stop it first"), std::string::npos) << refused.error().detail;

  const auto events = sw.drain();
  EXPECT_TRUE(has_text(events, "switch", "mode 0 -> 4")) << events.size();
  EXPECT_TRUE(has_text(events, "counting", "counting: note 7"));

  const auto ended = sw.stop(*server);  // no controller: nothing to leave
  ASSERT_TRUE(ended);
  EXPECT_EQ(ended->app, "counting");
  EXPECT_EQ(ended->reason, "stopped");
  EXPECT_TRUE(ended->left_cleanly);
  EXPECT_FALSE(ended->drive_off);
  EXPECT_FALSE(sw.has_app());
  h.run(sw);  // the monitor again (the counting app is gone)
  EXPECT_EQ(sw.in_force().app, "monitor");
  EXPECT_FALSE(sw.stop(*server));
}

TEST(AppSwitch, AnAppThatFinishesIsTakenOutAtTheNextPoll) {
  AppSwitch sw;
  auto server = idle_server(sw);
  test::Harness h;
  h.start(sw);
  h.set_modes(code(Mode::mode0));
  ASSERT_TRUE(sw.install(std::make_unique<CountingApp>(3)));
  for (int k = 0; k < 2; ++k) h.run(sw);
  EXPECT_FALSE(sw.poll(*server));
  h.run(sw);
  const auto ended = sw.poll(*server);
  ASSERT_TRUE(ended);
  EXPECT_EQ(ended->reason, "finished");
  EXPECT_TRUE(ended->finished);
  EXPECT_FALSE(sw.has_app());
  ASSERT_TRUE(sw.install(std::make_unique<CountingApp>()));  // the next one may come at once
}

TEST(AppSwitch, AnAppInstalledBeforeTheInitializationPacketHearsIt) {
  AppSwitch sw;
  auto app = std::make_unique<CountingApp>();
  auto* counting = app.get();
  ASSERT_TRUE(sw.install(std::move(app)));
  EXPECT_EQ(counting->set_up_axes.load(), -1);
  test::Harness h;
  h.start(sw);
  EXPECT_EQ(counting->set_up_axes.load(), 6);
}

// ---- against the controller simulator over UDP ----

bool wait_until(const std::function<bool()>& pred, double s = 20) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(s);
  while (!pred()) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

bool all_in(const AppSwitch& sw, Mode mode) {
  const auto m = sw.modes();
  return !m.empty() && std::all_of(m.begin(), m.end(), [mode](std::int32_t x) { return x == code(mode); });
}

TEST(AppSwitch, AppsComeAndGoWhileTheServerAnswersOneProgram) {
  AppSwitch sw;
  host::ServerOptions so;
  so.listen = net::Endpoint{"127.0.0.1", 0};
  so.max_late_cycles = 0;  // a loaded test machine must not trip the lateness check
  so.verify_reply_fields = true;
  auto server = host::Server::start(sw, so).value();
  sim::SimulatedControllerOptions co;
  co.server = server->local_address().to_string();
  co.reply_window = sim::ReplyWindow::period;  // lenient: a loaded machine
  co.duration_s = 60;
  co.scenario_yaml = "steps:\n  - drive_on\n  - go_open: {type: A, mode: 4, arms: [1]}\n  - wait_for_pc\n"
                     "  - delay: 0.2\n  - go_open: {type: A, mode: 7, arms: [1]}\n  - wait_for_pc\n  - delay: 0.2\n  - exit_open\n";
  auto controller = sim::SimulatedController::start(co);

  // Mode 4: the monitor holds it until a stream plays its trajectory and leaves by itself.
  ASSERT_TRUE(wait_until([&] { return all_in(sw, Mode::mode4); }));
  StreamOptions s;
  s.trajectory = std::make_shared<Trajectory>(
      Trajectory::from_rows({0.0, 0.3}, {{0, 0, 0, 0, 0, 0}, {1 * test::kDeg, 0, 0, 0, 0, 0}}).value());
  s.relative = true;
  ASSERT_TRUE(sw.install(std::make_unique<StreamApp>(s)));
  std::optional<AppEnded> stream_end;
  ASSERT_TRUE(wait_until([&] { return (stream_end = sw.poll(*server)).has_value(); }));
  EXPECT_EQ(stream_end->reason, "finished") << stream_end->error;
  EXPECT_TRUE(stream_end->left_cleanly);

  // Mode 7: a correction that would go on until stopped; the stop leaves the mode cleanly.
  ASSERT_TRUE(wait_until([&] { return all_in(sw, Mode::mode7); }));
  CorrectOptions c;
  c.amplitude_rad = {0.2 * test::kDeg};
  ASSERT_TRUE(sw.install(std::make_unique<CorrectApp>(c)));
  ASSERT_TRUE(wait_until([&] { return sw.in_force().phase == "running"; }));
  const auto correct_end = sw.stop(*server);
  ASSERT_TRUE(correct_end);
  EXPECT_EQ(correct_end->app, "correct");
  EXPECT_EQ(correct_end->reason, "stopped");
  EXPECT_TRUE(correct_end->left_cleanly);
  EXPECT_FALSE(correct_end->drive_off);
  EXPECT_EQ(sw.installs(), 2u);

  const auto seen = controller.wait();
  EXPECT_EQ(seen.outcome, sim::SimulatedControllerReport::Outcome::completed) << seen.outcome_text;
  EXPECT_FALSE(server->safety().faulted());
  EXPECT_EQ(server->counters().unused_fields.load(), 0u);
  const auto events = sw.drain();
  EXPECT_TRUE(has_text(events, "switch", "mode 0 -> 7"));
}

}  // namespace
}  // namespace axon::c4g::apps::switch_test

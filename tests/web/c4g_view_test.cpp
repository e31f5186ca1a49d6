// web::C4gView: the c4g page's state and metrics, from events handed in by hand (the shapes, the
// START / CRUISE / END of a mode, drives per arm) and from a ServeSession that the simulated
// controller plays the manual's mode-4 program against (the view fed through the session's hooks,
// as `axon c4g serve --http` feeds it). The simulator takes the lenient reply window of one period:
// the subject is what the page shows, not the latency of a loaded test machine.
#include "axon/web/c4g_view.hpp"

#include "axon/c4g/apps/app_factory.hpp"
#include "axon/c4g/apps/serve.hpp"
#include "axon/c4g/apps/trajectory.hpp"
#include "axon/c4g/sim/simulated_controller.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <numbers>
#include <numeric>
#include <set>
#include <sstream>
#include <string>
#include <thread>

namespace axon::web::c4g_view_test {
namespace {

namespace apps = c4g::apps;
namespace host = c4g::host;
namespace sim = c4g::sim;
using json = nlohmann::json;

apps::Event mode_change(int axis, std::int32_t from, std::int32_t to, std::int64_t wall_ns) {
  return apps::Event{apps::EventKind::mode_change, 10, wall_ns, axis, from, to};
}

std::int64_t wall_ns_ago(double s) {
  const auto now = std::chrono::system_clock::now().time_since_epoch();
  return std::chrono::duration_cast<std::chrono::nanoseconds>(now).count() - static_cast<std::int64_t>(s * 1e9);
}

// A server with no controller yet (nothing arrives): the view's shapes before any packet.
struct Idle {
  std::unique_ptr<apps::App> app;
  std::unique_ptr<host::Server> server;
  Idle() {
    apps::AppConfig c;
    c.app = "monitor";
    app = apps::make_app(c);
    host::ServerOptions o;
    o.listen = net::Endpoint{"127.0.0.1", 0};
    server = host::Server::start(*app, o).value();
  }
};

TEST(C4gView, StateHasEveryPartBeforeAnyPacket) {
  Idle rig;
  C4gView view(*rig.app, *rig.server, {.command = "serve --app monitor"});
  const auto s = json::parse(view.state_json());
  for (const char* key : {"t_s", "command", "app", "server", "axes", "arms", "counters", "safety", "timing", "controller_errors", "events"})
    EXPECT_TRUE(s.contains(key)) << key;
  EXPECT_EQ(s["command"], "serve --app monitor");
  EXPECT_EQ(s["app"]["name"], "monitor");
  EXPECT_TRUE(s["app"]["phase"].is_null());  // monitor has no phase machine
  EXPECT_EQ(s["server"]["state"], "waiting for the first packet");
  EXPECT_TRUE(s["server"]["controller"].is_null());
  EXPECT_TRUE(s["axes"].empty());
  EXPECT_EQ(s["timing"]["deadline_us"], 500.0);
  EXPECT_EQ(s["timing"]["cycle_hist"]["width_us"], 20.0);  // 50 bins up to twice the deadline
  EXPECT_EQ(s["timing"]["cycle_hist"]["counts"].size(), 51u);
  EXPECT_EQ(s["safety"]["fault"], "none");
  const auto info = json::parse(view.info_json());
  EXPECT_EQ(info["family"], "c4g");
  bool found = false;
  for (const auto& m : info["modes"])
    if (m["code"] == 11) found = m["label"] == "1'" && m["kind"] == "standby";
  EXPECT_TRUE(found) << info["modes"].dump();
}

TEST(C4gView, ModesTheirLabelsAndPhasesFollowTheEvents) {
  Idle rig;
  C4gView view(*rig.app, *rig.server, {});
  view.add_event({apps::EventKind::drives, 1, wall_ns_ago(5), 1, 1, 0}, "arm 1: drives on");
  view.add_event(mode_change(0, 0, 4, wall_ns_ago(1)), "axis 1: mode 0 -> 4 (mode4)");
  view.add_event(mode_change(1, 0, 1, wall_ns_ago(0.05)), "axis 2: mode 0 -> 1 (mode1)");  // within T1 + T2 + T3
  view.add_event(mode_change(2, 0, 2, wall_ns_ago(1)), "axis 3: mode 0 -> 2 (mode2)");    // past it
  view.add_event(mode_change(3, 0, 14, wall_ns_ago(0.1)), "axis 4: mode 0 -> 14");
  auto s = json::parse(view.state_json());
  ASSERT_EQ(s["axes"].size(), 4u);
  EXPECT_EQ(s["axes"][0]["mode"], 4);
  EXPECT_EQ(s["axes"][0]["label"], "4");
  EXPECT_EQ(s["axes"][0]["phase"], "running");  // mode 4 has no CRUISE: it runs at once
  EXPECT_NEAR(s["axes"][0]["in_mode_s"].get<double>(), 1.0, 0.5);
  EXPECT_EQ(s["axes"][1]["phase"], "start");
  EXPECT_EQ(s["axes"][2]["phase"], "cruise");
  EXPECT_EQ(s["axes"][3]["label"], "4'");
  EXPECT_EQ(s["axes"][3]["phase"], "end");
  EXPECT_EQ(s["arms"][0]["drives"], "on");
  EXPECT_EQ(s["events"].size(), 5u);
  EXPECT_EQ(s["events"].back()["text"], "axis 4: mode 0 -> 14");

  view.add_event({apps::EventKind::drives, 2, wall_ns_ago(0), 1, 0, 0}, "arm 1: drives off");
  view.add_event({apps::EventKind::silence, 3, wall_ns_ago(0), -1, 0, 0}, "no packets from the controller");
  s = json::parse(view.state_json());
  EXPECT_EQ(s["arms"][0]["drives"], "off");
  EXPECT_EQ(s["arms"][0]["drives_off"], 1);
  EXPECT_EQ(s["axes"][0]["mode"], 0);  // after silence: mode 0 until the next change
  EXPECT_EQ(s["axes"][0]["phase"], "");
  const auto m = view.metrics();
  EXPECT_NE(m.find("axon_c4g_drives_off_total{arm=\"1\"} 1\n"), std::string::npos) << m;
}

// Every family announced once with HELP and TYPE, every sample under one; histograms cumulative.
void check_exposition(const std::string& text) {
  std::istringstream in(text);
  std::string line, family;
  std::set<std::string> seen;
  double last_bucket = -1;
  while (std::getline(in, line)) {
    if (line.rfind("# HELP ", 0) == 0) {
      family = line.substr(7, line.find(' ', 7) - 7);
      EXPECT_TRUE(seen.insert(family).second) << "twice: " << family;
      last_bucket = -1;
      continue;
    }
    if (line.rfind("# TYPE ", 0) == 0) continue;
    ASSERT_EQ(line.rfind(family, 0), 0u) << line << " outside " << family;
    if (line.find("_bucket{") != std::string::npos) {
      const double v = std::stod(line.substr(line.rfind(' ') + 1));
      EXPECT_GE(v, last_bucket) << line;
      last_bucket = v;
    }
  }
  EXPECT_GT(seen.size(), 20u);
}

struct Played {
  std::vector<json> states;  // at each poll
  json final_state;
  std::string metrics;
  apps::ServeReport served;
  sim::SimulatedControllerReport seen;
};

Played play_mode4() {
  apps::AppConfig c;
  c.app = "stream";
  c.mode = 4;
  constexpr double kDeg = std::numbers::pi / 180.0;
  c.trajectory = std::make_shared<apps::Trajectory>(
      apps::Trajectory::from_rows({0.0, 0.4}, {{0, 0, 0, 0, 0, 0}, {0, 2 * kDeg, 0, 0, 0, 0}}).value());
  c.relative = true;
  auto app = apps::make_app(c);
  apps::ServeOptions o;
  o.server.listen = net::Endpoint{"127.0.0.1", 0};
  o.server.max_late_cycles = 0;  // a loaded test machine must not trip the lateness check
  o.stop_timeout_s = 2;
  o.until_controller_ends = true;
  o.duration_s = 30;  // a controller that gave up must not leave the test waiting
  apps::ServeSession session(*app, o);
  session.start();
  C4gView view(*app, session.server(), {.command = "serve --app stream --mode 4"});
  sim::SimulatedControllerOptions so;
  so.server = session.local_address();
  so.scenario_file = std::string(AXON_TESTS_DIR) + "/../data/c4g/programs/mode4.yaml";
  so.reply_window = sim::ReplyWindow::period;
  so.duration_s = 20;
  auto controller = sim::SimulatedController::start(so);
  Played p;
  apps::ServeSession::Hooks hooks;
  hooks.on_event = [&](const apps::Event& e, const std::string& text) { view.add_event(e, text); };
  hooks.on_poll = [&] { p.states.push_back(json::parse(view.state_json())); };
  p.served = session.run(hooks);
  p.seen = controller.wait();
  p.final_state = json::parse(view.state_json());
  p.metrics = view.metrics();
  return p;
}

TEST(C4gViewAgainstSim, ShowsTheModeAMode4ProgramSwitchesToAndTheCycleTiming) {
  const auto p = play_mode4();
  std::string seen;
  for (const auto& e : p.seen.events) seen += e.name + ": " + e.text + "\n";
  ASSERT_EQ(p.seen.outcome, sim::SimulatedControllerReport::Outcome::completed) << p.seen.outcome_text << "\n" << seen << p.served.text();
  // Some poll saw axis 1 in mode 4 with the stream running, the arm's drives on.
  bool in_mode4 = false;
  for (const auto& s : p.states) {
    if (s["axes"].size() != 6 || s["axes"][0]["mode"] != 4) continue;
    in_mode4 = true;
    EXPECT_EQ(s["axes"][0]["label"], "4");
    EXPECT_EQ(s["axes"][0]["arm"], 1);
    EXPECT_EQ(s["arms"][0]["drives"], "on");
    EXPECT_TRUE(s["app"]["phase"] == "running" || s["app"]["phase"] == "holding" || s["app"]["phase"] == "exiting" ||
                s["app"]["phase"] == "waiting")
        << s["app"];
  }
  EXPECT_TRUE(in_mode4);
  const auto& f = p.final_state;
  EXPECT_EQ(f["app"]["phase"], "done");
  EXPECT_EQ(f["axes"][0]["mode"], 504);  // the program ended the exchange
  EXPECT_EQ(f["server"]["period_ms"], 2.0);
  EXPECT_GT(f["axes"][0]["fe_threshold"].get<double>(), 0.0);
  // Every cycle timed lands in the receive-to-send histogram; the periods in the other.
  const auto cycles = f["timing"]["cycles"].get<std::uint64_t>();
  const auto counts = f["timing"]["cycle_hist"]["counts"].get<std::vector<std::uint64_t>>();
  EXPECT_GT(cycles, 500u);
  EXPECT_EQ(std::accumulate(counts.begin(), counts.end(), std::uint64_t{0}), cycles);
  const auto periods = f["timing"]["period_hist"]["counts"].get<std::vector<std::uint64_t>>();
  EXPECT_EQ(f["timing"]["period_hist"]["width_us"], 80.0);  // 2 ms over 25 bins: up to twice the period
  EXPECT_EQ(std::accumulate(periods.begin(), periods.end(), std::uint64_t{0}), cycles - 1);
  EXPECT_EQ(f["counters"]["cyclic"].get<std::uint64_t>(), p.served.stats.cyclic_packets);
  EXPECT_EQ(f["safety"]["fault"], "none");

  check_exposition(p.metrics);
  for (const char* family : {"axon_c4g_cycles_total", "axon_c4g_late_replies_total", "axon_c4g_drive_off_replies_total",
                             "axon_c4g_cycle_time_seconds", "axon_c4g_inter_packet_period_seconds", "axon_c4g_axis_mode",
                             "axon_c4g_app_phase"})
    EXPECT_NE(p.metrics.find(std::string("# TYPE ") + family + " "), std::string::npos) << family;
  EXPECT_NE(p.metrics.find("axon_c4g_cycle_time_seconds_count " + std::to_string(cycles) + "\n"), std::string::npos) << p.metrics;
  EXPECT_NE(p.metrics.find("axon_c4g_app_phase{phase=\"done\"} 1\n"), std::string::npos);
  EXPECT_NE(p.metrics.find("axon_c4g_axis_mode{axis=\"1\",arm=\"1\"} 504\n"), std::string::npos);
}

}  // namespace
}  // namespace axon::web::c4g_view_test

// The c4g actor without a broker: its replies go to a collector; the server it commands answers a
// simulated controller in this process over UDP on loopback (lenient reply window: a loaded
// machine), which plays open phases in modes 4 and 7 for the PC, one after the other.
#include "axon/actor/c4g_actor.hpp"
#include "axon/c4g/apps/app_switch.hpp"
#include "axon/c4g/host/server.hpp"
#include "axon/c4g/sim/simulated_controller.hpp"
#include "replies.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

namespace axon::actor::c4g_actor_test {
namespace {

using test::body_of;
using test::code_of;
using test::command;

constexpr const char* kProgram =
    "steps:\n"
    "  - drive_on\n"
    "  - go_open: {type: A, mode: 4, arms: [1]}\n"
    "  - wait_for_pc: {arms: [1]}\n"
    "  - delay: 0.2\n"
    "  - go_open: {type: A, mode: 7, arms: [1]}\n"
    "  - wait_for_pc: {arms: [1]}\n"
    "  - run\n";

// Changes from one mode to another in a mode_changes keyword.
long changes_in(const nlohmann::json& changes, const std::string& from, const std::string& to) {
  return std::count_if(changes.begin(), changes.end(),
                       [&](const auto& c) { return c["from_label"] == from && c["to_label"] == to; });
}

bool has(const nlohmann::json& kw, const std::string& needle) {
  return kw.contains("error") && kw["error"].get<std::string>().find(needle) != std::string::npos;
}

struct C4gActorOnSimulator : ::testing::Test {
  std::string program = kProgram;
  c4g::apps::AppSwitch apps{{2.0, 1.0}};
  std::unique_ptr<c4g::host::Server> server;
  std::unique_ptr<c4g::sim::SimulatedController> controller;
  test::Replies out;
  ActorCore core{"c4g", out.sink()};
  std::unique_ptr<C4gActor> actor;
  std::filesystem::path dir;
  int next_id = 0;

  void SetUp() override {
    c4g::host::ServerOptions so;
    so.listen = net::Endpoint{"127.0.0.1", 0};
    so.max_late_cycles = 0;  // a loaded test machine must not trip the lateness check
    so.verify_reply_fields = true;
    server = c4g::host::Server::start(apps, so).value();
    c4g::sim::SimulatedControllerOptions co;
    co.server = server->local_address().to_string();
    co.reply_window = c4g::sim::ReplyWindow::period;
    co.scenario_yaml = program;
    controller = std::make_unique<c4g::sim::SimulatedController>(c4g::sim::SimulatedController::start(co));
    actor = std::make_unique<C4gActor>(core, apps, *server, C4gActorOptions{0.0, 0.02, 1.0, 3.0});
    dir = std::filesystem::temp_directory_path() / fmt::format("axon-c4g-actor-{}-{}", ::getpid(), next_id++);
    std::filesystem::create_directories(dir);
  }
  void TearDown() override {
    actor.reset();
    std::filesystem::remove_all(dir);
  }

  // Sends `text` and returns its final reply (a failed wait is a failed test).
  nlohmann::json run(const std::string& text, char expected = ':') {
    const auto id = fmt::format("c{}", ++next_id);
    core.handle(command(text, id));
    const auto r = out.final_of(id);
    EXPECT_TRUE(r) << text;
    if (!r) return {};
    EXPECT_EQ(code_of(*r), expected) << text << ": " << r->body;
    return body_of(*r);
  }
  // Waits until every axis shows `label` in status.
  bool wait_for_mode(const std::string& label) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (std::chrono::steady_clock::now() < until) {
      const auto axes = run("status")["axes"];
      if (!axes.empty() && std::all_of(axes.begin(), axes.end(), [&](const auto& a) { return a["label"] == label; }))
        return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
  }
  // A broadcast carrying `keyword` for which `pred` holds.
  std::optional<Message> broadcast_with(const std::string& keyword, const std::function<bool(const nlohmann::json&)>& pred) {
    return out.wait_for([&](const Message& m) {
      if (m.routing_key != "reply.broadcast") return false;
      const auto kw = body_of(m);
      return kw.contains(keyword) && pred(kw[keyword]);
    });
  }
  // Waits until the mode_changes broadcasts so far show every axis going from `from` to `to` (the
  // six changes of one packet may come in two broadcasts: the watcher drains while they are queued).
  bool every_axis_changed(const std::string& from, const std::string& to) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (std::chrono::steady_clock::now() < until) {
      long seen = 0;
      {
        std::lock_guard lock(out.mutex);
        for (const auto& m : out.messages)
          if (m.routing_key == "reply.broadcast" && body_of(m).contains("mode_changes"))
            seen += changes_in(body_of(m)["mode_changes"], from, to);
      }
      if (seen >= 6) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
  }
  std::string trajectory(const std::string& name, double first_deg) {
    const auto path = dir / name;
    std::ofstream(path) << "# units: deg\nt,j1,j2,j3,j4,j5,j6\n0," << first_deg << ",0,0,0,0,0\n0.3," << first_deg + 1
                        << ",0,0,0,0,0\n";
    return path.string();
  }
};

TEST_F(C4gActorOnSimulator, StatusShowsTheServerEachAxisModeTheDrivesAndTheMonitor) {
  ASSERT_TRUE(wait_for_mode("4"));
  auto kw = run("status");
  EXPECT_EQ(kw["server"]["state"], "running");
  EXPECT_EQ(kw["server"]["address"], server->local_address().to_string());
  EXPECT_TRUE(kw["server"]["controller"].is_string());
  EXPECT_EQ(kw["server"]["period_ms"], 2.0);
  ASSERT_EQ(kw["axes"].size(), 6u);
  EXPECT_EQ(kw["axes"][5]["arm"], 1);
  EXPECT_EQ(kw["axes"][5]["arm_axis"], 6);
  EXPECT_EQ(kw["axes"][0]["mode"], 4);
  ASSERT_FALSE(kw["drives"].empty());
  EXPECT_EQ(kw["drives"][0], (nlohmann::json{{"arm", 1}, {"on", true}}));
  EXPECT_EQ(kw["app"]["name"], "monitor");
  EXPECT_EQ(kw["app"]["installed"], false);
  EXPECT_EQ(kw["safety"]["fault"], "none");
  EXPECT_TRUE(kw["last_app"].is_null());
  EXPECT_TRUE(has(run("status now", 'f'), "status takes no argument"));
}

TEST_F(C4gActorOnSimulator, AStreamServesThePhaseFinishesAndTheModeChangesAreBroadcast) {
  ASSERT_TRUE(wait_for_mode("4"));
  auto started = run("start stream --file " + trajectory("rel.csv", 0) + " --relative");
  EXPECT_EQ(started["app"]["name"], "stream");
  EXPECT_EQ(started["app"]["installed"], true);
  const auto ended = broadcast_with("app_ended", [](const auto& e) { return e["name"] == "stream"; });
  ASSERT_TRUE(ended);
  EXPECT_EQ(code_of(*ended), 'i');
  EXPECT_EQ(body_of(*ended)["app_ended"]["reason"], "finished");
  EXPECT_EQ(body_of(*ended)["app_ended"]["left_cleanly"], true);
  // Out of mode 4 through its standby code, and into the program's mode 7 phase.
  EXPECT_TRUE(every_axis_changed("4", "4'"));
  EXPECT_TRUE(every_axis_changed("4'", "0"));
  EXPECT_TRUE(every_axis_changed("0", "7"));
  EXPECT_EQ(run("status")["last_app"]["name"], "stream");
}

TEST_F(C4gActorOnSimulator, ASecondStartIsRefusedAndStopLeavesTheOpenModeCleanly) {
  ASSERT_TRUE(wait_for_mode("4"));
  ASSERT_TRUE(run("start stream --file " + trajectory("rel.csv", 0) + " --relative").contains("app"));
  ASSERT_TRUE(wait_for_mode("7"));
  run("start correct --amplitude 0.2");  // a correction that goes on until stopped
  auto refused = run("start echo", 'f');
  EXPECT_NE(refused["error"].get<std::string>().find("correct is in force: stop it first"), std::string::npos) << refused;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (run("status")["app"]["phase"] != "running" && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  auto stopped = run("stop");
  ASSERT_TRUE(stopped.contains("app_ended")) << stopped;
  EXPECT_EQ(stopped["app_ended"]["name"], "correct");
  EXPECT_EQ(stopped["app_ended"]["reason"], "stopped");
  EXPECT_EQ(stopped["app_ended"]["left_cleanly"], true);
  EXPECT_EQ(stopped["app_ended"]["drive_off"], false);
  EXPECT_EQ(stopped["safety"]["latched"], false);
  EXPECT_TRUE(wait_for_mode("0"));  // the program's `run`: mode 0 from now on
  EXPECT_EQ(run("status")["app"]["name"], "monitor");
  EXPECT_EQ(run("stop")["text"], "no application in force: the monitor answers");
}

TEST_F(C4gActorOnSimulator, AnAppThatHoldsNoModeIsStoppedAtOnce) {
  ASSERT_TRUE(wait_for_mode("4"));  // the program's phase, not the apps'
  for (const std::string app : {"echo", "monitor", "correct --amplitude 0.2"}) {  // correct waits for mode 7
    run("start " + app);
    auto stopped = run("stop");
    ASSERT_TRUE(stopped.contains("app_ended")) << stopped;
    EXPECT_EQ(stopped["app_ended"]["name"], app.substr(0, app.find(' ')));
    EXPECT_EQ(stopped["app_ended"]["left_cleanly"], true);
    EXPECT_EQ(stopped["app_ended"]["drive_off"], false);
    EXPECT_LT(stopped["app_ended"]["in_force_s"].get<double>(), 1.5);  // not the stop timeout (2 s here)
  }
  EXPECT_EQ(run("status")["axes"][0]["label"], "4");
}

TEST_F(C4gActorOnSimulator, AnAppThatRefusesIsReportedWithItsErrorAndTakenOut) {
  ASSERT_TRUE(wait_for_mode("4"));
  run("start stream --file " + trajectory("far.csv", 30));  // absolute: 30 deg away from the robot
  const auto ended = broadcast_with("app_ended", [](const auto&) { return true; });
  ASSERT_TRUE(ended);
  EXPECT_EQ(code_of(*ended), 'e');
  auto e = body_of(*ended)["app_ended"];
  EXPECT_EQ(e["reason"], "refused");
  EXPECT_FALSE(e["error"].get<std::string>().empty());
  EXPECT_EQ(run("status")["app"]["name"], "monitor");
}

TEST_F(C4gActorOnSimulator, BadStartsFailWithAReason) {
  const std::pair<std::string, std::string> cases[] = {
      {"start", "start takes APP"},
      {"start fly", "unknown --app 'fly'"},
      {"start correct --amplitude big", "--amplitude takes a number"},
      {"start correct --bogus 1", "unknown option"},
      {"start correct --open-time", "--open-time takes a value"},
      {"start stream", "needs --file"},
      {"start stream --file /nonexistent.csv", "nonexistent"},
  };
  for (const auto& [text, reason] : cases) {
    auto kw = run(text, 'f');
    EXPECT_NE(kw["error"].get<std::string>().find(reason), std::string::npos) << text << ": " << kw;
  }
  EXPECT_EQ(run("status")["app"]["name"], "monitor");
}

TEST_F(C4gActorOnSimulator, StatsGivesTheCountersAndTheTimingFigures) {
  ASSERT_TRUE(wait_for_mode("4"));
  auto s = run("stats")["stats"];
  EXPECT_GT(s["cyclic_packets"].get<std::uint64_t>(), 0u);
  EXPECT_EQ(s["init_packets"], 1);
  EXPECT_EQ(s["safety_fault"], "none");
  EXPECT_GT(s["timing"]["cycles"].get<std::uint64_t>(), 0u);
  EXPECT_EQ(s["timing"]["nominal_period_s"], 0.002);
  EXPECT_EQ(s["timing"]["inter_packet_period_s"].size(), 2u);
  EXPECT_TRUE(s["timing"].contains("missed_deadlines"));
  EXPECT_GT(s["reply_latency"]["count"].get<std::uint64_t>(), 0u);
}

// Takes 0.7 ms of every cycle: over the server's 400 us budget and its 500 us deadline.
class SlowApp final : public c4g::apps::App {
 public:
  [[nodiscard]] std::string_view name() const noexcept override { return "slow"; }

 protected:
  void step(const c4g::host::CycleContext&, c4g::host::ReplyBuilder&) override {
    const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(700);
    while (std::chrono::steady_clock::now() < until) {
    }
  }
};

TEST_F(C4gActorOnSimulator, LateCyclesAreBroadcastAtMostOnceASecond) {
  ASSERT_TRUE(wait_for_mode("4"));
  ASSERT_TRUE(apps.install(std::make_unique<SlowApp>()));  // no built-in app is this slow
  const auto late = broadcast_with("late", [](const auto& l) { return l["new_controller_late"] > 0; });
  ASSERT_TRUE(late);
  EXPECT_EQ(code_of(*late), 'w');
  EXPECT_GT(body_of(*late)["late"]["new_missed_deadlines"].get<std::uint64_t>(), 0u);
  auto count = [this] {
    std::lock_guard lock(out.mutex);
    return std::count_if(out.messages.begin(), out.messages.end(), [](const Message& m) {
      return m.routing_key == "reply.broadcast" && body_of(m).contains("late");
    });
  };
  const auto before = count();
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  EXPECT_LE(count() - before, 2);  // at most one a second, though every cycle is late
}

// A program that goes on after a drive off ended its open phase (the default one would then fail
// its next GO OPEN and stop sending, and a reset takes effect only at the next packet).
struct C4gActorAfterDriveOff : C4gActorOnSimulator {
  C4gActorAfterDriveOff() { program = "steps:\n  - drive_on\n  - go_open: {type: A, mode: 4, arms: [1]}\n  - wait_for_pc\n  - run\n"; }
};

// A program that stays in mode 0 with the drives on: what active freezing needs.
struct C4gActorInMode0 : C4gActorOnSimulator {
  C4gActorInMode0() { program = "steps:\n  - drive_on\n  - run\n"; }
};

TEST_F(C4gActorInMode0, FreezeAndReleaseTheExchange) {
  ASSERT_TRUE(wait_for_mode("0"));
  EXPECT_EQ(run("status")["server"]["freeze"], "off");
  EXPECT_EQ(run("freeze")["server"]["freeze"], "frozen");
  EXPECT_EQ(run("status")["axes"][0]["label"], "500");
  EXPECT_EQ(run("release")["server"]["freeze"], "off");
  EXPECT_TRUE(wait_for_mode("0"));
}

TEST_F(C4gActorAfterDriveOff, DriveOffIsObeyedBroadcastAndResetClearsIt) {
  ASSERT_TRUE(wait_for_mode("4"));
  auto off = run("driveoff");
  EXPECT_EQ(off["safety"]["latched"], true);
  EXPECT_EQ(off["safety"]["obeyed"], true);
  EXPECT_TRUE(broadcast_with("drive_off", [](const auto& d) { return d["reason"] == "user_request"; }));
  auto refused = run("start echo", 'f');
  EXPECT_NE(refused["error"].get<std::string>().find("reset it first"), std::string::npos) << refused;
  auto reset = run("reset");
  EXPECT_EQ(reset["safety"]["latched"], false);
  EXPECT_EQ(run("reset")["text"], "no fault latched");
}

}  // namespace
}  // namespace axon::actor::c4g_actor_test

// The blmc actor on a motor driver board simulated in this process, without a broker: its replies
// go to a collector. The waits are bounded polls of the simulator or the replies, never timing
// assertions (the machines that run these are loaded).
#include "axon/actor/blmc_actor.hpp"
#include "axon/blmc/host/motor_board.hpp"
#include "axon/blmc/sim/simulated_board.hpp"
#include "replies.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <thread>

namespace axon::actor::blmc_actor_test {

using namespace std::chrono_literals;
using test::body_of;
using test::code_of;
using test::command;

blmc::sim::SimulatedBoardOptions sim_options() {
  blmc::sim::SimulatedBoardOptions o;
  o.config.alignment_time = 200ms;
  return o;
}

blmc::MotorBoardOptions board_options() {
  blmc::MotorBoardOptions o;
  o.recv_timeout_ms = 250;  // a simulator on a loaded machine needs the slack a real board does not
  return o;
}

// Limits with slack for a loaded machine (not what these tests are about), no real-time request.
BlmcActorOptions actor_options() {
  BlmcActorOptions o;
  o.status_period_s = 0;
  o.control.realtime = false;
  o.control.limits.stale_after = 200ms;
  o.front_end.stale_after = 2s;
  o.recv_timeout_ms = 250;
  return o;
}

bool eventually(const std::function<bool()>& done, std::chrono::milliseconds limit = 10s) {
  for (auto t = 0ms; t < limit; t += 10ms) {
    if (done()) return true;
    std::this_thread::sleep_for(10ms);
  }
  return done();
}

struct BlmcActorOnSim : ::testing::Test {
  blmc::sim::SimulatedBoard sim{sim_options()};
  blmc::MotorBoard board{sim.bus_spec(), board_options()};
  test::Replies out;
  ActorCore core{"blmc", out.sink()};
  std::unique_ptr<BlmcActor> actor;
  int next = 0;

  void SetUp() override { actor = std::make_unique<BlmcActor>(core, board, actor_options()); }

  // The final reply to `text`.
  Message run(const std::string& text) {
    const auto id = std::to_string(next++);
    core.handle(command(text, id));
    const auto r = out.final_of(id);
    if (!r) ADD_FAILURE() << "no final reply to " << text;
    return r ? *r : Message{};
  }
  nlohmann::json done(const std::string& text) {
    const auto r = run(text);
    EXPECT_EQ(code_of(r), ':') << text << ": " << r.body;
    return body_of(r);
  }
  std::string failure(const std::string& text) {
    const auto r = run(text);
    EXPECT_EQ(code_of(r), 'f') << text << ": " << r.body;
    return body_of(r).value("error", "");
  }
  std::optional<Message> broadcast_with(const std::string& keyword) {
    return out.wait_for([&](const Message& m) { return m.routing_key == kBroadcastKey && body_of(m).contains(keyword); });
  }
  bool board_off() const {
    const auto r = sim.report();
    return !r.status.system_enabled && !r.motors[0].enabled && !r.motors[1].enabled && r.motors[0].iq_ref_a == 0.0 &&
           r.motors[1].iq_ref_a == 0.0;
  }
  void enable_and_start() {
    done("enable");
    done("start");
  }
};

TEST_F(BlmcActorOnSim, StatusGivesTheBoardBothMotorsTheLimitsAndNoLoop) {
  const auto kw = done("status");
  EXPECT_EQ(kw["stale"], false);
  ASSERT_EQ(kw["board"]["motors"].size(), 2u) << kw;
  EXPECT_EQ(kw["board"]["motors"][1]["motor"], 2);
  EXPECT_EQ(kw["board_error"]["code"], 0);
  EXPECT_EQ(kw["board_error"]["meaning"], "no error");
  EXPECT_EQ(kw["loop"]["running"], false);
  EXPECT_EQ(kw["limits"]["max_current_a"], 2.0);
  EXPECT_EQ(kw["last_run"], nullptr);
  EXPECT_FALSE(kw.contains("action"));
}

// The whole session a commander runs: enable, start, currents, pd, stop, disable; each answer says
// what is now in force, and the simulated board sees the currents.
TEST_F(BlmcActorOnSim, EnableStartCurrentsPdStopDisableDriveTheBoard) {
  auto kw = done("enable");
  EXPECT_EQ(kw["board"]["enabled"], true);
  EXPECT_EQ(kw["board"]["motors"][0]["ready"], true) << kw;
  kw = done("start --max-current 1.5");
  EXPECT_EQ(kw["loop"]["running"], true);
  EXPECT_EQ(kw["limits"]["max_current_a"], 1.5);
  EXPECT_EQ(kw["action"]["motors"][0]["mode"], "idle");

  kw = done("currents 0.3 -0.2");
  EXPECT_EQ(kw["action"]["motors"][0]["mode"], "current");
  EXPECT_EQ(kw["action"]["motors"][1]["current_a"], -0.2);
  EXPECT_TRUE(eventually([&] { return std::abs(sim.report().motors[0].iq_ref_a - 0.3) < 1e-3; }));
  EXPECT_TRUE(eventually([&] { return std::abs(sim.report().motors[1].iq_ref_a + 0.2) < 1e-3; }));
  kw = done("current 2 0.1");
  EXPECT_EQ(kw["action"]["motors"][0]["current_a"], 0.3);  // motor 1 keeps its current
  EXPECT_EQ(kw["action"]["motors"][1]["current_a"], 0.1);

  const auto here = done("status")["board"]["motors"];
  kw = done("pd " + std::to_string(here[0]["position_rev"].get<double>()) + " " +
            std::to_string(here[1]["position_rev"].get<double>()) + " 4 0.05");
  EXPECT_EQ(kw["action"]["motors"][1]["mode"], "pd");
  EXPECT_EQ(kw["action"]["motors"][1]["kp"], 4.0);
  kw = done("status");
  EXPECT_EQ(kw["loop"]["running"], true);
  EXPECT_EQ(kw["action"]["motors"][0]["mode"], "pd");
  EXPECT_GT(kw["loop"]["back_end"]["cycles"].get<std::uint64_t>(), 0u);
  EXPECT_EQ(done("idle")["action"]["motors"][0]["mode"], "idle");

  kw = done("stop");
  EXPECT_EQ(kw["stopped"]["end"], "requested") << kw;
  EXPECT_GT(kw["stopped"]["cycles"].get<std::uint64_t>(), 0u);
  EXPECT_EQ(kw["board"]["enabled"], true);  // still enabled, at zero current
  EXPECT_EQ(done("status")["last_run"]["end"], "requested");
  EXPECT_NE(failure("currents 0.1 0.1").find("no control loop runs"), std::string::npos);
  EXPECT_EQ(done("disable")["board"]["enabled"], false);
  EXPECT_TRUE(eventually([&] { return board_off(); }));
}

TEST_F(BlmcActorOnSim, RefusesActionsWithoutALoopASecondStartAndBadArguments) {
  EXPECT_NE(failure("currents 0.1 0").find("no control loop runs (start it first)"), std::string::npos);
  EXPECT_NE(failure("start").find("not enabled (enable first)"), std::string::npos);
  EXPECT_EQ(done("stop")["text"], "no control loop was running");
  enable_and_start();
  EXPECT_NE(failure("start").find("already runs"), std::string::npos);
  EXPECT_NE(failure("enable").find("the control loop runs"), std::string::npos);
  EXPECT_NE(failure("recover").find("stop it first"), std::string::npos);
  EXPECT_NE(failure("currents 0.1").find("currents takes A1 A2"), std::string::npos);
  EXPECT_NE(failure("currents 3 0").find("beyond the current limit"), std::string::npos);
  EXPECT_NE(failure("currents one 0").find("not a number"), std::string::npos);
  EXPECT_NE(failure("current 3 0.1").find("MOTOR (1 or 2)"), std::string::npos);
  EXPECT_NE(failure("pd 0 0 -1 0").find("must not be negative"), std::string::npos);
  EXPECT_NE(failure("pd 0").find("pd takes P1 P2"), std::string::npos);
  done("stop");
  EXPECT_NE(failure("start --max-current 9").find("the actor's limit"), std::string::npos);
  EXPECT_NE(failure("start --speed 1").find("start takes"), std::string::npos);
}

// The bus is the front end: once the broker is gone nobody may be steering, so the motors get the
// idle action (zero current) at once, and every listener is told once the broker is back.
TEST_F(BlmcActorOnSim, BrokerLossSetsTheIdleActionAndWarnsOnReconnection) {
  enable_and_start();
  done("currents 0.3 0.3");
  ASSERT_TRUE(eventually([&] { return sim.report().motors[0].iq_ref_a > 0.2; }));
  actor->broker_state(false);
  EXPECT_TRUE(eventually([&] {
    const auto r = sim.report();
    return r.motors[0].iq_ref_a == 0.0 && r.motors[1].iq_ref_a == 0.0;
  }));
  const auto kw = done("status");
  EXPECT_EQ(kw["action"]["motors"][0]["mode"], "idle");
  EXPECT_EQ(kw["action"]["by"], "broker lost");
  EXPECT_EQ(kw["loop"]["running"], true);  // the loop goes on: the board keeps being fed zero current
  actor->broker_state(true);
  const auto warning = broadcast_with("broker_lost");
  ASSERT_TRUE(warning);
  EXPECT_EQ(code_of(*warning), 'w');
  const auto lost = body_of(*warning)["broker_lost"];
  EXPECT_EQ(lost["idle_set"], true);
  EXPECT_EQ(lost["action_before"]["motors"][0]["current_a"], 0.3);
  const auto faults = done("errors")["faults"];
  ASSERT_FALSE(faults.empty());
  EXPECT_EQ(faults.back()["source"], "broker");
}

// A board error during control: the loop's safety stop (zero current, motors off) reaches every
// listener with the library's fault text; actions are refused until a new start; errors lists it
// and recover brings the board back.
TEST_F(BlmcActorOnSim, ABoardFaultIsASafetyStopThatEveryListenerHearsWithItsText) {
  enable_and_start();
  done("currents 0.1 0");
  ASSERT_TRUE(eventually([&] { return sim.report().motors[0].iq_ref_a > 0.05; }));
  sim.inject(blmc::sim::FaultKind::encoder);
  const auto alert = broadcast_with("safety_stop");
  ASSERT_TRUE(alert);
  EXPECT_EQ(code_of(*alert), 'e');
  const auto stop = body_of(*alert)["safety_stop"];
  EXPECT_EQ(stop["end"], "fault");
  EXPECT_NE(stop["text"].get<std::string>().find("ENCODER"), std::string::npos) << stop;
  EXPECT_NE(failure("currents 0.1 0").find("the last run ended"), std::string::npos);
  const auto board_error = broadcast_with("board_error");
  ASSERT_TRUE(board_error);
  EXPECT_EQ(body_of(*board_error)["board_error"]["name"], "ENCODER");
  const auto errors = done("errors");
  EXPECT_EQ(errors["last_run"]["end"], "fault");
  bool listed = false;
  for (const auto& f : errors["faults"]) listed = listed || (f["source"] == "safety_stop" && f["text"] == stop["text"]);
  EXPECT_TRUE(listed) << errors;
  const auto recovered = done("recover");
  EXPECT_EQ(recovered["board_error"]["code"], 0) << recovered;
  done("start");
  done("currents 0.1 0");
}

// home finds each motor's index under its own loop; it needs the motors enabled and no loop running.
TEST_F(BlmcActorOnSim, HomeFindsBothIndexMarksWhenNoLoopRuns) {
  EXPECT_NE(failure("home").find("not enabled"), std::string::npos);
  enable_and_start();
  EXPECT_NE(failure("home").find("the control loop runs"), std::string::npos);
  done("stop");
  EXPECT_NE(failure("home 0").find("not 0"), std::string::npos);
  const auto kw = done("home 1");
  EXPECT_EQ(kw["homing"]["all_found"], true) << kw;
  EXPECT_EQ(kw["homing"]["motors"][1]["state"], "found");
  EXPECT_TRUE(kw["homing"]["motors"][0]["index_rev"].is_number());
  EXPECT_EQ(kw["stopped"]["end"], "requested");
}

TEST_F(BlmcActorOnSim, DisableDuringTheLoopStopsItAndTurnsTheMotorsOff) {
  enable_and_start();
  done("currents 0.2 0.2");
  const auto kw = done("disable");
  EXPECT_EQ(kw["stopped"]["end"], "requested");
  EXPECT_EQ(kw["loop"]["running"], false);
  EXPECT_TRUE(eventually([&] { return board_off(); }));
}

// disable is the one command that is never refused: sent while an enable waits for the alignment,
// it interrupts that wait and the motors end off.
TEST_F(BlmcActorOnSim, DisableIsNeverRefusedAndInterruptsAnEnableInProgress) {
  core.handle(command("enable", "e"));
  const auto d = run("disable");
  EXPECT_EQ(code_of(d), ':') << d.body;
  const auto e = out.final_of("e");
  ASSERT_TRUE(e);  // done or interrupted, depending on how far it got: either way it ended
  if (code_of(*e) == 'f') {
    EXPECT_NE(body_of(*e)["error"].get<std::string>().find("stopped on request"), std::string::npos) << e->body;
  }
  EXPECT_TRUE(eventually([&] { return board_off(); }));
  EXPECT_EQ(done("status")["board"]["enabled"], false);
}

TEST_F(BlmcActorOnSim, TheDestructorStopsTheLoopAndDisablesTheMotors) {
  enable_and_start();
  done("currents 0.2 -0.2");
  ASSERT_TRUE(eventually([&] { return sim.report().motors[0].iq_ref_a > 0.1; }));
  actor.reset();
  EXPECT_TRUE(eventually([&] { return board_off(); }));
  const auto r = run("status");  // the core is closed: refused, not run on a board nobody owns
  EXPECT_EQ(code_of(r), 'f');
}

// The actor going away (a stop signal) while an enable waits for the alignment: the wait ends, the
// enable gets its final reply, the motors end off.
TEST_F(BlmcActorOnSim, TheDestructorEndsAnEnableInProgressAndLeavesTheMotorsOff) {
  core.handle(command("enable", "e"));
  actor.reset();
  const auto e = out.final_of("e");
  ASSERT_TRUE(e);
  EXPECT_TRUE(eventually([&] { return board_off(); }));
}

TEST_F(BlmcActorOnSim, BroadcastsTheStatusEveryPeriod) {
  actor.reset();
  auto o = actor_options();
  o.status_period_s = 0.2;
  // The fixture's actor gone, one with a period on a core of its own.
  ActorCore other{"blmc", out.sink()};
  BlmcActor periodic(other, board, o);
  const auto status = broadcast_with("limits");
  ASSERT_TRUE(status);
  EXPECT_EQ(code_of(*status), 'i');
  EXPECT_TRUE(body_of(*status).contains("board"));
}

// Outside the loop the board's status frames (once a second) are the sign that it is there: when
// they stop (the simulated board's transmitter stalls for a while) every listener is warned, and
// told again when they resume.
TEST(BlmcActorStaleData, StatusFramesThatStopAreStaleDataUntilTheyResume) {
  auto so = sim_options();
  blmc::sim::BoardFaultPlan plan;
  // From 2.5 s: the board has sent its first status frames (one a second) however loaded the machine.
  plan.stalls.push_back({std::chrono::milliseconds(2500), std::chrono::seconds(5), blmc::sim::LinkDirection::tx});
  so.faults.push_back(plan);
  blmc::sim::SimulatedBoard sim(so);
  blmc::MotorBoard board(sim.bus_spec(), board_options());
  test::Replies out;
  ActorCore core{"blmc", out.sink()};
  auto o = actor_options();
  o.status_stale_s = 2.0;
  BlmcActor actor(core, board, o);
  const auto stale_data = [&](bool stale) {
    return out.wait_for([&](const Message& m) {
      const auto kw = body_of(m);
      return m.routing_key == kBroadcastKey && kw.contains("stale_data") && kw["stale_data"]["stale"] == stale;
    });
  };
  const auto gone = stale_data(true);
  ASSERT_TRUE(gone);
  EXPECT_EQ(code_of(*gone), 'w');
  EXPECT_EQ(body_of(*gone)["stale_data"]["quantity"], "status");
  EXPECT_GT(body_of(*gone)["stale_data"]["age_s"].get<double>(), 2.0);
  const auto back = stale_data(false);
  ASSERT_TRUE(back);
  EXPECT_EQ(code_of(*back), 'i');
}

}  // namespace axon::actor::blmc_actor_test

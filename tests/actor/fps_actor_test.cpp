// The fps actor on the six-robot benchtop plane simulated in this process, without a broker: its
// replies go to a collector.
#include "axon/actor/fps_actor.hpp"
#include "axon/fps/host/client.hpp"
#include "axon/fps/sim/firmware_marker.hpp"
#include "axon/fps/sim/simulated_plane.hpp"
#include "replies.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace axon::actor {
namespace {

using test::body_of;
using test::code_of;
using test::command;

struct FpsActorOnBenchtop : ::testing::Test {
  fps::sim::SimulatedPlane plane{"benchtop", fps::sim::SimulatedPlaneOptions{50.0, 1, false, false}};
  fps::Client client;
  test::Replies out;
  ActorCore core{"fps", out.sink()};
  std::unique_ptr<FpsActor> actor;

  void SetUp() override {
    client.open(plane.plane());
    actor = std::make_unique<FpsActor>(core, client, FpsActorOptions{0.0, 0.02, 0.2});
  }
  std::uint16_t first_robot() const { return plane.plane().robots().front().id; }
};

TEST_F(FpsActorOnBenchtop, StatusListsEveryRobotAndTheLock) {
  core.handle(command("status", "s"));
  const auto r = out.final_of("s");
  ASSERT_TRUE(r);
  EXPECT_EQ(code_of(*r), ':');
  const auto kw = body_of(*r);
  EXPECT_EQ(kw["robots"].size(), plane.plane().robots().size());
  EXPECT_EQ(kw["ready"], plane.plane().robots().size());
  EXPECT_EQ(kw["locked"], false);
  EXPECT_EQ(kw["stale"], false);
}

TEST_F(FpsActorOnBenchtop, GotoMovesTheRobotAndEndsDoneWithItsResult) {
  const auto id = first_robot();
  core.handle(command(fmt::format("goto {} 30 170", id), "g"));
  const auto r = out.final_of("g");
  ASSERT_TRUE(r);
  EXPECT_EQ(code_of(*r), ':') << r->body;
  const auto robots = body_of(*r)["move_result"]["robots"];
  ASSERT_EQ(robots.size(), 1u);
  EXPECT_NEAR(robots[0]["alpha"].get<double>(), 30.0, 0.1);
  EXPECT_NEAR(robots[0]["beta"].get<double>(), 170.0, 0.1);
  EXPECT_EQ(code_of(out.of("g").front()), '>');  // move_started first
}

TEST_F(FpsActorOnBenchtop, BadGotoArgumentsFailWithAReason) {
  const std::pair<std::string, std::string> cases[] = {{"goto 1 2", "triplets"},
                                                         {"goto 999 10 10", "robot 999 is not on the buses"},
                                                         {fmt::format("goto {} ten 10", first_robot()), "not angles"}};
  int n = 0;
  for (const auto& [text, reason] : cases) {  // one after the other: goto is exclusive
    const auto id = std::to_string(n++);
    core.handle(command(text, id));
    const auto r = out.final_of(id);
    ASSERT_TRUE(r) << text;
    EXPECT_EQ(code_of(*r), 'f') << text;
    EXPECT_NE(body_of(*r)["error"].get<std::string>().find(reason), std::string::npos) << r->body;
  }
}

TEST_F(FpsActorOnBenchtop, ACollisionLocksAndEveryListenerGetsTheAlert) {
  plane.inject_collision(first_robot());
  const auto alert = out.wait_for([](const Message& m) {
    return m.routing_key == kBroadcastKey && body_of(m).contains("collision_alert");
  });
  ASSERT_TRUE(alert);
  EXPECT_EQ(code_of(*alert), 'e');
  EXPECT_EQ(body_of(*alert)["locked"], true);
  core.handle(command("goto all 10 170", "refused"));  // moves are refused while locked
  const auto r = out.final_of("refused");
  ASSERT_TRUE(r);
  EXPECT_EQ(code_of(*r), 'f');
  EXPECT_NE(body_of(*r)["error"].get<std::string>().find("locked"), std::string::npos) << r->body;
  core.handle(command("unlock", "u"));
  const auto u = out.final_of("u");
  ASSERT_TRUE(u);
  EXPECT_EQ(code_of(*u), ':') << u->body;
  EXPECT_EQ(body_of(*u)["locked"], false);
}

// After the collision and unlock, `backoff ID` moves the robot the document's 2 degrees away and
// says how; an id that is not on the buses is refused with the reason.
TEST_F(FpsActorOnBenchtop, BackoffMovesTheRobotThatCollidedAwayAfterUnlock) {
  const auto id = first_robot();
  plane.inject_collision(id);
  ASSERT_TRUE(out.wait_for([](const Message& m) { return body_of(m).contains("collision_alert"); }));
  core.handle(command("unlock", "u"));
  ASSERT_TRUE(out.final_of("u"));
  core.handle(command("backoff " + std::to_string(id), "b"));
  const auto b = out.final_of("b");
  ASSERT_TRUE(b);
  EXPECT_EQ(code_of(*b), ':') << b->body;
  const auto kw = body_of(*b)["back_off"];
  EXPECT_EQ(kw["ok"], true);
  ASSERT_EQ(kw["moves"].size(), 1u) << b->body;
  EXPECT_EQ(kw["moves"][0]["id"], id);
  EXPECT_EQ(kw["moves"][0]["moved"], true);
  EXPECT_GE(std::abs(kw["moves"][0]["step_deg"].get<double>()), 2.0);
  core.handle(command("backoff 4000", "bad"));
  const auto bad = out.final_of("bad");
  ASSERT_TRUE(bad);
  EXPECT_EQ(code_of(*bad), 'f');
  EXPECT_NE(body_of(*bad)["error"].get<std::string>().find("robot 4000 is not on the buses"), std::string::npos) << bad->body;
}

// plan: collision-free moves from where every robot stands, verified, then run; the robots not
// named fold. discover answers the robots again.
TEST_F(FpsActorOnBenchtop, PlanMovesTheNamedRobotCollisionFreeAndDiscoverListsEveryRobot) {
  const auto id = first_robot();
  core.handle(command(fmt::format("plan {} 30 150", id), "p"));
  const auto r = out.final_of("p");
  ASSERT_TRUE(r);
  EXPECT_EQ(code_of(*r), ':') << r->body;
  const auto kw = body_of(*r);
  EXPECT_EQ(kw["plan_result"]["verified"], true) << r->body;
  EXPECT_EQ(kw["plan_result"]["moved"], true);
  EXPECT_GE(kw["plan_result"]["min_clearance_mm"].get<double>(), 0.0);
  const auto reached = plane.arms(id).value();
  EXPECT_NEAR(reached.alpha, 30.0, 0.1);
  EXPECT_NEAR(reached.beta, 150.0, 0.1);
  EXPECT_EQ(plane.collisions(), 0u);
  core.handle(command("plan", "p0"));
  ASSERT_TRUE(out.final_of("p0"));
  EXPECT_EQ(code_of(*out.final_of("p0")), 'f');
  core.handle(command("check", "c"));
  const auto ck = out.final_of("c");
  ASSERT_TRUE(ck);
  EXPECT_EQ(code_of(*ck), ':') << ck->body;
  EXPECT_EQ(body_of(*ck)["layout_check"]["matched"].size(), plane.plane().robots().size()) << ck->body;
  core.handle(command("cold", "cold"));  // this plane has no PLC
  ASSERT_TRUE(out.final_of("cold"));
  EXPECT_EQ(code_of(*out.final_of("cold")), 'f');
  core.handle(command("discover", "d"));
  const auto d = out.final_of("d");
  ASSERT_TRUE(d);
  EXPECT_EQ(code_of(*d), ':') << d->body;
  EXPECT_EQ(body_of(*d)["robots"].size(), plane.plane().robots().size());
}

// Troubleshooting verbs (interface document 9.4.3): a stuck hall sensor is found and the command
// fails with the verdict in its keyword; bad arguments fail with a reason, nothing moves.
TEST_F(FpsActorOnBenchtop, HalltestFindsAStuckSensorAndFailsWithTheVerdict) {
  const auto id = first_robot();
  plane.set_hall_fault(id, 'a', "stuck");
  core.handle(command(fmt::format("halltest {}", id), "h"));
  const auto h = out.final_of("h");
  ASSERT_TRUE(h);
  EXPECT_EQ(code_of(*h), 'f') << h->body;
  const auto kw = body_of(*h)["hall_test"];
  ASSERT_EQ(kw["arms"].size(), 2u) << h->body;
  EXPECT_EQ(kw["arms"][0]["verdict"], "no_hall_change") << h->body;
  EXPECT_EQ(kw["arms"][1]["verdict"], "ok") << h->body;
  EXPECT_EQ(kw["arms"][0]["restored"], true);
  EXPECT_EQ(body_of(*h)["locked"], false);
  int n = 0;
  for (const std::string& bad : {std::string("halltest"), fmt::format("halltest {} gamma", id), std::string("halltest 4000")}) {
    const auto cid = fmt::format("bad{}", n++);
    core.handle(command(bad, cid));
    const auto b = out.final_of(cid);
    ASSERT_TRUE(b) << bad;
    EXPECT_EQ(code_of(*b), 'f') << bad;
    EXPECT_TRUE(body_of(*b).contains("error")) << b->body;
  }
}

// upgrade FILE VERSION through the embedded plane's PLC: `>` upgrade_progress, then `:` with every
// robot on the new image; an unreadable file fails at once, nothing switched.
TEST(FpsActorUpgrade, UpgradeReportsProgressAndEndsWithEveryRobotOnTheNewImage) {
  fps::sim::SimulatedPlane plane{"benchtop", fps::sim::SimulatedPlaneOptions{20.0, 1, false, true}};
  fps::ClientConfig cc;
  cc.plc_address = plane.plc_address();
  fps::Client client(cc);
  test::Replies out;
  ActorCore core{"fps", out.sink()};
  client.open(plane.plane());
  auto actor = std::make_unique<FpsActor>(core, client, FpsActorOptions{0.0, 0.02, 0.2});
  const auto path = (std::filesystem::temp_directory_path() / fmt::format("axon-actor-image-{}.bin", ::getpid())).string();
  {
    const auto image = fps::sim::make_firmware_image({4, 2, 0}, 3000).value();
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(image.data()), static_cast<std::streamsize>(image.size()));
  }
  core.handle(command("upgrade " + path + " 04.02.00", "up"));
  const auto r = out.final_of("up");
  std::filesystem::remove(path);
  ASSERT_TRUE(r);
  EXPECT_EQ(code_of(*r), ':') << r->body;
  const auto kw = body_of(*r)["upgrade_result"];
  EXPECT_EQ(kw["ok"], true);
  ASSERT_EQ(kw["robots"].size(), 6u) << r->body;
  for (const auto& robot : kw["robots"]) EXPECT_EQ(robot["after"], "04.02.00") << robot.dump();
  bool finished = false;
  for (const auto& m : out.of("up"))
    if (code_of(m) == '>' && body_of(m).contains("upgrade_progress"))
      finished = finished || body_of(m)["upgrade_progress"]["finished"].get<bool>();
  EXPECT_TRUE(finished) << "no upgrade_progress at the sextant's end";
  core.handle(command("upgrade /nonexistent/image.bin", "bad"));
  const auto bad = out.final_of("bad");
  ASSERT_TRUE(bad);
  EXPECT_EQ(code_of(*bad), 'f');
  EXPECT_NE(body_of(*bad)["error"].get<std::string>().find("cannot open"), std::string::npos) << bad->body;
  actor.reset();
}

// The PLC verbs on the embedded plane's PLC emulator, whose relays act on the simulated robots:
// power off silences sextant 1's robots (status: none ready), on brings them back; the sync line
// follows high/low/pulse; wrong arguments fail with the usage; without a PLC every PLC verb fails
// saying how to give one.
TEST(FpsActorPlc, PowerGatewayAndSyncActOnThePlcAndArgumentsAreChecked) {
  fps::sim::SimulatedPlane plane{"benchtop", fps::sim::SimulatedPlaneOptions{20.0, 1, false, true}};
  fps::Client client;
  test::Replies out;
  ActorCore core{"fps", out.sink()};
  client.open(plane.plane());
  FpsActorOptions o{0.0, 0.02, 0.2};
  o.plc_address = plane.plc_address();
  auto actor = std::make_unique<FpsActor>(core, client, o);
  int n = 0;
  auto run = [&](const std::string& text, ActorCore* to = nullptr) {
    const auto id = fmt::format("c{}", n++);
    (to ? *to : core).handle(command(text, id));
    const auto r = out.final_of(id);
    EXPECT_TRUE(r) << text;
    return r ? *r : Message{};
  };
  auto r = run("plc");
  ASSERT_EQ(code_of(r), ':') << r.body;
  EXPECT_EQ(body_of(r)["plc"]["positioner_power"].size(), 6u) << r.body;
  EXPECT_EQ(body_of(r)["plc"]["positioner_power"][0], true) << r.body;
  r = run("power 1 off");
  ASSERT_EQ(code_of(r), ':') << r.body;
  EXPECT_EQ(body_of(r)["relay"]["name"], "positioner power 1");
  EXPECT_EQ(body_of(r)["relay"]["on"], false);
  r = run("status");
  EXPECT_EQ(body_of(r)["ready"], 0) << r.body;
  EXPECT_EQ(body_of(run("plc"))["plc"]["positioner_power"][0], false);
  r = run("power 1 on");
  ASSERT_EQ(code_of(r), ':') << r.body;
  EXPECT_EQ(body_of(r)["relay"]["on"], true);
  r = run("gateway 2 off");
  EXPECT_EQ(code_of(r), ':') << r.body;
  EXPECT_EQ(body_of(r)["relay"]["name"], "gateway power 2");
  EXPECT_EQ(code_of(run("gateway 2 on")), ':');
  r = run("sync high");
  EXPECT_EQ(body_of(r)["relay"]["on"], true) << r.body;
  r = run("sync low");
  EXPECT_EQ(body_of(r)["relay"]["on"], false) << r.body;
  r = run("sync pulse 0.05");
  EXPECT_EQ(code_of(r), ':') << r.body;
  EXPECT_EQ(body_of(r)["relay"]["on"], false) << r.body;  // low again after the pulse
  for (const std::string bad : {"power 7 on", "power 1", "power one on", "gateway 1 maybe", "sync", "sync pulse -1",
                                "sync pulse 60", "sync sideways", "plc now"}) {
    r = run(bad);
    EXPECT_EQ(code_of(r), 'f') << bad;
    EXPECT_TRUE(body_of(r).contains("error")) << bad;
  }
  actor.reset();

  ActorCore other{"fps", out.sink()};  // the first actor closed its core
  FpsActor no_plc(other, client, FpsActorOptions{0.0, 0.02, 0.2});
  r = run("power 1 off", &other);
  EXPECT_EQ(code_of(r), 'f');
  EXPECT_NE(body_of(r)["error"].get<std::string>().find("--plc"), std::string::npos) << r.body;
}

}  // namespace
}  // namespace axon::actor

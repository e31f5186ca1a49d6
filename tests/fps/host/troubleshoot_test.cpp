// Troubleshooting false collisions (interface document 9.4.2, 9.4.3; host/troubleshoot.hpp): the
// friction fit and its history, the test-move sweep check, and the friction survey and hall test
// of fps::Client against a simulated plane (SimulatedPlane, over the CAN@net transport on
// loopback) with the simulator's friction and hall faults injected.
#include "axon/fps/host/client.hpp"
#include "axon/fps/host/error.hpp"
#include "axon/fps/host/troubleshoot.hpp"
#include "axon/fps/layout/layout_name.hpp"
#include "axon/fps/plan/layout_model.hpp"
#include "axon/fps/plan/stop_sweep.hpp"
#include "axon/fps/sim/simulated_plane.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <cmath>
#include <fstream>
#include <iostream>
#include <thread>

namespace axon::fps::troubleshoot_test {
namespace {

using host::FrictionFinding;
using host::FrictionOptions;
using host::FrictionPoint;
using host::FrictionRecord;
using host::FrictionVerdict;
using host::HallVerdict;

// A scratch path in the temporary folder, removed afterwards.
struct ScratchFile {
  explicit ScratchFile(const std::string& stem)
      : path((std::filesystem::temp_directory_path() /
              (stem + "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name() + "-" +
               std::to_string(::getpid()) + ".csv"))
                 .string()) {
    std::filesystem::remove(path);
  }
  ~ScratchFile() { std::filesystem::remove(path); }
  std::string path;
};

TEST(FrictionFit, RecoversStictionAndViscousFriction) {
  const std::vector<FrictionPoint> pts{{1000, 20}, {2000, 25}, {3000, 30}, {4000, 35}};
  const auto f = host::fit_friction(pts);
  ASSERT_TRUE(f.has_value());
  EXPECT_NEAR(f->stiction_percent, 15, 1e-9);
  EXPECT_NEAR(f->viscous_percent_per_krpm, 5, 1e-9);
  EXPECT_NEAR(f->rms_percent, 0, 1e-9);
  EXPECT_NEAR(f->at(3000), 30, 1e-9);
  EXPECT_FALSE(host::fit_friction(std::vector<FrictionPoint>{{1000, 20}}).has_value());
  EXPECT_FALSE(host::fit_friction(std::vector<FrictionPoint>{{1000, 20}, {1000, 22}}).has_value());
}

FrictionFinding measured(double stiction, double viscous) {
  FrictionFinding f;
  f.id = 7;
  f.arm = 'b';
  f.fit = host::FrictionFit{stiction, viscous, 0.1};
  return f;
}

TEST(FrictionJudge, TheFirstRecordIsTheBaselineAndGrowthAgainstItIsIncreased) {
  const FrictionOptions o;  // 25 % at 3000 rpm
  EXPECT_EQ(host::judge_friction(measured(15, 5), {}, o).verdict, FrictionVerdict::baseline);
  const std::vector<FrictionRecord> history{{"2026-01-01T00:00:00Z", 7, 'b', {15, 5, 0.1}, 0},
                                            {"2025-06-01T00:00:00Z", 7, 'b', {14, 5, 0.1}, 0},   // the oldest
                                            {"2025-01-01T00:00:00Z", 7, 'a', {99, 9, 0.1}, 0},   // the other arm
                                            {"2024-01-01T00:00:00Z", 8, 'b', {1, 1, 0.1}, 0}};   // another robot
  const auto same = host::judge_friction(measured(15, 5), history, o);
  EXPECT_EQ(same.verdict, FrictionVerdict::ok);
  ASSERT_TRUE(same.baseline.has_value());
  EXPECT_EQ(same.baseline->time_utc, "2025-06-01T00:00:00Z");
  EXPECT_NEAR(same.growth, 30.0 / 29.0 - 1, 1e-9);
  const auto worse = host::judge_friction(measured(25, 7), history, o);  // 46 % against 29 %
  EXPECT_EQ(worse.verdict, FrictionVerdict::increased);
  EXPECT_NE(worse.advice.find("SET_COLLISION_MARGIN"), std::string::npos) << worse.advice;
  EXPECT_NE(worse.advice.find("2025-06-01"), std::string::npos) << worse.advice;
  FrictionFinding none;
  none.problem = "no room";
  EXPECT_EQ(host::judge_friction(none, history, o).verdict, FrictionVerdict::failed);
}

TEST(FrictionHistory, RoundTripsAndAMissingFileIsEmpty) {
  ScratchFile file("friction");
  EXPECT_TRUE(host::load_friction_history(file.path).value().empty());
  const std::vector<FrictionRecord> recs{{"2026-12-02T03:04:05Z", 12, 'a', {15.25, 5.125, 0.5}, 1.05},
                                         {"2026-12-02T03:04:05Z", 12, 'b', {16, 4, 0.25}, 0}};
  ASSERT_TRUE(host::append_friction_history(file.path, recs));
  ASSERT_TRUE(host::append_friction_history(file.path, {recs[0]}));
  const auto back = host::load_friction_history(file.path).value();
  ASSERT_EQ(back.size(), 3u);
  EXPECT_EQ(back[1].arm, 'b');
  EXPECT_EQ(back[1].id, 12);
  EXPECT_DOUBLE_EQ(back[0].fit.viscous_percent_per_krpm, 5.125);
  EXPECT_DOUBLE_EQ(back[0].move_ratio, 1.05);
  std::ifstream in(file.path);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "time_utc,robot,arm,stiction_percent,viscous_percent_per_krpm,rms_percent,move_ratio");
}

TEST(FrictionHistory, AMalformedLineIsAnErrorNamingTheLine) {
  ScratchFile file("friction");
  for (const std::string bad : {"2026-12-02T03:04:05Z,12,gamma,1,2,3,4", "2026-12-02T03:04:05Z,12,alpha,1,x,3,4",
                                "2026-12-02T03:04:05Z,0,alpha,1,2,3,4", "yesterday,12,alpha,1,2,3,4",
                                "2026-12-02T03:04:05Z,12,alpha,1,2,3"}) {
    std::ofstream(file.path) << "time_utc,robot,arm,stiction_percent,viscous_percent_per_krpm,rms_percent,move_ratio\n"
                             << "2026-12-02T03:04:05Z,12,beta,1,2,3,4\n"
                             << bad << "\n";
    const auto r = host::load_friction_history(file.path);
    ASSERT_FALSE(r.has_value()) << bad;
    EXPECT_NE(r.error().message().find(":3:"), std::string::npos) << r.error().message();
  }
}

// ---- the sweep of a test move --------------------------------------------------------------------

TEST(ArmSweep, AnArmTurningIntoANeighbourIsNotClearAndNamesIt) {
  const auto plane = resolve_layout("benchtop").value();
  const auto model = plan::model_from_layout(plane).value();
  std::vector<plan::Pose> poses(model.size(), plan::Pose{0, 180});
  // Robot 0 stretched, turning its alpha round: somewhere it sweeps through a folded neighbour's
  // beta arm, and a short turn from a clear pose away from it stays clear.
  bool blocked_by_robot = false, clear = false;
  for (double a = 0; a < 360; a += 5) {
    poses[0] = {a, 0};
    const auto s = plan::check_arm_sweep(model, 0, poses, 'a', a + 5);
    if (!s.clear) {
      ASSERT_FALSE(s.in_the_way.empty());
      EXPECT_LT(s.min_clearance_mm, 0);
      for (const auto& w : s.in_the_way) blocked_by_robot = blocked_by_robot || w.rfind("robot ", 0) == 0;
    } else {
      clear = true;
      EXPECT_GE(s.min_clearance_mm, 0);
    }
  }
  EXPECT_TRUE(blocked_by_robot);
  EXPECT_TRUE(clear);
  poses[0] = {0, 180};
  const auto beyond = plan::check_arm_sweep(model, 0, poses, 'b', model.robot(0).limits().beta_max_deg + 1);
  EXPECT_FALSE(beyond.clear);
  ASSERT_FALSE(beyond.in_the_way.empty());
  EXPECT_NE(beyond.in_the_way[0].find("angle limit"), std::string::npos);
}

// ---- host against the simulated plane --------------------------------------------------------------

sim::SimulatedPlaneOptions plane_options() {
  sim::SimulatedPlaneOptions o;
  o.time_scale = 5;  // slow enough for several current readings during the shortest test move
  o.plc = false;
  return o;
}

ClientConfig client_config() {
  ClientConfig c;
  c.poll_interval_s = 0.02;
  c.discover_window_s = 0.3;
  c.call_timeout_s = 120;
  return c;
}

class Troubleshoot : public ::testing::Test {
 protected:
  void SetUp() override {
    fps.open(plane.plane());
    ASSERT_EQ(fps.discover().size(), 6u);
  }
  // Robot 1 moved to a pose where every test move has room (folded robots all round).
  sim::SimulatedPlane plane{"benchtop", plane_options()};
  Client fps{client_config()};
};

const FrictionFinding& arm_of(const host::FrictionReport& r, std::uint16_t id, char arm) {
  for (const auto& f : r.arms)
    if (f.id == id && f.arm == arm) return f;
  throw std::runtime_error("no finding");
}

// The simulator's arms draw 15 % + 5 % per 1000 rpm while they turn (its defaults): the survey's
// fit finds that model; its first run is the baseline, a second one agrees with it, and a friction
// fault of level 10 on one arm (below the beta margin of 20: no false collisions yet) shows as an
// increase of that arm alone, with the document's advice.
TEST_F(Troubleshoot, TheFrictionTrendFindsTheSimulatorsFrictionAndItsGrowth) {
  ScratchFile history("friction");
  const auto first = fps.friction_survey({1}, {}, history.path);
  std::cout << first.summary();
  ASSERT_EQ(first.arms.size(), 2u);
  for (const auto& f : first.arms) {
    EXPECT_EQ(f.verdict, FrictionVerdict::baseline) << f.problem;
    ASSERT_TRUE(f.fit.has_value()) << f.problem;
    EXPECT_NEAR(f.fit->stiction_percent, 15, 1.5);
    EXPECT_NEAR(f.fit->viscous_percent_per_krpm, 5, 0.6);
    EXPECT_EQ(f.points.size(), 4u);
    EXPECT_GE(std::abs(f.step_deg), 10);
  }
  EXPECT_TRUE(first.ok()) << first.summary();
  const auto truth = plane.arms(1).value();
  EXPECT_NEAR(truth.alpha, 0, 0.1) << "the test moves go there and back";
  EXPECT_NEAR(truth.beta, 180, 0.1);

  const auto again = fps.friction_survey({1}, {}, history.path);
  EXPECT_TRUE(again.ok()) << again.summary();
  EXPECT_EQ(arm_of(again, 1, 'a').verdict, FrictionVerdict::ok);

  plane.set_friction_fault(1, 'b', 10);
  const auto stiff = fps.friction_survey({1}, {}, history.path);
  std::cout << stiff.summary();
  EXPECT_FALSE(stiff.ok());
  EXPECT_EQ(arm_of(stiff, 1, 'a').verdict, FrictionVerdict::ok) << stiff.summary();
  const auto& beta = arm_of(stiff, 1, 'b');
  EXPECT_EQ(beta.verdict, FrictionVerdict::increased) << stiff.summary();
  EXPECT_GT(beta.growth, 0.4);  // 46 % at 3000 rpm against 30 %
  EXPECT_NE(beta.advice.find("collision margin"), std::string::npos);
  EXPECT_EQ(host::load_friction_history(history.path).value().size(), 6u);
  EXPECT_FALSE(fps.locked());
}

TEST_F(Troubleshoot, AHealthyRobotPassesTheHallTestAndIsBackInClosedLoop) {
  const auto before = plane.arms(2).value();
  const auto r = fps.hall_test(2);
  std::cout << r.summary();
  ASSERT_EQ(r.arms.size(), 2u);
  EXPECT_TRUE(r.ok()) << r.summary();
  for (const auto& f : r.arms) {
    EXPECT_EQ(f.verdict, HallVerdict::ok);
    EXPECT_TRUE(f.restored);
    EXPECT_LE(f.tracking_error_deg, 0.04);
    EXPECT_NEAR(std::abs(f.position_after_deg - f.position_before_deg), 5, 0.1);
  }
  const auto after = plane.arms(2).value();
  EXPECT_NEAR(after.alpha, before.alpha, 0.1);
  EXPECT_NEAR(after.beta, before.beta, 0.1);
}

// A stuck sensor makes every closed-loop move collide (the symptom); the open-loop test finds the
// arm whose hall reading does not follow and leaves the other one ok. Afterwards collision
// detection is on again: the next move of that arm is caught.
TEST_F(Troubleshoot, AStuckHallSensorIsFoundAndDetectionIsOnAgainAfterwards) {
  plane.set_hall_fault(3, 'a', "stuck");
  const auto r = fps.hall_test(3);
  std::cout << r.summary();
  ASSERT_EQ(r.arms.size(), 2u);
  EXPECT_EQ(r.arms[0].verdict, HallVerdict::no_hall_change) << r.summary();
  EXPECT_NE(r.arms[0].advice.find("sensor wire"), std::string::npos);
  EXPECT_EQ(r.arms[1].verdict, HallVerdict::ok) << r.summary();
  EXPECT_FALSE(r.ok());
  for (const auto& f : r.arms) EXPECT_TRUE(f.restored);
  EXPECT_FALSE(fps.locked()) << "the open-loop test moves collided";
  const auto move = fps.goto_absolute({{3, {4, 180}}});
  EXPECT_FALSE(move.completed);
  EXPECT_TRUE(fps.locked()) << "collision detection was left off";
}

TEST_F(Troubleshoot, ADeadMotorLeavesTheArmWhereItWasAndTheHallReadingWithIt) {
  plane.set_hall_fault(4, 'b', "dead");
  const auto before = plane.arms(4).value();
  const auto r = fps.hall_test(4, {.alpha = false});
  ASSERT_EQ(r.arms.size(), 1u);
  EXPECT_EQ(r.arms[0].arm, 'b');
  EXPECT_EQ(r.arms[0].verdict, HallVerdict::no_hall_change) << r.summary();
  EXPECT_NEAR(plane.arms(4)->beta, before.beta, 1e-6) << "a dead motor turned";
}

// A robot stretched so close to a neighbour that its alpha cannot turn 5 degrees either way without
// touching it: the test of that arm is not run (the finding names the neighbour) and nothing moves;
// its beta, which has room, is tested.
TEST_F(Troubleshoot, AnArmWithNoRoomForItsTestMoveIsNotMoved) {
  const auto model = plan::model_from_layout(plane.plane()).value();
  std::vector<plan::Pose> poses(model.size());
  for (std::size_t i = 0; i < model.size(); ++i) {
    const auto a = plane.arms(static_cast<std::uint16_t>(model.robot(i).id())).value();
    poses[i] = {a.alpha, a.beta};
  }
  std::optional<std::pair<std::size_t, plan::Pose>> boxed;
  for (std::size_t i = 0; i < model.size() && !boxed; ++i) {
    for (double a = 10; a < 350 && !boxed; a += 5) {  // away from the angle limits: bodies on both sides
      for (double b = 0; b <= 180 && !boxed; b += 2) {
        auto p = poses;
        p[i] = {a, b};
        std::vector<plan::Segment> segs(model.size());
        std::vector<plan::Contact> contacts;
        model.segments(p, segs);
        model.find_contacts(segs, contacts);
        if (!contacts.empty()) continue;
        if (!plan::check_arm_sweep(model, i, p, 'a', a + 5).clear && !plan::check_arm_sweep(model, i, p, 'a', a - 5).clear &&
            plan::check_arm_sweep(model, i, p, 'b', b + 5).clear)
          boxed = {i, p[i]};
      }
    }
  }
  ASSERT_TRUE(boxed.has_value());
  const auto id = static_cast<std::uint16_t>(model.robot(boxed->first).id());
  ASSERT_TRUE(fps.goto_absolute({{id, {boxed->second.alpha_deg, 180}}}).completed);
  ASSERT_TRUE(fps.goto_absolute({{id, {boxed->second.alpha_deg, boxed->second.beta_deg}}}).completed);
  const auto r = fps.hall_test(id);
  std::cout << r.summary();
  ASSERT_EQ(r.arms.size(), 2u);
  EXPECT_EQ(r.arms[0].verdict, HallVerdict::failed);
  EXPECT_NE(r.arms[0].problem.find("no room for a test move"), std::string::npos) << r.arms[0].problem;
  EXPECT_NE(r.arms[0].problem.find("robot "), std::string::npos) << r.arms[0].problem;
  EXPECT_EQ(r.arms[0].problem.find("angle limit"), std::string::npos) << r.arms[0].problem;
  EXPECT_EQ(r.arms[1].verdict, HallVerdict::ok) << r.summary();
  const auto truth = plane.arms(id).value();
  EXPECT_NEAR(truth.alpha, boxed->second.alpha_deg, 0.05) << "the boxed-in arm moved";
  EXPECT_EQ(plane.collisions(), 0u);
  FrictionOptions alpha_only;
  alpha_only.speeds_rpm = {1000, 2000};
  alpha_only.beta = false;
  const auto f = fps.friction_survey({id}, alpha_only);
  ASSERT_EQ(f.arms.size(), 1u);
  EXPECT_EQ(f.arms[0].verdict, FrictionVerdict::failed);
  EXPECT_NEAR(plane.arms(id)->alpha, boxed->second.alpha_deg, 0.05);
}

TEST_F(Troubleshoot, BothAreRefusedWhileLocked) {
  plane.inject_collision(5);
  for (int i = 0; i < 500 && !fps.locked(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_TRUE(fps.locked());
  for (int which = 0; which < 2; ++which) {
    try {
      if (which == 0) fps.friction_survey({1});
      else fps.hall_test(1);
      FAIL() << "a test move went out while locked";
    } catch (const Exception& e) {
      EXPECT_EQ(e.code(), host::HostErrc::locked) << e.what();
    }
  }
}

TEST(TroubleshootClient, NeedsTheLayoutAndSaneOptions) {
  sim::SimulatedPlane plane("benchtop", plane_options());
  Client fps(client_config());
  fps.open(plane.bus_specs());
  fps.discover();
  try {
    fps.hall_test(1);
    FAIL();
  } catch (const Exception& e) {
    EXPECT_EQ(e.code(), host::HostErrc::invalid_argument);
  }
  fps.set_layout(plane.plane());
  FrictionOptions one_speed;
  one_speed.speeds_rpm = {2000, 2000};
  try {
    fps.friction_survey({1}, one_speed);
    FAIL();
  } catch (const Exception& e) {
    EXPECT_EQ(e.code(), host::HostErrc::invalid_argument) << e.what();
  }
  try {
    fps.hall_test(99);
    FAIL();
  } catch (const Exception& e) {
    EXPECT_EQ(e.code(), host::HostErrc::unknown_positioner) << e.what();
  }
}

}  // namespace
}  // namespace axon::fps::troubleshoot_test

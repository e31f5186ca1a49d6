// Correction iterations against the simulated plane over TCP: every simulated robot carries an
// angular offset the host does not know about (SET_OFFSETS in the robot: its arms sit that much
// away from what it reports), so the first move misses by a computable amount; the "camera" is
// the simulator's true arm angles put through the planner's kinematics.
#include "plane_rig.hpp"

#include "axon/fps/host/plane_correct.hpp"
#include "axon/fps/plan/layout_model.hpp"

#include <gtest/gtest.h>

#include <boost/asio/steady_timer.hpp>
#include <boost/asio/this_coro.hpp>
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <unistd.h>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::host;
using namespace axon::fps::host::testing;

namespace {

// Where the camera sees each robot's boss fibre: the simulator's physical arm angles.
MeasurementSet camera(sim::FocalPlaneSimulator& s, const plan::CollisionModel& model, const std::string& name) {
  MeasurementSet m;
  m.source = name;
  for (std::size_t i = 0; i < model.size(); ++i) {
    const auto id = model.robot(i).id();
    const auto* r = s.simulator().find(static_cast<std::uint16_t>(id));
    if (!r) continue;
    const plan::Pose phys{r->physical_deg(sim::Arm::alpha), r->physical_deg(sim::Arm::beta)};
    m.items.push_back({id, model.robot(i).fibre(phys, plan::kBossFibre), std::nullopt, static_cast<int>(i) + 2});
  }
  return m;
}

plan::Pose offset_of(std::int32_t id) { return {0.3 + 0.02 * id, -0.5 + 0.03 * id}; }

}  // namespace

TEST(PlaneCorrect, OneRoundRemovesAKnownAngularOffset) {
  PlaneRig rig;
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    auto& array = rig.fpa->array();
    const auto model = plan::model_from_layout(rig.plane).value();
    const plan::Pose cmd{40, 140};  // every robot the same pose: translated copies, no contact

    std::vector<plan::Target> targets;
    std::map<std::uint16_t, ArmAngles> first;
    for (std::size_t i = 0; i < model.size(); ++i) {
      const auto id = model.robot(i).id();
      const auto off = offset_of(id);
      auto set = co_await array.find(static_cast<std::uint16_t>(id))->set_offsets({off.alpha_deg, off.beta_deg});
      EXPECT_TRUE(set.has_value()) << set.error().message();
      plan::Target t;
      t.robot = id;
      t.position = model.robot(i).fibre(cmd, plan::kBossFibre);
      targets.push_back(t);
      first[static_cast<std::uint16_t>(id)] = {cmd.alpha_deg, cmd.beta_deg};
    }
    // The first move: every robot reports arriving, but its arms sit at cmd + offset.
    auto moved = co_await array.goto_absolute(first);
    EXPECT_TRUE(moved.has_value());
    const auto before = camera(*rig.sim, model, "exposure-1.csv");
    for (const auto& m : before.items) {
      const auto i = *model.index_of(m.robot);
      const auto off = offset_of(m.robot);
      const plan::Vec2 expected =
          model.robot(i).fibre({cmd.alpha_deg + off.alpha_deg, cmd.beta_deg + off.beta_deg}, plan::kBossFibre);
      EXPECT_LT(plan::norm(m.position - expected), 1e-4) << "robot " << m.robot;
      EXPECT_GT(plan::norm(m.position - targets[i].position.value()), 0.02) << "robot " << m.robot;
    }

    CorrectionRunOptions o;
    o.iterations = 1;
    auto source = [&](int round) -> asio::awaitable<Result<std::optional<MeasurementSet>>> {
      if (round == 1) co_return std::optional<MeasurementSet>(before);
      if (round == 2) co_return std::optional<MeasurementSet>(camera(*rig.sim, model, "exposure-2.csv"));
      co_return std::optional<MeasurementSet>();
    };
    auto run = co_await correct_positions(array, model, targets, source, o);
    EXPECT_TRUE(run.converged) << run.summary() << (run.rounds.empty() ? "" : run.rounds.back().to_text());
    EXPECT_TRUE(run.ok());
    EXPECT_TRUE(run.verified);
    EXPECT_FALSE(run.stopped_by.has_value());
    EXPECT_EQ(run.rounds.size(), 2u);
    if (run.rounds.size() != 2) co_return;
    const auto& r1 = run.rounds[0];
    EXPECT_EQ(r1.sent, 12u);
    EXPECT_EQ(r1.arrived, 12u) << r1.to_text();
    for (const auto& rc : r1.plan.robots) {
      EXPECT_EQ(rc.status, CorrectionStatus::move) << rc.robot << ": " << rc.detail;
      // The correction undoes the offset; the new command is the pose minus it.
      EXPECT_NEAR(rc.delta.alpha_deg, -offset_of(rc.robot).alpha_deg, 1e-4) << rc.robot;
      EXPECT_NEAR(rc.delta.beta_deg, -offset_of(rc.robot).beta_deg, 1e-4) << rc.robot;
    }
    EXPECT_NE(r1.to_text().find("arrived"), std::string::npos) << r1.to_text();
    // The second measurement: every fibre within 5 um, nothing more sent.
    const auto& r2 = run.rounds[1];
    EXPECT_EQ(r2.sent, 0u);
    EXPECT_LT(r2.plan.worst_error_mm(), 0.005) << r2.to_text();
    EXPECT_EQ(r2.plan.count(CorrectionStatus::within_tolerance), 12u);
  });
}

TEST(PlaneCorrect, RobotsWithinToleranceAndProblemsAreNotMoved) {
  PlaneRig rig;
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    auto& array = rig.fpa->array();
    const auto model = plan::model_from_layout(rig.plane).value();
    // Robots stand folded (0, 180); targets where they are, except robot 2's: its fibre at (1, 179).
    auto here = camera(*rig.sim, model, "m.csv");
    std::vector<plan::Target> targets;
    for (const auto& m : here.items) {
      plan::Target t;
      t.robot = m.robot;
      t.position = m.robot == 2 ? model.robot(*model.index_of(2)).fibre({1, 179}, plan::kBossFibre) : m.position;
      targets.push_back(t);
    }
    // Robot 5 measured far outside its reach: reported unreachable, not sent.
    for (auto& m : here.items)
      if (m.robot == 5) m.position = m.position + plan::Vec2{40, 0};
    auto r = co_await correction_round(array, model, targets, here);
    EXPECT_TRUE(r.has_value());
    if (!r) co_return;
    EXPECT_EQ(r.value().sent, 1u) << r.value().to_text();
    EXPECT_EQ(r.value().arrived, 1u) << r.value().to_text();
    EXPECT_EQ(r.value().plan.find(2)->status, CorrectionStatus::move);
    EXPECT_NEAR(r.value().plan.find(2)->command.alpha_deg, 1.0, 1e-4);
    EXPECT_NEAR(r.value().plan.find(2)->command.beta_deg, 179.0, 1e-4);
    EXPECT_EQ(r.value().plan.find(5)->status, CorrectionStatus::unreachable);
    EXPECT_EQ(r.value().plan.count(CorrectionStatus::within_tolerance), 10u);
    EXPECT_TRUE(r.value().results.contains(2));
    EXPECT_FALSE(r.value().results.contains(5));
    // Only robot 2 moved: its arms changed, robot 1's did not.
    EXPECT_NE(rig.sim->simulator().find(2)->physical_deg(sim::Arm::beta), 180.0);
    EXPECT_EQ(rig.sim->simulator().find(1)->physical_deg(sim::Arm::beta), 180.0);
  });
}

// Measurement files as the CLI gives them: the first read at once, the next one waited for until
// it is there and complete (written while the source waits), a missing one an error naming it after
// the wait, and no round after the last file.
TEST(PlaneCorrect, MeasurementFilesAreReadInTurnWaitingForEachNext) {
  const auto dir = std::filesystem::temp_directory_path() / fmt::format("axon-measured-{}", ::getpid());
  std::filesystem::create_directories(dir);
  const auto first = (dir / "m1.csv").string(), second = (dir / "m2.csv").string(), third = (dir / "m3.csv").string();
  std::ofstream(first) << "robot,x,y\n1,0.5,-0.25\n";
  std::vector<std::string> waited;
  auto source = measurement_files({first, second, third}, {1, 2}, 3.0, [&](const std::string& p) { waited.push_back(p); });
  Runner runner;
  runner.run([&]() -> asio::awaitable<void> {
    auto m1 = co_await source(1);
    EXPECT_TRUE(m1 && m1.value());
    if (m1 && m1.value()) {
      EXPECT_EQ(m1.value()->items.size(), 1u);
    }
    asio::steady_timer later(co_await asio::this_coro::executor, std::chrono::milliseconds(300));
    later.async_wait([&](const boost::system::error_code&) { std::ofstream(second) << "robot,x,y\n1,0,0\n2,1,1\n"; });
    auto m2 = co_await source(2);
    EXPECT_TRUE(m2 && m2.value());
    if (m2 && m2.value()) {
      EXPECT_EQ(m2.value()->items.size(), 2u);
    }
    EXPECT_EQ(waited, std::vector<std::string>{second});
    auto quick = measurement_files({first, third}, {1}, 0.2);
    auto m3 = co_await quick(2);
    EXPECT_FALSE(m3);
    if (!m3) {
      EXPECT_NE(m3.error().message().find("m3.csv: not there after 0.2 s"), std::string::npos) << m3.error().message();
    }
    auto end = co_await source(4);
    EXPECT_TRUE(end && !end.value());
  });
  std::filesystem::remove_all(dir);
}

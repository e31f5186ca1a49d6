// A plane simulated from a layout collides with the layout's own geometry, the planner's: robots
// with longer beta arms touch where nominal ones would not, and the simulator and the planner
// agree on every contact of random poses on a layout whose robots all differ.
#include "axon/fps/host/client.hpp"
#include "axon/fps/plan/layout_model.hpp"
#include "axon/fps/sim/focal_plane_sim.hpp"
#include "axon/fps/sim/simulated_plane.hpp"

#include "axon/core/error.hpp"

#include <boost/asio/io_context.hpp>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

namespace axon::fps::sim {
namespace {

FocalPlaneSpec bench_spec() {
  FocalPlaneSpec s;
  s.name = "geometry";
  s.gateways.push_back({1, "127.0.0.1:19228", 0, kMaxGatewayChannels});
  return s;
}

RobotSite robot(std::uint16_t id, double x, double y) {
  RobotSite r;
  r.id = id;
  r.x_mm = x;
  r.y_mm = y;
  r.sextant = 1;
  r.bus = {1, 1};
  return r;
}

// Two robots 48.7 mm apart whose beta arms, stretched towards each other, end 4.5 mm apart with
// the nominal arms (14.7 mm collision segments: the capsules, 2 mm each, clear) or, with beta arms
// 1 mm longer (17.2 mm instead of 16.2: segments of 15.7 mm), 2.5 mm apart (touching).
FocalPlane facing_pair(std::optional<double> beta_length_mm) {
  auto s = bench_spec();
  for (auto r : {robot(1, 0, 0), robot(2, 48.7, 0)}) {
    r.beta_length_mm = beta_length_mm;
    s.robots.push_back(r);
  }
  return FocalPlane::build(std::move(s)).value();
}

struct MoveResult {
  bool completed = false;
  std::uint64_t collisions = 0;
  std::string refused;     // why the client would not move
  std::string notes;       // the plan's
  bool at_targets = true;  // where the simulator has the arms
};

// Both robots stretched towards each other: straight there (goto) or planned by the host.
MoveResult stretch_towards_each_other(const FocalPlane& layout, bool planned) {
  SimulatedPlaneOptions po;
  po.time_scale = 50;
  po.plc = false;
  SimulatedPlane plane(layout, po);
  ClientConfig cc;
  cc.poll_interval_s = 0.02;
  cc.discover_window_s = 0.3;
  cc.call_timeout_s = 60;
  Client fps(cc);
  fps.open(plane.plane());
  fps.discover();
  const std::map<std::uint16_t, Angles> targets{{1, {0, 0}}, {2, {180, 0}}};
  MoveResult r;
  try {
    if (planned) {
      const auto out = fps.plan_and_move(targets);
      r.completed = out.move.completed;
      r.notes = out.plan.notes;
    } else {
      r.completed = fps.goto_absolute(targets).completed;
    }
  } catch (const Exception& e) {
    r.refused = e.what();
  }
  r.collisions = plane.collisions();
  for (const auto& [id, t] : targets) {
    const auto at = plane.arms(id);
    r.at_targets = r.at_targets && at && std::abs(at->alpha - t.alpha) < 0.1 && std::abs(at->beta - t.beta) < 0.1;
  }
  return r;
}

TEST(FpsSimLayoutGeometry, LongerBetaArmsCollideWhereNominalOnesDoNot) {
  const FocalPlane nominal = facing_pair(std::nullopt), longer = facing_pair(17.2);
  // The planner's model of each layout at the end poses.
  for (const auto* plane : {&nominal, &longer}) {
    const auto model = plan::model_from_layout(*plane).value();
    std::vector<plan::Segment> segs(2);
    model.segments(std::vector<plan::Pose>{{0, 0}, {180, 0}}, segs);
    std::vector<plan::Contact> contacts;
    model.find_contacts(segs, contacts);
    EXPECT_EQ(contacts.size(), plane == &longer ? 1u : 0u);
  }
  // Straight there: the simulator feels the contact of the longer arms only.
  const auto n = stretch_towards_each_other(nominal, false);
  EXPECT_TRUE(n.completed) << n.refused;
  EXPECT_EQ(n.collisions, 0u);
  const auto l = stretch_towards_each_other(longer, false);
  EXPECT_FALSE(l.completed);
  EXPECT_GE(l.collisions, 1u);
}

TEST(FpsSimLayoutGeometry, TheHostPlansOnTheSameLongerArms) {
  // The host's plan-and-move checks the targets on the layout's model: with the nominal arms both
  // robots get there; with the longer ones one target would touch, so that robot is parked (folded)
  // with the reason, and the move runs without a collision.
  const auto n = stretch_towards_each_other(facing_pair(std::nullopt), true);
  EXPECT_TRUE(n.completed) << n.refused;
  EXPECT_TRUE(n.at_targets);
  EXPECT_EQ(n.collisions, 0u);
  const auto l = stretch_towards_each_other(facing_pair(17.2), true);
  EXPECT_TRUE(l.completed) << l.refused;
  EXPECT_FALSE(l.at_targets);
  EXPECT_NE(l.notes.find("park"), std::string::npos) << l.notes;
  EXPECT_EQ(l.collisions, 0u);
}

// 19 robots on the hex grid, each with its own orientation, arm lengths and zero offsets; the
// plane's collision segment 14.7276 mm; fiducials between robots and a guide camera above them.
FocalPlane varied_plane() {
  auto s = bench_spec();
  s.arms = {7.4, 16.2, 14.7276};
  std::mt19937_64 rng(16);
  std::uniform_real_distribution<double> turn(0, 360), alpha_len(7.3, 7.5), beta_len(16.0, 16.6), offset(-1, 1);
  const double p = kDefaultPitchMm, h = p * 0.8660254037844386;
  std::uint16_t id = 1;
  for (int row = -2; row <= 2; ++row) {
    const int n = 5 - std::abs(row);
    for (int k = 0; k < n; ++k) {
      auto r = robot(id++, (k - 0.5 * (n - 1)) * p, row * h);
      r.orientation_deg = turn(rng);
      r.alpha_length_mm = alpha_len(rng);
      r.beta_length_mm = beta_len(rng);
      r.offsets = ArmOffsets{offset(rng), offset(rng)};
      s.robots.push_back(r);
    }
  }
  // The centres of the triangles around the middle robot.
  for (int k = 0; k < 6; ++k) {
    const double a = (30.0 + 60.0 * k) * 3.14159265358979323846 / 180.0;
    s.fiducials.push_back({k + 1, p / 1.7320508075688772 * std::cos(a), p / 1.7320508075688772 * std::sin(a)});
  }
  s.guide_cameras.push_back({1, -30, 2 * h + 19, 30, 2 * h + 19, 3.0});
  return FocalPlane::build(std::move(s)).value();
}

// Every contact as "a-b" (robot ids, a < b) or "a:obstacle name".
std::set<std::string> planner_contacts(const plan::CollisionModel& m, std::span<const plan::Pose> poses) {
  std::vector<plan::Segment> segs(m.size());
  m.segments(poses, segs);
  std::vector<plan::Contact> contacts;
  m.find_contacts(segs, contacts);
  std::set<std::string> out;
  for (const auto& c : contacts) {
    const auto a = m.robot(c.a).id();
    out.insert(c.kind == plan::Contact::Kind::robot ? fmt::format("{}-{}", a, m.robot(c.b).id())
                                                    : fmt::format("{}:{}", a, m.obstacles()[c.b].name));
  }
  return out;
}

std::set<std::string> monitor_contacts(CollisionMonitor& monitor, std::span<const plan::Pose> folded,
                                       std::span<const plan::Pose> poses) {
  const auto& m = monitor.model();
  (void)monitor.update(folded);
  std::set<std::string> out;
  for (const auto& c : monitor.update(poses)) {
    const auto a = m.robot(c.robot).id();
    if (c.other) {
      const auto b = m.robot(*c.other).id();
      out.insert(fmt::format("{}-{}", std::min(a, b), std::max(a, b)));
    } else {
      out.insert(fmt::format("{}:{}", a, m.obstacles()[c.obstacle].name));
    }
  }
  return out;
}

TEST(FpsSimLayoutGeometry, SimulatorAndPlannerAgreeOnEveryContact) {
  const FocalPlane plane = varied_plane();
  const auto planner = plan::model_from_layout(plane).value();
  boost::asio::io_context io;
  FocalPlaneSimOptions o;
  o.plc = false;
  o.random_start = false;
  o.fiducial_radius_mm = plan::LayoutModelOptions{}.fiducial_buffer_mm;  // the planner's buffers
  auto started = FocalPlaneSimulator::start(io.get_executor(), plane, o);
  ASSERT_TRUE(started) << started.error().message();
  auto& fps_sim = *started.value();
  CollisionMonitor monitor(fps_sim.simulator().collision_model());
  ASSERT_EQ(monitor.size(), planner.size());
  for (std::size_t i = 0; i < planner.size(); ++i) ASSERT_EQ(monitor.model().robot(i).id(), planner.robot(i).id());
  EXPECT_EQ(monitor.model().obstacles().size(), planner.obstacles().size());

  // From the folded start (no contact) some robots move to random poses: the simulator reports
  // exactly the contacts the planner finds.
  const std::vector<plan::Pose> folded(planner.size(), plan::Pose{0, 180});
  ASSERT_TRUE(planner_contacts(planner, folded).empty());
  std::mt19937_64 rng(1601);
  std::uniform_real_distribution<double> alpha(0, 360), beta(0, 180), pick(0, 1);
  std::size_t with_contact = 0, robot_contacts = 0, obstacle_contacts = 0;
  for (int round = 0; round < 300; ++round) {
    std::vector<plan::Pose> poses = folded;
    for (auto& p : poses)
      if (pick(rng) < 0.3) p = {alpha(rng), beta(rng)};
    const auto expected = planner_contacts(planner, poses);
    EXPECT_EQ(monitor_contacts(monitor, folded, poses), expected) << "round " << round;
    with_contact += expected.empty() ? 0 : 1;
    for (const auto& c : expected) ++(c.find(':') == std::string::npos ? robot_contacts : obstacle_contacts);
  }
  // Both outcomes, and both kinds of contact, were seen.
  EXPECT_GT(with_contact, 30u);
  EXPECT_LT(with_contact, 270u);
  EXPECT_GT(robot_contacts, 0u);
  EXPECT_GT(obstacle_contacts, 0u);
  fps_sim.stop();
}

}  // namespace
}  // namespace axon::fps::sim

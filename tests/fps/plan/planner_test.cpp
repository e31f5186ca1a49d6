// The planner on small hand-made focal planes: every plan is verified by the independent checker
// here (not only by the planner's own report), stays within the firmware's limits, and robots
// that cannot reach their targets are reported with a reason, never dropped.
#include "axon/fps/plan/planner.hpp"
#include "axon/fps/plan/problems.hpp"
#include "model_util.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace axon::fps::plan {
namespace {

using test::build;
using test::hex_patch;
using test::robot_at;
using test::static_clearance;

// What every plan must satisfy, checked independently of the planner's own report.
// `start_in_contact`: robots held where they started in contact may stay in that contact.
void expect_sound(const CollisionModel& m, const Plan& p, const PlanRequest& req, const PlannerOptions& o = {},
                  bool start_in_contact = false) {
  ASSERT_EQ(p.trajectories.size(), m.size());
  TrajectoryChecker checker(m);
  CheckReport report;
  CheckOptions co;
  co.allow_standing_contacts = start_in_contact;
  ASSERT_TRUE(checker.check(p.trajectories, co, report));
  EXPECT_TRUE(report.ok()) << report.collided_pairs << " pairs collide; min clearance " << report.min_clearance_mm;
  EXPECT_TRUE(p.verified);
  std::size_t not_reached = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    const RobotTrajectory& t = p.trajectories[i];
    EXPECT_EQ(t.alpha.front().t_s, 0.0);
    EXPECT_EQ(t.alpha.front().deg, req.current[i].alpha_deg);
    EXPECT_EQ(t.beta.front().deg, req.current[i].beta_deg);
    EXPECT_LE(t.alpha.size() - 1, 1023u);
    EXPECT_LE(t.beta.size() - 1, 1023u);
    EXPECT_LE(max_speed(t.alpha), o.speed.alpha_deg_s + 1e-6) << "robot " << m.robot(i).id();
    EXPECT_LE(max_speed(t.beta), o.speed.beta_deg_s + 1e-6) << "robot " << m.robot(i).id();
    for (const auto* arm : {&t.alpha, &t.beta})
      for (const auto& pt : *arm) {
        EXPECT_GE(pt.deg, 0.0);
        EXPECT_LE(pt.deg, 360.0);
      }
    const Pose end{t.alpha.back().deg, t.beta.back().deg};
    EXPECT_EQ(end, p.robots[i].end);
    switch (p.robots[i].status) {
      case RobotPlan::Status::reached:
        EXPECT_NEAR(end.alpha_deg, req.target[i].alpha_deg, 1e-9) << "robot " << m.robot(i).id();
        EXPECT_NEAR(end.beta_deg, req.target[i].beta_deg, 1e-9) << "robot " << m.robot(i).id();
        break;
      case RobotPlan::Status::frozen:
        EXPECT_EQ(t.alpha.size(), 1u);
        EXPECT_EQ(t.beta.size(), 1u);
        break;
      case RobotPlan::Status::parked:
      case RobotPlan::Status::held:
        ++not_reached;
        EXPECT_FALSE(p.robots[i].reason.empty());
        break;
    }
  }
  EXPECT_EQ(not_reached, p.not_reached);
}

TEST(Planner, TwoRobotsSwapSides) {
  // Robot 1's arm starts in the gap between the two robots (pointing up-right), robot 2's must
  // end there (cw elbow, pointing up-left): robot 1 has to clear out before robot 2 comes in.
  const auto m = build({robot_at(1, 0, 0), robot_at(2, 22.4, 0)});
  PlanRequest req;
  req.current = {{0, 60}, {0, 0}};
  req.target = {{180, 0}, {180, 300}};
  ASSERT_GT(static_clearance(m, req.current), 0);
  ASSERT_GT(static_clearance(m, req.target), 0);
  // In the wrong order (robot 2 first) the arms cross.
  std::vector<RobotTrajectory> naive{
      RobotTrajectory{{{0, 0}, {5, 0}, {20, 180}}, {{0, 60}, {5, 60}, {20, 0}}},
      RobotTrajectory::linear(req.current[1], req.target[1], 0, 5)};
  TrajectoryChecker checker(m);
  CheckReport naive_report;
  ASSERT_TRUE(checker.check(naive, {}, naive_report));
  EXPECT_FALSE(naive_report.ok());

  auto r = plan_moves(m, req);
  ASSERT_TRUE(r) << r.error().message();
  const Plan& p = r.value();
  EXPECT_TRUE(p.ok()) << p.summary(m);
  EXPECT_EQ(p.not_reached, 0u);
  expect_sound(m, p, req);
  EXPECT_LE(p.stats.max_points, 8u);
}

TEST(Planner, RobotBoxedInByStillNeighboursReachesItsTarget) {
  // The centre robot turns half a turn and stretches out; its six neighbours are frozen with their
  // arms half out, so it has to fold first and pass between them.
  auto robots = hex_patch(1);
  const auto m = build(robots);
  ASSERT_EQ(m.size(), 7u);
  const std::size_t centre = 3;  // (0, 0) in hex_patch order
  ASSERT_EQ(m.robot(centre).centre(), (Vec2{0, 0}));
  PlanRequest req;
  req.current.assign(7, Pose{0, 0});
  req.frozen.assign(7, true);
  for (std::size_t i = 0; i < 7; ++i) {
    // Neighbours point away from the centre robot, beta 90: clear of each other.
    const Vec2 c = m.robot(i).centre();
    req.current[i] = {std::fmod(std::atan2(c.y, c.x) * 180 / std::numbers::pi + 360, 360), 90};
  }
  req.frozen[centre] = false;
  req.current[centre] = {30, 40};
  req.target = req.current;
  req.target[centre] = {210, 40};
  ASSERT_GT(static_clearance(m, req.current), 0);
  ASSERT_GT(static_clearance(m, req.target), 0);
  auto r = plan_moves(m, req);
  ASSERT_TRUE(r) << r.error().message();
  const Plan& p = r.value();
  EXPECT_EQ(p.robots[centre].status, RobotPlan::Status::reached) << p.summary(m);
  for (std::size_t i = 0; i < 7; ++i)
    if (i != centre) {
      EXPECT_EQ(p.robots[i].status, RobotPlan::Status::frozen);
    }
  expect_sound(m, p, req);
}

TEST(Planner, BoxedInRobotWhoseTargetIsTakenIsReportedNotDropped) {
  // The target of robot 2 lies where frozen robot 1's arm stands: robot 2 is parked, with the
  // reason and the blocker, and the plan for the others is still checked clear.
  const auto m = build({robot_at(1, 0, 0), robot_at(2, 22.4, 0), robot_at(3, -22.4, 0)});
  PlanRequest req;
  req.current = {{0, 90}, {90, 180}, {90, 180}};
  req.target = {{0, 90}, {180, 10}, {0, 150}};
  req.frozen = {true, false, false};
  ASSERT_LT(static_clearance(m, req.target), 0);
  auto r = plan_moves(m, req);
  ASSERT_TRUE(r) << r.error().message();
  const Plan& p = r.value();
  EXPECT_EQ(p.robots[1].status, RobotPlan::Status::parked);
  EXPECT_NE(p.robots[1].reason.find("collides with robot 1"), std::string::npos) << p.robots[1].reason;
  EXPECT_EQ(p.robots[1].blockers, std::vector<std::int32_t>{1});
  EXPECT_EQ(p.robots[2].status, RobotPlan::Status::reached);
  EXPECT_EQ(p.not_reached, 1u);
  EXPECT_FALSE(p.ok());
  EXPECT_NE(p.summary(m).find("robot 2: parked"), std::string::npos);
  expect_sound(m, p, req);
}

TEST(Planner, TargetNextToAFiducial) {
  // A fiducial in the hex hole at (22.4, 0): the target puts the arm's capsule 0.3 mm from the
  // fiducial's buffer.
  const auto m = build({robot_at(1, 0, 0)}, {{7, {22.4, 0}, 3.0}});
  // Segment along the x axis ending at 22.1 mm: distance 0.3 to the fiducial; limit 5 mm.
  // Turn the arm up until the distance is 5.3 mm: alpha 0, beta b with the end at 5.3 mm.
  Pose target{0, 0};
  for (double b = 0; b < 90; b += 0.01) {
    std::vector<Segment> s(1);
    m.segments(std::vector<Pose>{{0, b}}, s);
    if (segment_distance(s[0], {{22.4, 0}, {22.4, 0}}) - 5.0 >= 0.3) {
      target = {0, b};
      break;
    }
  }
  ASSERT_GT(target.beta_deg, 0);
  PlanRequest req;
  req.current = {{180, 170}};
  req.target = {target};
  auto r = plan_moves(m, req);
  ASSERT_TRUE(r) << r.error().message();
  const Plan& p = r.value();
  EXPECT_TRUE(p.ok()) << p.summary(m);
  expect_sound(m, p, req);
  EXPECT_GE(p.check.min_clearance_mm, 0.0);
  EXPECT_LT(p.check.min_clearance_mm, 0.35);
}

TEST(Planner, UnreachableTargetIntoAFiducialIsParkedAndReported) {
  const auto m = build({robot_at(1, 0, 0), robot_at(2, 0, 22.4 * std::sqrt(3.0))}, {{7, {22.4, 0}, 3.0}});
  PlanRequest req;
  req.current = {{10, 170}, {10, 170}};
  req.target = {{0, 0}, {270, 30}};  // robot 1 stretched onto the fiducial
  auto r = plan_moves(m, req);
  ASSERT_TRUE(r) << r.error().message();
  const Plan& p = r.value();
  EXPECT_EQ(p.robots[0].status, RobotPlan::Status::parked);
  EXPECT_NE(p.robots[0].reason.find("fiducial 7"), std::string::npos) << p.robots[0].reason;
  EXPECT_EQ(p.robots[1].status, RobotPlan::Status::reached);
  EXPECT_EQ(p.not_reached, 1u);
  expect_sound(m, p, req);
}

// Two robots that start inside each other's buffers (as a power loss mid-move can leave them) are
// held where they stand, each naming the other; the third is planned around them, and the plan is
// verified. Before, the whole plan was refused ("current poses already in contact").
TEST(Planner, RobotsThatStartInContactAreHeldAndTheRestIsPlanned) {
  const auto m = build({robot_at(1, 0, 0), robot_at(2, 22.4, 0), robot_at(3, 11.2, 22.4 * std::sqrt(3.0) / 2)});
  PlanRequest req;
  req.current = {{0, 0}, {180, 0}, {90, 170}};
  req.target = {{10, 170}, {10, 170}, {270, 60}};
  ASSERT_LT(static_clearance(m, req.current), 0.0);
  auto r = plan_moves(m, req);
  ASSERT_TRUE(r) << r.error().message();
  const Plan& p = r.value();
  EXPECT_EQ(p.robots[0].status, RobotPlan::Status::held);
  EXPECT_EQ(p.robots[1].status, RobotPlan::Status::held);
  EXPECT_NE(p.robots[0].reason.find("starts in contact with robot 2"), std::string::npos) << p.robots[0].reason;
  EXPECT_NE(p.robots[1].reason.find("starts in contact with robot 1"), std::string::npos) << p.robots[1].reason;
  EXPECT_EQ(p.robots[0].blockers, std::vector<std::int32_t>{2});
  EXPECT_EQ(p.robots[2].status, RobotPlan::Status::reached) << p.summary(m);
  EXPECT_EQ(p.not_reached, 2u);
  EXPECT_EQ(p.check.standing_contacts, 1u);
  EXPECT_EQ(p.robots[0].end, req.current[0]);
  expect_sound(m, p, req, {}, true);
}

// A robot against its alpha stop with a fiducial just ahead of its stretched arm cannot fold
// whatever its neighbours do: it is held at once with the reason (a flood fill of its angle space),
// not sent into the engine to be given up on after its retries.
TEST(Planner, ARobotBoxedInByAFiducialAndItsAlphaStopIsHeldWithTheReason) {
  // The fiducial sits on the arm's collision segment at alpha 12, beta 12: from alpha 1, beta 0
  // every way to the fold (beta 180) sweeps the arm across it, and alpha cannot go below 0.
  const auto probe = build({robot_at(1, 0, 0)});
  std::vector<Segment> seg(1);
  probe.segments(std::vector<Pose>{{12, 12}}, seg);
  const Vec2 f = seg[0].b;
  const auto m = build({robot_at(1, 0, 0), robot_at(2, 0, -22.4 * std::sqrt(3.0))}, {{7, f, 3.0}});
  PlanRequest req;
  req.current = {{1, 0}, {90, 170}};
  req.target = {{200, 170}, {100, 170}};
  ASSERT_GT(static_clearance(m, req.current), 0.0);
  auto r = plan_moves(m, req);
  ASSERT_TRUE(r) << r.error().message();
  const Plan& p = r.value();
  EXPECT_EQ(p.robots[0].status, RobotPlan::Status::held) << p.summary(m);
  EXPECT_NE(p.robots[0].reason.find("no fold is reachable from its start"), std::string::npos) << p.robots[0].reason;
  EXPECT_NE(p.robots[0].reason.find("fiducial 7"), std::string::npos) << p.robots[0].reason;
  EXPECT_EQ(p.robots[1].status, RobotPlan::Status::reached);
  expect_sound(m, p, req);

  // The same pocket as a target: parked at its fold, with the reason.
  PlanRequest back;
  back.current = {{200, 170}, {90, 170}};
  back.target = {{1, 0}, {100, 170}};
  auto rb = plan_moves(m, back);
  ASSERT_TRUE(rb) << rb.error().message();
  EXPECT_EQ(rb.value().robots[0].status, RobotPlan::Status::parked) << rb.value().summary(m);
  EXPECT_NE(rb.value().robots[0].reason.find("cannot be reached from any fold"), std::string::npos) << rb.value().robots[0].reason;
  expect_sound(m, rb.value(), back);
}

TEST(Planner, WrongRequestSizeIsAnError) {
  const auto m = build({robot_at(1, 0, 0)});
  PlanRequest req;
  req.current = {{0, 0}};
  auto r = plan_moves(m, req);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, make_error_code(PlanErrc::bad_trajectory));
}

TEST(Planner, SeededRandomPatchEveryRobotAccountedFor) {
  // 37 robots, from the folded lattice to a random clear configuration and back again from
  // there to another: every plan is clear, and every robot either reaches its target or is
  // reported with a reason.
  const auto m = build(hex_patch(3));
  ASSERT_EQ(m.size(), 37u);
  for (std::uint64_t seed : {1u, 2u}) {
    PlanRequest req;
    req.current = seed == 1 ? folded_poses(m) : random_poses(m, 100 + seed);
    req.target = random_poses(m, seed);
    PlannerOptions o;
    o.seed = seed;
    auto r = plan_moves(m, req, o);
    ASSERT_TRUE(r) << r.error().message();
    const Plan& p = r.value();
    expect_sound(m, p, req, o);
    // Most robots get there (the planner's success is measured on 500 robots by bench/fps_plan).
    EXPECT_LE(p.not_reached, 4u) << p.summary(m);
    EXPECT_GT(p.stats.duration_s, 0);
  }
}

TEST(Planner, OverlappingTheHalvesShortensMovesFromRandomStartsAndStaysClear) {
  // Random to random on 37 robots: with B started before A ends (as far as each robot's own halves
  // and the checker allow) and the middle phase's turns as soon as each robot has folded, the move
  // is shorter by at least the overlap, every plan still sound and the same robots reach their
  // targets.
  const auto m = build(hex_patch(3));
  double overlapped = 0;
  for (std::uint64_t seed : {3u, 4u, 5u}) {
    PlanRequest req;
    req.current = random_poses(m, 200 + seed);
    req.target = random_poses(m, seed);
    PlannerOptions on, off;
    on.seed = off.seed = seed;
    off.overlap_halves = false;
    auto a = plan_moves(m, req, on);
    auto b = plan_moves(m, req, off);
    ASSERT_TRUE(a && b);
    expect_sound(m, a.value(), req, on);
    expect_sound(m, b.value(), req, off);
    EXPECT_EQ(b.value().stats.overlap_s, 0.0);
    EXPECT_EQ(a.value().not_reached, b.value().not_reached);
    // Shorter by at least the overlap (more where middle-phase turns start early).
    EXPECT_LE(a.value().stats.duration_s, b.value().stats.duration_s - a.value().stats.overlap_s + 1e-6) << "seed " << seed;
    overlapped += a.value().stats.overlap_s;
  }
  EXPECT_GT(overlapped, 0);
}

TEST(Planner, SlowerSpeedGivesALongerMoveWithinThatSpeed) {
  const auto m = build({robot_at(1, 0, 0), robot_at(2, 22.4, 0)});
  PlanRequest req;
  req.current = {{0, 60}, {90, 170}};
  req.target = {{90, 180}, {180, 60}};
  PlannerOptions fast, slow;
  slow.speed = SpeedLimits::from_motor(1000, 1000);  // 6 deg/s
  EXPECT_DOUBLE_EQ(slow.speed.alpha_deg_s, 6.0);
  auto a = plan_moves(m, req, fast);
  auto b = plan_moves(m, req, slow);
  ASSERT_TRUE(a);
  ASSERT_TRUE(b);
  expect_sound(m, b.value(), req, slow);
  EXPECT_GT(b.value().stats.duration_s, 1.5 * a.value().stats.duration_s);
}

TEST(PlannerSimplify, DropsPointsWithinToleranceAndNeverSpeedsUp) {
  std::vector<TimedAngle> pts;
  for (int k = 0; k <= 20; ++k) pts.push_back({k * 0.1, k * 1.0 + ((k % 2) ? 0.05 : 0.0)});
  const auto s = simplify_arm(pts, 0.2);
  EXPECT_EQ(s.size(), 2u);
  EXPECT_LE(max_speed(s), max_speed(pts));
  for (const auto& p : pts) EXPECT_NEAR(angle_at(s, p.t_s), p.deg, 0.2);
  // A corner beyond the tolerance stays.
  const std::vector<TimedAngle> corner{{0, 0}, {1, 10}, {2, 10}};
  EXPECT_EQ(simplify_arm(corner, 0.2).size(), 3u);
  EXPECT_EQ(simplify_arm(corner, 0).size(), 3u);
}

}  // namespace
}  // namespace axon::fps::plan

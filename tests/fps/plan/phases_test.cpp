// The planner's phases (phases.hpp) one at a time, on small hand-made focal planes and hand-made
// engine results: what each phase decides, independently of the others.
#include "axon/fps/plan/phases.hpp"
#include "axon/fps/plan/problems.hpp"
#include "model_util.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

// A named namespace: in the unity build this file shares a translation unit with planner_test.cpp,
// whose anonymous-namespace helpers would clash with helpers of the same name here.
namespace axon::fps::plan::phases_test {

using namespace axon::fps::plan::phases;
using test::build;
using test::hex_patch;
using test::pts;
using test::robot_at;
using test::static_clearance;

// Contacts between targets that not both stay (what settle_targets must clear).
std::size_t moving_contacts(const CollisionModel& m, const Work& w) {
  std::vector<Segment> s(m.size());
  std::vector<Contact> c;
  m.segments(w.target, s);
  m.find_contacts(s, c);
  std::size_t count = 0;
  for (const auto& k : c) count += (w.still[k.a] && (k.kind != Contact::Kind::robot || w.still[k.b])) ? 0 : 1;
  return count;
}

// A one-point engine path per robot at `poses` (an engine result where nobody moved).
StepperResult standing(const std::vector<Pose>& poses) {
  StepperResult r;
  for (const Pose& p : poses) {
    r.paths.push_back(RobotTrajectory::hold(p));
    r.end.push_back(p);
    r.reached.push_back(true);
    r.blockers.emplace_back();
  }
  return r;
}

// Half A of two robots far apart that start at alpha 10 and 20, beta 100: robot 0 folds in A's
// first second, robot 1 until A's end at 4 s.
StepperResult a_folding_early_and_late() {
  StepperResult a = standing({{10, 180}, {20, 180}});
  a.paths[0].beta = {{0, 100}, {1, 180}};
  a.paths[1].beta = {{0, 100}, {4, 180}};
  a.duration_s = 4;
  return a;
}

// A small random problem on 19 robots (folded lattice to random targets), prepared and settled.
struct Patch {
  CollisionModel model = build(hex_patch(2));
  PlanRequest request;
  PlannerOptions options;
  Patch() {
    request.current = random_poses(model, 5);
    request.target = random_poses(model, 6);
  }
};

TEST(PlanPhases, CheckRequestRefusesWrongSizesAnglesAndSpeeds) {
  const auto m = test::two_robots();
  PlanRequest req;
  req.current = {{0, 180}, {180, 180}};
  req.target = req.current;
  PlannerOptions o;
  EXPECT_TRUE(check_request(m, req, o));
  PlanRequest short_req = req;
  short_req.target.pop_back();
  EXPECT_FALSE(check_request(m, short_req, o));
  PlanRequest frozen_req = req;
  frozen_req.frozen = {true};
  EXPECT_FALSE(check_request(m, frozen_req, o));
  PlanRequest nan_req = req;
  nan_req.target[1].beta_deg = std::numeric_limits<double>::quiet_NaN();
  auto r = check_request(m, nan_req, o);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, make_error_code(PlanErrc::bad_trajectory));
  PlannerOptions slow = o;
  slow.speed.beta_deg_s = 0;
  EXPECT_FALSE(check_request(m, req, slow));
  PlannerOptions no_step = o;
  no_step.step_deg = -1;
  EXPECT_FALSE(check_request(m, req, no_step));
}

TEST(PlanPhases, ContextDerivesTheEngineStepAndTheFold) {
  const auto m = build({robot_at(1, 0, 0), RobotSpec{2, {22.4, 0}, {}, {0, 360, 0, 170}, 2.0}});
  PlanRequest req;
  req.current = {{30, 100}, {60, 120}};
  req.target = req.current;
  PlannerOptions o;
  o.speed = {6, 12};
  o.step_deg = 2;
  const Context ctx = make_context(m, req, o);
  EXPECT_DOUBLE_EQ(ctx.engine.dt_s, 2.0 / 12.0);  // the faster arm moves step_deg per step
  EXPECT_DOUBLE_EQ(ctx.engine.alpha_step_deg, 1.0);
  EXPECT_DOUBLE_EQ(ctx.engine.beta_step_deg, 2.0);
  EXPECT_EQ(ctx.park_pose(0), (Pose{30, 180}));
  EXPECT_EQ(ctx.park_pose(1), (Pose{60, 170}));  // the fold beta within the robot's limits
  EXPECT_EQ(ctx.ids_of({1, 0}), (std::vector<std::int32_t>{2, 1}));
}

TEST(PlanPhases, PrepareHoldsFrozenAndStartContactsAndParksTargetsOutsideTheLimits) {
  // Robots 1 and 2 start stretched into each other; 3 is frozen; 4's target is past its alpha stop.
  const auto m = build({robot_at(1, 0, 0), robot_at(2, 22.4, 0), robot_at(3, 0, 100),
                        RobotSpec{4, {100, 0}, {}, {0, 180, 0, 360}, 2.0}});
  PlanRequest req;
  req.current = {{0, 0}, {180, 0}, {90, 90}, {90, 180}};
  req.target = {{10, 170}, {10, 170}, {0, 90}, {270, 90}};
  req.frozen = {false, false, true, false};
  ASSERT_LT(static_clearance(m, req.current), 0.0);
  const PlannerOptions o{};
  const Context ctx = make_context(m, req, o);
  const Work w = prepare(ctx);
  EXPECT_EQ(w.plan.robots[0].status, RobotPlan::Status::held);
  EXPECT_EQ(w.plan.robots[1].status, RobotPlan::Status::held);
  EXPECT_EQ(w.plan.robots[0].blockers, std::vector<std::int32_t>{2});
  EXPECT_EQ(w.plan.robots[2].status, RobotPlan::Status::frozen);
  EXPECT_EQ(w.plan.robots[3].status, RobotPlan::Status::parked);
  EXPECT_EQ(w.plan.robots[3].reason, "target outside the angle limits");
  EXPECT_EQ(w.still, (std::vector<bool>{true, true, true, false}));
  EXPECT_EQ(w.target[0], req.current[0]);
  EXPECT_EQ(w.target[2], req.current[2]);
  EXPECT_EQ(w.target[3], ctx.park_pose(3));
}

TEST(PlanPhases, SettleTargetsLeavesNoTargetInContact) {
  // Six robots stretched towards the centre robot, whose target is its fold: theirs overlap each
  // other's and the centre's.
  const auto m = build(hex_patch(1));
  const std::size_t centre = 3;
  ASSERT_EQ(m.robot(centre).centre(), (Vec2{0, 0}));
  PlanRequest req;
  req.current = folded_poses(m);
  for (std::size_t i = 0; i < m.size(); ++i) {
    const Vec2 c = m.robot(i).centre();
    const double towards = std::fmod(std::atan2(-c.y, -c.x) * 180 / std::acos(-1.0) + 360, 360);
    req.target.push_back({towards, 0});
  }
  const PlannerOptions o{};
  const Context ctx = make_context(m, req, o);
  req.target[centre] = ctx.park_pose(centre);
  Work w = prepare(ctx);
  ASSERT_GT(moving_contacts(m, w), 0u);
  settle_targets(ctx, w);
  EXPECT_EQ(moving_contacts(m, w), 0u);
  std::size_t parked = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    if (w.plan.robots[i].status != RobotPlan::Status::parked) continue;
    ++parked;
    EXPECT_EQ(w.target[i], ctx.park_pose(i));
    EXPECT_NE(w.plan.robots[i].reason.find("target collides with robot"), std::string::npos) << w.plan.robots[i].reason;
  }
  // The centre is folded already: every other robot gives way to it.
  EXPECT_EQ(parked, m.size() - 1);
  EXPECT_EQ(w.plan.robots[centre].status, RobotPlan::Status::reached);
  EXPECT_EQ(w.target[centre], req.target[centre]);
}

TEST(PlanPhases, SettleTargetsHoldsARobotWhoseFoldTouchesARobotThatStays) {
  // Robot 1 is frozen stretched over robot 2's centre, so robot 2 cannot even fold there.
  const auto m = test::two_robots();
  PlanRequest req;
  req.current = {{0, 0}, {0, 0}};
  req.target = {{0, 0}, {180, 0}};
  req.frozen = {true, false};
  const PlannerOptions o{};
  const Context ctx = make_context(m, req, o);
  ASSERT_GT(static_clearance(m, req.current), 0.0);
  ASSERT_LT(static_clearance(m, {req.current[0], ctx.park_pose(1)}), 0.0);
  ASSERT_LT(static_clearance(m, req.target), 0.0);
  Work w = prepare(ctx);
  settle_targets(ctx, w);
  EXPECT_EQ(w.plan.robots[1].status, RobotPlan::Status::held);
  EXPECT_EQ(w.plan.robots[1].reason, "its folded pose collides with a robot that stays");
  EXPECT_TRUE(w.still[1]);
  EXPECT_EQ(w.target[1], req.current[1]);
}

TEST(PlanPhases, ChooseFoldsFoldsEveryMovingRobotClearOfTheOthers) {
  Patch p;
  const Context ctx = make_context(p.model, p.request, p.options);
  Work w = prepare(ctx);
  settle_targets(ctx, w);
  w.still[0] = true;  // as if robot 1 were held
  w.target[0] = p.request.current[0];
  Folds f = no_folds(p.model.size());
  choose_folds(ctx, w, f);
  std::vector<Pose> folds;
  for (std::size_t i = 0; i < p.model.size(); ++i) {
    folds.push_back(w.still[i] ? ctx.park_pose(i) : f.a[i].goal);
    if (w.still[i]) {
      EXPECT_TRUE(f.a[i].frozen && f.b[i].frozen);
      EXPECT_EQ(f.a[i].goal, p.request.current[i]);
      continue;
    }
    EXPECT_EQ(f.a[i].start, p.request.current[i]);
    EXPECT_EQ(f.b[i].start, w.target[i]);
    EXPECT_EQ(f.a[i].goal, f.b[i].goal);  // both halves meet at one fold
    EXPECT_EQ(f.a[i].goal.beta_deg, ctx.fold_beta(i));
    EXPECT_TRUE(p.model.robot(i).within_limits(f.a[i].goal));
  }
  EXPECT_GT(static_clearance(p.model, folds), 0.0);  // no fold touches another robot

  // A half that gave up its fold keeps its own alpha.
  f.relax_b[1] = true;
  f.relax_a[2] = true;
  choose_folds(ctx, w, f);
  EXPECT_EQ(f.a[1].goal.alpha_deg, w.target[1].alpha_deg);
  EXPECT_EQ(f.b[1].goal.alpha_deg, w.target[1].alpha_deg);
  EXPECT_EQ(f.a[2].goal.alpha_deg, p.request.current[2].alpha_deg);
}

TEST(PlanPhases, RunHalvesEndAtTheFoldsAndDoNotDependOnTheThreads) {
  Patch p;
  const Context ctx = make_context(p.model, p.request, p.options);
  Work w = prepare(ctx);
  settle_targets(ctx, w);
  Folds f = no_folds(p.model.size());
  choose_folds(ctx, w, f);
  Folds f1 = f;
  Search s;
  run_halves(ctx, w, f, 0, s);
  ASSERT_EQ(s.a.paths.size(), p.model.size());
  for (std::size_t i = 0; i < p.model.size(); ++i) {
    ASSERT_TRUE(s.a.reached[i] && s.b.reached[i]) << "robot " << i;  // an easy problem: nobody stuck
    EXPECT_EQ(s.a.paths[i].alpha.front().deg, p.request.current[i].alpha_deg);
    EXPECT_EQ(s.b.paths[i].beta.front().deg, w.target[i].beta_deg);
    EXPECT_EQ(s.a.end[i], f.a[i].goal);
    EXPECT_EQ(s.b.end[i], f.b[i].goal);
  }
  PlannerOptions serial = p.options;
  serial.parallel = false;
  const Context ctx1 = make_context(p.model, p.request, serial);
  Search s1;
  run_halves(ctx1, w, f1, 0, s1);
  for (std::size_t i = 0; i < p.model.size(); ++i) {
    EXPECT_EQ(s1.a.end[i], s.a.end[i]);
    EXPECT_EQ(s1.b.paths[i].alpha.size(), s.b.paths[i].alpha.size());
  }
}


TEST(PlanPhases, TakeStuckRobotsHoldsThoseStuckInAAndParksThoseStuckInB) {
  const auto m = build({robot_at(1, 0, 0), robot_at(2, 100, 0), robot_at(3, 200, 0)});
  PlanRequest req;
  req.current = {{0, 180}, {10, 90}, {20, 90}};
  req.target = {{90, 90}, {100, 90}, {110, 90}};
  const PlannerOptions o{};
  const Context ctx = make_context(m, req, o);
  Work w = prepare(ctx);
  Search s;
  s.a = standing(req.current);
  s.b = standing(req.target);
  EXPECT_FALSE(take_stuck_robots(ctx, w, s));
  s.a.reached[1] = false;
  s.a.blockers[1] = {0};
  s.b.reached[2] = false;
  s.b.blockers[2] = {1, 0};
  EXPECT_TRUE(take_stuck_robots(ctx, w, s));
  EXPECT_EQ(w.plan.robots[0].status, RobotPlan::Status::reached);
  EXPECT_EQ(w.plan.robots[1].status, RobotPlan::Status::held);
  EXPECT_EQ(w.plan.robots[1].blockers, std::vector<std::int32_t>{1});
  EXPECT_TRUE(w.still[1]);
  EXPECT_EQ(w.target[1], req.current[1]);
  EXPECT_EQ(w.plan.robots[2].status, RobotPlan::Status::parked);
  EXPECT_EQ(w.plan.robots[2].reason, kReverseStuck);
  EXPECT_EQ(w.plan.robots[2].blockers, (std::vector<std::int32_t>{2, 1}));
  EXPECT_EQ(w.target[2], ctx.park_pose(2));
}

TEST(PlanPhases, RunMiddleTurnsFoldedRobotsFromTheirAFoldToTheirBFold) {
  const auto m = build(hex_patch(1));
  PlanRequest req;
  req.current = folded_poses(m);
  req.target = req.current;
  const PlannerOptions o{};
  const Context ctx = make_context(m, req, o);
  Work w = prepare(ctx);
  Folds f = no_folds(m.size());
  Search s;
  std::vector<Pose> fold_a(m.size(), Pose{40, 180}), fold_b = fold_a;
  s.a = standing(fold_a);
  s.b = standing(fold_b);
  EXPECT_FALSE(run_middle(ctx, w, f, 0, s));
  EXPECT_TRUE(s.middle.paths.empty());  // nobody turns: no middle phase

  fold_b[3] = {130, 180};
  s.b = standing(fold_b);
  f.relax_a[3] = true;
  EXPECT_FALSE(run_middle(ctx, w, f, 0, s));
  ASSERT_EQ(s.middle.paths.size(), m.size());
  EXPECT_TRUE(s.middle.reached[3]);
  EXPECT_EQ(s.middle.paths[3].alpha.back().deg, 130.0);
  EXPECT_NEAR(s.middle.duration_s, 90.0 / o.speed.alpha_deg_s, 0.2);
  EXPECT_EQ(s.middle.paths[0].alpha.size(), 1u);  // the others stand still
  EXPECT_TRUE(f.relax_a[3]);
  EXPECT_EQ(w.plan.robots[3].status, RobotPlan::Status::reached);
}

TEST(PlanPhases, RunMiddleParksARobotThatCannotTurnWhileFolded) {
  // Robot 2 stays stretched with its arm's end next to robot 1's centre: robot 1 folded at alpha
  // 167 is clear of it, at alpha 77 (pointing at it) not.
  const auto m = test::two_robots();
  PlanRequest req;
  req.current = {{167, 180}, {158, 0}};
  req.target = req.current;
  req.frozen = {false, true};
  const PlannerOptions o{};
  const Context ctx = make_context(m, req, o);
  ASSERT_GT(static_clearance(m, req.current), 0.0);
  ASSERT_LT(static_clearance(m, {{77, 180}, req.current[1]}), 0.0);
  Work w = prepare(ctx);
  Folds f = no_folds(m.size());
  f.relax_b[0] = true;
  Search s;
  s.a = standing(req.current);
  s.b = standing({{77, 180}, req.current[1]});
  EXPECT_TRUE(run_middle(ctx, w, f, 0, s));
  EXPECT_EQ(w.plan.robots[0].status, RobotPlan::Status::parked);
  EXPECT_EQ(w.plan.robots[0].reason, "cannot turn to its fold alpha while folded");
  EXPECT_EQ(w.target[0], ctx.park_pose(0));
  EXPECT_FALSE(f.relax_b[0]);  // parked robots choose their folds afresh
}

TEST(PlanPhases, SearchRoundsLeavesEveryRobotThatMovesFoldedByBothHalves) {
  Patch p;
  const Context ctx = make_context(p.model, p.request, p.options);
  Work w = prepare(ctx);
  settle_targets(ctx, w);
  Search s;
  ASSERT_TRUE(search_rounds(ctx, w, s));
  EXPECT_GE(w.plan.stats.rounds, 1u);
  EXPECT_GT(s.search_s, 0.0);
  for (std::size_t i = 0; i < p.model.size(); ++i) {
    if (w.still[i]) {
      EXPECT_NE(w.plan.robots[i].status, RobotPlan::Status::reached);
      continue;
    }
    EXPECT_TRUE(s.a.reached[i]) << "robot " << i;
    EXPECT_TRUE(s.b.reached[i]) << "robot " << i;
    EXPECT_EQ(s.b.paths[i].alpha.front().deg, w.target[i].alpha_deg);
    EXPECT_EQ(s.a.end[i].beta_deg, ctx.fold_beta(i));
  }
}

TEST(PlanPhases, FinishParkedDrivesReverseStuckRobotsToTheirTargetsAndDropsThoseThatCannot) {
  const auto m = test::two_robots();
  PlanRequest req;
  req.current = {{0, 180}, {180, 180}};
  req.target = {{90, 60}, {180, 180}};
  const PlannerOptions o{};
  const Context ctx = make_context(m, req, o);
  Work w = prepare(ctx);
  w.plan.robots[0] = {RobotPlan::Status::parked, {}, kReverseStuck, {}};
  w.target[0] = ctx.park_pose(0);
  Search s;
  s.b = standing({ctx.park_pose(0), req.current[1]});  // where B starts: the ends
  const Finish fin = finish_parked(ctx, w, s);
  ASSERT_TRUE(fin.any);
  EXPECT_EQ(fin.in, (std::vector<bool>{true, false}));
  ASSERT_TRUE(fin.run.reached[0]);
  EXPECT_EQ(fin.run.end[0], req.target[0]);
  EXPECT_EQ(fin.run.paths[0].alpha.front().deg, ctx.park_pose(0).alpha_deg);

  // A target robot 2's arm stands over at the end (its fold is clear): dropped, stays folded.
  // Robot 2 is parked for another reason: not finished.
  PlanRequest blocked;
  blocked.current = {{167, 180}, {158, 0}};
  blocked.target = {{77, 0}, {158, 0}};
  const Context ctx2 = make_context(m, blocked, o);
  ASSERT_GT(static_clearance(m, blocked.current), 0.0);
  ASSERT_LT(static_clearance(m, blocked.target), 0.0);
  Work w2 = prepare(ctx2);
  w2.plan.robots[0] = {RobotPlan::Status::parked, {}, kReverseStuck, {}};
  w2.plan.robots[1] = {RobotPlan::Status::parked, {}, "target collides with robot 1", {}};
  Search s2;
  s2.b = standing({ctx2.park_pose(0), blocked.current[1]});
  const Finish fin2 = finish_parked(ctx2, w2, s2);
  EXPECT_FALSE(fin2.any);
  EXPECT_EQ(fin2.in, (std::vector<bool>{false, false}));
  EXPECT_TRUE(fin2.run.paths.empty());
}

TEST(PlanPhases, JoinHalvesPlaysBBackwardsAfterAAndTheMiddle) {
  const auto m = build({robot_at(1, 0, 0), robot_at(2, 100, 0)});
  PlanRequest req;
  req.current = {{10, 100}, {20, 100}};
  req.target = {{50, 90}, {20, 100}};
  const PlannerOptions o{};
  const Context ctx = make_context(m, req, o);
  Work w = prepare(ctx);
  w.plan.robots[1] = {RobotPlan::Status::held, {}, "test", {}};
  Search s;
  s.a = standing({{30, 180}, req.current[1]});
  s.a.paths[0] = {{{0, 10}, {2, 30}}, {{0, 100}, {1, 180}}};
  s.a.duration_s = 2;
  s.b = standing({{40, 180}, req.current[1]});
  s.b.paths[0] = {{{0, 50}, {3, 40}}, {{0, 90}, {1.5, 180}}};
  s.b.duration_s = 3;
  s.middle = standing({{30, 180}, req.current[1]});
  s.middle.paths[0].alpha = {{0, 30}, {1, 40}};
  s.middle.duration_s = 1;
  join_halves(ctx, w, s, Finish{{}, {false, false}, false});
  const RobotTrajectory& t = w.plan.trajectories[0];
  // A until 2 s, the middle until 3 s, B backwards from 3 to 6 s.
  EXPECT_EQ(pts(t.alpha), pts({{0, 10}, {2, 30}, {3, 40}, {6, 50}}));
  EXPECT_EQ(pts(t.beta), pts({{0, 100}, {1, 180}, {4.5, 180}, {6, 90}}));
  EXPECT_EQ(w.plan.robots[0].end, (Pose{50, 90}));
  EXPECT_EQ(w.plan.trajectories[1].alpha.size(), 1u);  // still points dropped
  EXPECT_EQ(w.plan.stats.middle_s, 1.0);
  EXPECT_EQ(w.plan.not_reached, 1u);

  // With a finish for robot 1: appended after B, and the robot counts as reached.
  Work w2 = prepare(ctx);
  w2.plan.robots[0] = {RobotPlan::Status::parked, {}, kReverseStuck, {}};
  s.a.paths[0] = {{{0, 10}, {2, 30}}, {{0, 100}, {1, 180}}};
  s.middle = {};
  Finish fin{standing({{40, 180}, req.current[1]}), {true, false}, true};
  fin.run.paths[0].alpha = {{0, 50}, {2, 70}};
  join_halves(ctx, w2, s, fin);
  EXPECT_EQ(pts(w2.plan.trajectories[0].alpha), pts({{0, 10}, {2, 30}, {5, 50}, {7, 70}}));
  EXPECT_EQ(w2.plan.robots[0].status, RobotPlan::Status::reached);
  EXPECT_EQ(w2.plan.not_reached, 0u);
}

TEST(PlanPhases, OverlapStartsBAsEarlyAsEveryRobotsOwnHalvesAllow) {
  // Two robots far apart: robot 0 is folded after 1 s of A and needs all of B's 3 s; robot 1 folds
  // until A's end at 4 s and leaves its fold 2 s into B. B can start 2 s early (robot 1's wait);
  // robot 0 alone would allow 3 s.
  const auto m = build({robot_at(1, 0, 0), robot_at(2, 100, 0)});
  PlanRequest req;
  req.current = {{10, 100}, {20, 100}};
  req.target = {{50, 90}, {60, 120}};
  const PlannerOptions o{};
  const Context ctx = make_context(m, req, o);
  Search s;
  s.a = a_folding_early_and_late();
  s.b = standing({{50, 180}, {60, 180}});
  s.b.paths[0] = {{{0, 50}, {3, 10}}, {{0, 90}, {3, 180}}};
  s.b.paths[1].beta = {{0, 120}, {1, 180}};
  s.b.duration_s = 3;
  std::size_t checks = 0;
  double check_s = 0;
  EXPECT_DOUBLE_EQ(overlap_shift(ctx, s, 4, 3, checks, check_s), 2.0);
  EXPECT_EQ(checks, 1u);

  Work w = prepare(ctx);
  join_halves(ctx, w, s, Finish{{}, {false, false}, false});
  EXPECT_DOUBLE_EQ(w.plan.stats.overlap_s, 2.0);
  // B from 2 s on: robot 0 leaves its fold right away, robot 1 at 4 s, as it arrived.
  EXPECT_EQ(pts(w.plan.trajectories[0].alpha), pts({{0, 10}, {2, 10}, {5, 50}}));
  EXPECT_EQ(pts(w.plan.trajectories[1].beta), pts({{0, 100}, {4, 180}, {5, 120}}));

  // Off: B starts at A's end.
  PlannerOptions off;
  off.overlap_halves = false;
  const Context ctx_off = make_context(m, req, off);
  EXPECT_EQ(overlap_shift(ctx_off, s, 4, 3, checks, check_s), 0.0);
}

TEST(PlanPhases, OverlapIsRefusedWhereARobotStillInAAndOneAlreadyInBWouldTouch) {
  // Robot 0 waits at its start until 4 s of A, then folds; robot 1 starts folded and unfolds
  // towards it in B over 5 s. Each half is clear; started together, robot 1 sweeps into robot 0
  // while it still waits.
  const CollisionModel m = test::two_robots();
  const Pose s0{165, 0}, f0{165, 180}, f1{180, 180}, t1{180, 45};
  ASSERT_GT(static_clearance(m, {s0, f1}), 0);
  ASSERT_GT(static_clearance(m, {f0, t1}), 0);
  PlanRequest req;
  req.current = {s0, f1};
  req.target = {f0, t1};
  const PlannerOptions o{};
  const Context ctx = make_context(m, req, o);
  Search s;
  s.a = standing({f0, f1});
  s.a.paths[0].beta = {{0, 0}, {4, 0}, {5, 180}};
  s.a.duration_s = 5;
  s.b = standing({f0, f1});
  s.b.paths[1].beta = {{0, 45}, {5, 180}};
  s.b.duration_s = 5;
  // The most the robots' own halves allow, 5 s, would collide: the checker says so on its own.
  TrajectoryChecker checker(m);
  CheckReport r;
  const std::vector<RobotTrajectory> together{s.a.paths[0], {{{0, 180}}, {{0, 180}, {5, 45}}}};
  ASSERT_TRUE(checker.check(together, CheckOptions{}, r));
  ASSERT_FALSE(r.ok());
  for (const auto* half : {&s.a.paths, &s.b.paths}) {  // each half on its own is clear
    ASSERT_TRUE(checker.check(*half, CheckOptions{}, r));
    ASSERT_TRUE(r.ok());
  }

  std::size_t checks = 0;
  double check_s = 0;
  const double shift = overlap_shift(ctx, s, 5, 5, checks, check_s);
  EXPECT_LT(shift, 5.0);
  EXPECT_GT(checks, 1u);
  Work w = prepare(ctx);
  join_halves(ctx, w, s, Finish{{}, {false, false}, false});
  EXPECT_EQ(w.plan.stats.overlap_s, shift);
  const auto checked = checker.check(w.plan.trajectories, CheckOptions{}, r);
  ASSERT_TRUE(checked) << checked.error().message();
  EXPECT_TRUE(r.ok()) << r.collided_pairs << " pairs collided";
  EXPECT_DOUBLE_EQ(end_time(w.plan.trajectories[1]), 10.0 - shift);
}

TEST(PlanPhases, MiddleTurnsStartWhenTheRobotHasFolded) {
  // Robot 0 is folded after 1 s of A and turns alpha 10 -> 40 in the middle phase (2.5 s); robot 1,
  // far away, folds until A's end at 4 s. Robot 0 turns from 1 s on, and B (3 s) starts when its
  // turn ends (3.5 s: robot 0 leaves at once in B): 6.5 s instead of 4 + 2.5 + 3.
  const auto m = build({robot_at(1, 0, 0), robot_at(2, 100, 0)});
  PlanRequest req;
  req.current = {{10, 100}, {20, 100}};
  req.target = {{50, 90}, {20, 180}};
  const PlannerOptions o{};
  const Context ctx = make_context(m, req, o);
  Search s;
  s.a = a_folding_early_and_late();
  s.middle = standing({{40, 180}, {20, 180}});
  s.middle.paths[0].alpha = {{0, 10}, {2.5, 40}};
  s.middle.duration_s = 2.5;
  s.b = standing({{40, 180}, {20, 180}});
  s.b.paths[0] = {{{0, 50}, {3, 40}}, {{0, 90}, {3, 180}}};
  s.b.duration_s = 3;
  std::size_t checks = 0;
  double check_s = 0;
  EXPECT_EQ(middle_starts(ctx, s, checks, check_s), (std::vector<double>{1, 4}));
  EXPECT_EQ(checks, 1u);

  Work w = prepare(ctx);
  join_halves(ctx, w, s, Finish{{}, {false, false}, false});
  EXPECT_EQ(pts(w.plan.trajectories[0].alpha), pts({{0, 10}, {1, 10}, {3.5, 40}, {6.5, 50}}));
  EXPECT_DOUBLE_EQ(w.plan.stats.overlap_s, 0.5);  // robot 1 would allow 3 s, robot 0 0.5 s
  EXPECT_EQ(w.plan.stats.middle_s, 2.5);

  PlannerOptions off;
  off.overlap_halves = false;
  const Context ctx_off = make_context(m, req, off);
  EXPECT_EQ(middle_starts(ctx_off, s, checks, check_s), (std::vector<double>{4, 4}));
}

TEST(PlanPhases, MiddleTurnWaitsForANeighbourStillUnfoldedInA) {
  // Robot 0 is folded from the start and turns alpha 0 -> 120 in the middle; robot 1 stands
  // unfolded next to it until 4 s of A, then folds. Turning at once would sweep robot 0 into it
  // (the checker says so on its own): robot 0 turns at A's end.
  const CollisionModel m = test::two_robots();
  PlanRequest req;
  req.current = {{0, 180}, {180, 45}};
  req.target = {{120, 180}, {180, 180}};
  const PlannerOptions o{};
  const Context ctx = make_context(m, req, o);
  Search s;
  s.a = standing({{0, 180}, {180, 180}});
  s.a.paths[1].beta = {{0, 45}, {4, 45}, {5, 180}};
  s.a.duration_s = 5;
  s.middle = standing({{120, 180}, {180, 180}});
  s.middle.paths[0].alpha = {{0, 0}, {2.5, 120}};
  s.middle.duration_s = 2.5;
  s.b = standing({{120, 180}, {180, 180}});
  TrajectoryChecker checker(m);
  CheckReport r;
  ASSERT_TRUE(checker.check(std::vector<RobotTrajectory>{s.middle.paths[0], s.a.paths[1]}, CheckOptions{}, r));
  ASSERT_FALSE(r.ok());

  std::size_t checks = 0;
  double check_s = 0;
  EXPECT_EQ(middle_starts(ctx, s, checks, check_s), (std::vector<double>{5, 5}));
  EXPECT_EQ(checks, 2u);  // the early turn refused, then the turns at A's end checked
  Work w = prepare(ctx);
  join_halves(ctx, w, s, Finish{{}, {false, false}, false});
  EXPECT_EQ(pts(w.plan.trajectories[0].alpha), pts({{0, 0}, {5, 0}, {7.5, 120}}));
  ASSERT_TRUE(checker.check(w.plan.trajectories, CheckOptions{}, r));
  EXPECT_TRUE(r.ok());
}

TEST(PlanPhases, SmoothAndSimplifyBuildsTheLayersAndFitsTheFirmwareLimit) {
  const auto m = build({robot_at(1, 0, 0), robot_at(2, 100, 0)});
  PlanRequest req;
  req.current = {{0, 180}, {0, 180}};
  req.target = req.current;
  PlannerOptions o;
  o.smooth_points = 0;
  o.simplify_deg = 0;
  o.max_points = 3;
  const Context ctx = make_context(m, req, o);
  Work w = prepare(ctx);
  RobotTrajectory zigzag;
  for (int k = 0; k <= 10; ++k) zigzag.alpha.push_back({double(k), k % 2 == 0 ? 0.0 : 5.0});
  zigzag.beta = {{0, 180}};
  RobotTrajectory small = {{{0, 0}, {1, 1.001}, {2, 2}, {3, 5}}, {{0, 180}}};
  w.plan.trajectories = {zigzag, small};
  const Layers L = smooth_and_simplify(ctx, w);
  ASSERT_EQ(L.plans.size(), 2u);  // simplified, exact (no smoothing)
  EXPECT_EQ(pts(L.plans[1][0].alpha), pts(zigzag.alpha));
  EXPECT_LE(L.plans[0][0].alpha.size() - 1, o.max_points);  // coarser until it fits
  EXPECT_TRUE(L.simplified[0]);
  EXPECT_FALSE(L.simplified[1]);  // within the limit, and simplify_deg 0: left alone
  EXPECT_EQ(pts(L.plans[0][1].alpha), pts(small.alpha));

  PlannerOptions fine = o;
  fine.simplify_deg = 0.01;
  const Context ctx2 = make_context(m, req, fine);
  const Layers L2 = smooth_and_simplify(ctx2, w);
  EXPECT_TRUE(L2.simplified[1]);
  EXPECT_EQ(pts(L2.plans[0][1].alpha), pts({{0, 0}, {2, 2}, {3, 5}}));  // the point within 0.01 deg dropped
}

// Two robots one pitch apart that stretch towards each other (they touch at the end), stay folded,
// or (robot 1, a_away) stretch away from the other, its arm pointing away all the way.
struct Collide {
  CollisionModel model = test::two_robots();
  PlanRequest request;
  PlannerOptions options;
  RobotTrajectory a_moves = RobotTrajectory::linear({0, 180}, {0, 0}, 0, 5);
  RobotTrajectory b_moves = RobotTrajectory::linear({180, 180}, {180, 0}, 0, 5);
  RobotTrajectory a_away = RobotTrajectory::linear({0, 180}, {180, 0}, 0, 5);
  RobotTrajectory a_stays = RobotTrajectory::hold({0, 180});
  RobotTrajectory b_stays = RobotTrajectory::hold({180, 180});
  Collide() {
    request.current = {{0, 180}, {180, 180}};
    request.target = {{0, 0}, {180, 0}};
  }
  bool clean(const std::vector<RobotTrajectory>& layer) {
    TrajectoryChecker checker(model);
    CheckReport r;
    CheckOptions co;
    co.allow_standing_contacts = true;
    EXPECT_TRUE(checker.check(layer, co, r));
    return r.ok();
  }
};

TEST(PlanPhases, VerifyLayersKeepsTheFirstLayerWhenItIsClean) {
  Collide c;
  const Context ctx = make_context(c.model, c.request, c.options);
  Work w = prepare(ctx);
  Layers L{{{c.a_away, c.b_stays}, {c.a_stays, c.b_stays}}, {true, false}, {true, true}, {}};
  ASSERT_TRUE(c.clean(L.plans[0]));
  ASSERT_TRUE(verify_layers(ctx, w, L));
  EXPECT_TRUE(w.plan.verified);
  EXPECT_EQ(w.plan.stats.checks, 1u);
  EXPECT_EQ(L.level, (std::vector<std::size_t>{0, 0}));
  EXPECT_EQ(pts(w.plan.trajectories[0].alpha), pts(c.a_away.alpha));
  EXPECT_EQ(L.simplified, (std::vector<bool>{true, true}));
  EXPECT_EQ(L.smoothed, (std::vector<bool>{true, false}));
}

TEST(PlanPhases, VerifyLayersFallsBackPastLayersThatCollide) {
  Collide c;
  const Context ctx = make_context(c.model, c.request, c.options);
  Work w = prepare(ctx);
  // Layer 1 still collides for robot 2 (the same as layer 0): robot 2 goes on to layer 2.
  Layers L{{{c.a_moves, c.b_moves}, {c.a_stays, c.b_moves}, {c.a_stays, c.b_stays}}, {true, true}, {true, true}, {}};
  ASSERT_FALSE(c.clean(L.plans[0]));
  ASSERT_FALSE(c.clean(L.plans[1]));
  ASSERT_TRUE(c.clean(L.plans[2]));
  ASSERT_TRUE(verify_layers(ctx, w, L));
  EXPECT_TRUE(w.plan.verified);
  EXPECT_TRUE(w.plan.check.ok());
  EXPECT_EQ(w.plan.stats.checks, 2u);
  EXPECT_EQ(L.level, (std::vector<std::size_t>{1, 2}));
  EXPECT_EQ(pts(w.plan.trajectories[1].alpha), pts(c.b_stays.alpha));
  EXPECT_EQ(pts(w.plan.trajectories[0].beta), pts(c.a_stays.beta));
  EXPECT_EQ(L.simplified, (std::vector<bool>{false, false}));  // neither kept its simplified layer
  EXPECT_EQ(L.smoothed, (std::vector<bool>{true, false}));     // robot 2 ended on the exact layer

  // Not verifying: layer 0 as it is.
  PlannerOptions off = c.options;
  off.verify = false;
  const Context ctx2 = make_context(c.model, c.request, off);
  Work w2 = prepare(ctx2);
  Layers L2{{{c.a_moves, c.b_moves}, {c.a_stays, c.b_stays}}, {false, false}, {false, false}, {}};
  ASSERT_TRUE(verify_layers(ctx2, w2, L2));
  EXPECT_FALSE(w2.plan.verified);
  EXPECT_EQ(w2.plan.stats.checks, 0u);
  EXPECT_EQ(pts(w2.plan.trajectories[1].beta), pts(c.b_moves.beta));
}

TEST(PlanPhases, CollectStatsCountsPointsSpeedsAndTheDuration) {
  Work w;
  w.plan.trajectories = {
      {{{0, 0}, {2, 12}, {4, 12}, {5, 20}}, {{0, 180}}},  // alpha: 3 points, up to 8 deg/s
      {{{0, 30}}, {{0, 180}, {3, 150}}},                  // beta: 1 point, 10 deg/s
      {{{0, 50}, {1, 51}}, {{0, 170}, {6, 176}}},          // 1 point each
  };
  Layers L;
  L.simplified = {true, false, true};
  L.smoothed = {false, false, true};
  collect_stats(w, L);
  const PlanStats& st = w.plan.stats;
  EXPECT_EQ(st.max_points, 3u);
  EXPECT_EQ(st.median_points, 1u);  // of 3, 1, 1, 1
  EXPECT_DOUBLE_EQ(st.max_alpha_speed, 8.0);
  EXPECT_DOUBLE_EQ(st.max_beta_speed, 10.0);
  EXPECT_DOUBLE_EQ(st.duration_s, 6.0);
  EXPECT_EQ(st.simplified, 2u);
  EXPECT_EQ(st.smoothed, 1u);
}

}  // namespace axon::fps::plan::phases_test

// The checker, both methods: collisions that only happen mid-move, clearances, the dense method's
// sampling step, the advancing method against brute force.
#include "axon/fps/plan/checker.hpp"
#include "model_util.hpp"
#include "support/short_run.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

namespace axon::fps::plan {
namespace {

using test::build;
using test::static_clearance;

// Robot 1 at the origin sweeps alpha from -60 to +60 deg in 10 s (12 deg/s) with beta 0.
// Robot 2 at (24, 0) holds alpha 90, beta 0: its segment runs up from (24, 7.4) to (24, 22.1).
// Robot 1's segment end (22.1 mm out) passes closest to (24, 7.4) at alpha = atan2(7.4, 24) =
// 17.14 deg (t = 77.14 / 12 = 6.43 s): gap hypot(24, 7.4) - 22.1 = 3.0149, clearance -0.9851.
// At both ends the arms are far apart.
struct Sweep {
  CollisionModel model = build({{1, {0, 0}, {}, {}, 2.0}, {2, {24, 0}, {}, {}, 2.0}});
  std::vector<RobotTrajectory> traj{RobotTrajectory::linear({-60, 0}, {60, 0}, 0, 10),
                                    RobotTrajectory::hold({90, 0})};
};

CheckOptions dense() {
  CheckOptions o;
  o.method = CheckMethod::dense;
  return o;
}

TEST(PlanChecker, CatchesCollisionThatOnlyHappensMidMove) {
  Sweep s;
  EXPECT_GT(static_clearance(s.model, {{-60, 0}, {90, 0}}), 5.0);
  EXPECT_GT(static_clearance(s.model, {{60, 0}, {90, 0}}), 5.0);

  TrajectoryChecker checker(s.model);
  CheckReport r;
  ASSERT_TRUE(checker.check(s.traj, dense(), r));
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.collided_pairs, 1u);
  ASSERT_EQ(r.robot_pairs.size(), 1u);
  const PairOutcome& p = r.robot_pairs[0];
  EXPECT_TRUE(p.collided);
  const double t_min = (std::atan2(7.4, 24.0) * 180 / std::numbers::pi + 60) / 12;
  EXPECT_NEAR(p.min_clearance_s, t_min, 0.02);
  EXPECT_NEAR(p.min_clearance_mm, std::hypot(24.0, 7.4) - 22.1 - 4, 1e-3);
  EXPECT_DOUBLE_EQ(r.min_clearance_mm, p.min_clearance_mm);
  // Contact starts before the closest approach and after the start.
  EXPECT_GT(p.first_collision_s, 0.0);
  EXPECT_LT(p.first_collision_s, t_min);
  // The reported first collision really is one, and a step earlier was clear.
  auto pose_at = [&](double t) { return Pose{angle_at(s.traj[0].alpha, t), 0}; };
  EXPECT_LT(static_clearance(s.model, {pose_at(p.first_collision_s), {90, 0}}), 0);
  EXPECT_GE(static_clearance(s.model, {pose_at(p.first_collision_s - r.step_s), {90, 0}}), 0);
}

// Two robots standing in contact the whole move (held by the planner where a power loss left
// them) keep the clearance they started with: a standing contact, not a collision of the move;
// with allow_standing_contacts off it counts. A third robot moving into one of them always counts.
TEST(PlanChecker, AContactBetweenRobotsThatNeverMoveIsTheStartsNotTheMoves) {
  const auto m = build({{1, {0, 0}, {}, {}, 2.0}, {2, {22.4, 0}, {}, {}, 2.0}});
  ASSERT_LT(static_clearance(m, {{0, 0}, {180, 0}}), 0.0);
  const std::vector<RobotTrajectory> still{RobotTrajectory::hold({0, 0}), RobotTrajectory::hold({180, 0})};
  TrajectoryChecker checker(m);
  CheckReport r;
  CheckOptions allow;
  allow.allow_standing_contacts = true;
  ASSERT_TRUE(checker.check(still, allow, r));
  EXPECT_TRUE(r.ok());
  EXPECT_EQ(r.standing_contacts, 1u);
  EXPECT_TRUE(r.robot_pairs[0].standing);
  ASSERT_TRUE(checker.check(still, {}, r));  // by default every contact counts
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.collided_pairs, 1u);
  EXPECT_LT(r.min_clearance_mm, 0.0);

  // Robot 2 turns further into robot 1: the move's collision.
  const std::vector<RobotTrajectory> moving{RobotTrajectory::hold({0, 0}), RobotTrajectory::linear({170, 0}, {180, 0}, 0, 1)};
  ASSERT_TRUE(checker.check(moving, allow, r));
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.standing_contacts, 0u);
}

TEST(PlanChecker, StepKeepsEveryArmPointWithinTheLimit) {
  Sweep s;
  TrajectoryChecker checker(s.model);
  CheckReport r;
  CheckOptions o = dense();
  o.max_step_mm = 0.05;
  ASSERT_TRUE(checker.check(s.traj, o, r));
  // 12 deg/s at up to 22.1 mm from the alpha axis: 4.63 mm/s, so steps of at most 10.8 ms.
  const double speed = 12 * std::numbers::pi / 180 * 22.1;
  EXPECT_LE(r.step_s * speed, 0.05 + 1e-12);
  EXPECT_GT(r.step_s * speed, 0.045);
  EXPECT_DOUBLE_EQ(r.start_s, 0);
  EXPECT_DOUBLE_EQ(r.end_s, 10);
  EXPECT_EQ(r.samples, static_cast<std::size_t>(std::round(10 / r.step_s)) + 1);
}

TEST(PlanChecker, SameReportWithOneOrTwoThreads) {
  Sweep s;
  // A slower step so the run is long enough to be split.
  TrajectoryChecker checker(s.model);
  CheckReport one, two;
  CheckOptions o = dense();
  o.max_step_mm = 0.01;
  o.threads = 1;
  ASSERT_TRUE(checker.check(s.traj, o, one));
  o.threads = 2;
  ASSERT_TRUE(checker.check(s.traj, o, two));
  ASSERT_GT(one.samples, 512u);
  EXPECT_DOUBLE_EQ(one.robot_pairs[0].first_collision_s, two.robot_pairs[0].first_collision_s);
  EXPECT_DOUBLE_EQ(one.robot_pairs[0].min_clearance_mm, two.robot_pairs[0].min_clearance_mm);
  EXPECT_DOUBLE_EQ(one.robot_pairs[0].min_clearance_s, two.robot_pairs[0].min_clearance_s);
}

// The advancing method on the same sweep: the contact's first instant is found to within the
// shortest step it takes (it never steps over a clear stretch's end), the deepest point to within
// the precision.
TEST(PlanChecker, AdvancingFindsTheContactWhereItBegins) {
  Sweep s;
  TrajectoryChecker checker(s.model);
  CheckReport r;
  ASSERT_TRUE(checker.check(s.traj, {}, r));
  EXPECT_FALSE(r.ok());
  const PairOutcome& p = r.robot_pairs[0];
  ASSERT_TRUE(p.collided);
  auto clearance_at = [&](double t) { return static_clearance(s.model, {{angle_at(s.traj[0].alpha, t), 0}, {90, 0}}); };
  double lo = 0, hi = 6.43;  // clear at 0, in contact at the closest approach
  for (int k = 0; k < 60; ++k) (clearance_at(0.5 * (lo + hi)) < 0 ? hi : lo) = 0.5 * (lo + hi);
  EXPECT_NEAR(p.first_collision_s, hi, 1e-4);
  const double deepest = std::hypot(24.0, 7.4) - 22.1 - 4;
  EXPECT_GE(p.min_clearance_mm, deepest - 1e-9);
  EXPECT_LE(p.min_clearance_mm, deepest + 0.05);
  EXPECT_EQ(r.step_s, 0.0);
  EXPECT_GT(r.evaluations(), 10u);
}

// Close but clear (0.3 mm at the closest approach): the reported clearance is a real one and
// within the precision (0.05 mm) of the smallest.
TEST(PlanChecker, AdvancingReportsACloseClearanceWithinItsPrecision) {
  const double x = std::sqrt(std::pow(22.1 + 4 + 0.3, 2) - 7.4 * 7.4);
  auto model = build({{1, {0, 0}, {}, {}, 2.0}, {2, {x, 0}, {}, {}, 2.0}});
  std::vector<RobotTrajectory> traj{RobotTrajectory::linear({-60, 0}, {60, 0}, 0, 10), RobotTrajectory::hold({90, 0})};
  TrajectoryChecker checker(model);
  CheckReport r;
  ASSERT_TRUE(checker.check(traj, {}, r));
  EXPECT_TRUE(r.ok());
  EXPECT_GE(r.min_clearance_mm, 0.3 - 1e-9);
  EXPECT_LE(r.min_clearance_mm, 0.3 + 0.05);

  // The beta arm turns its side at a fiducial (closing at 35-70% of the bound's rate) and back at
  // once: the clearance falls and rises in a V whose point is a trajectory point. Stretches end
  // at trajectory points, so the point is evaluated, not stepped over.
  for (const double along : {5.0, 7.35, 10.0})
    for (const double gap : {0.3, 0.6, 0.9}) {
      auto near_fiducial = build({{1, {0, 0}, {}, {}, 2.0}}, {{3, {7.4 + along, 2 + 3 + gap}, 3.0}});
      const RobotTrajectory poke{{{0, 0}}, {{0, -40}, {40.0 / 12, 0}, {80.0 / 12, -40}}};
      TrajectoryChecker fc(near_fiducial);
      ASSERT_TRUE(fc.check(std::vector{poke}, {}, r));
      EXPECT_TRUE(r.ok()) << gap;
      EXPECT_NEAR(r.min_clearance_mm, gap, 1e-9) << along << " mm along, gap " << gap;
      EXPECT_NEAR(r.obstacle_pairs[0].min_clearance_s, 40.0 / 12, 1e-9);
    }
}

// Random moves of several points per arm on a hex patch (7 rings: 169 robots), checked by the advancing
// method and by an evaluation of every pair at instants 0.01 mm of travel apart, written here.
struct RandomPatchMove {
  CollisionModel model;
  std::vector<RobotTrajectory> traj;
  double speed_mm_s = 0;  // the fastest body point of any robot
  explicit RandomPatchMove(unsigned seed, int rings = 7) : model(build(test::hex_patch(rings))) {
    std::mt19937 rng(seed);
    // Arms 12-30 deg/s at most (hops of up to 60 deg in 2-5 s), some standing still.
    std::uniform_real_distribution<double> a(0, 360), b(0, 180), turn(-60, 60), hop(2, 5), still(0, 1);
    for (std::size_t i = 0; i < model.size(); ++i) {
      RobotTrajectory t;
      for (auto* arm : {&t.alpha, &t.beta}) {
        double time = still(rng) < 0.3 ? 0.0 : hop(rng);
        const double hi = arm == &t.alpha ? 360 : 180;
        double angle = arm == &t.alpha ? a(rng) : b(rng);
        arm->push_back({time, angle});
        const int points = still(rng) < 0.2 ? 0 : 1 + static_cast<int>(still(rng) * 3);
        for (int k = 0; k < points; ++k) {
          time += hop(rng);
          angle = std::clamp(angle + turn(rng), 0.0, hi);
          arm->push_back({time, angle});
        }
      }
      const Positioner& p = model.robot(i);
      speed_mm_s = std::max(speed_mm_s, (max_speed(t.alpha) * p.reach_mm() + max_speed(t.beta) * p.collision_length_mm()) *
                                            std::numbers::pi / 180);
      traj.push_back(std::move(t));
    }
  }
  // Per robot pair: the smallest clearance at the brute-force instants.
  [[nodiscard]] std::vector<double> brute_force(double end_s, double travel_mm) const {
    std::vector<double> out(model.robot_pairs().size(), std::numeric_limits<double>::infinity());
    std::vector<Pose> poses(model.size());
    std::vector<Segment> segs(model.size());
    const double dt = travel_mm / speed_mm_s;
    for (double t = 0;; t = std::min(end_s, t + dt)) {
      for (std::size_t i = 0; i < model.size(); ++i) poses[i] = {angle_at(traj[i].alpha, t), angle_at(traj[i].beta, t)};
      model.segments(poses, segs);
      for (std::size_t k = 0; k < out.size(); ++k) out[k] = std::min(out[k], model.clearance(model.robot_pairs()[k], segs));
      if (t >= end_s) break;
    }
    return out;
  }
};

TEST(PlanChecker, AdvancingAgreesWithBruteForceOnRandomPatchMoves) {
  std::size_t contacts = 0, close = 0;
  // Under AXON_TEST_SHORT one move (seed 2: 35 contacts and 7 near misses of its own).
  const std::vector<unsigned> seeds = test_support::short_run() ? std::vector<unsigned>{2} : std::vector<unsigned>{1, 2, 3};
  for (const unsigned seed : seeds) {
    RandomPatchMove mv(seed, 4);
    TrajectoryChecker checker(mv.model);
    CheckReport r;
    CheckOptions o;
    o.obstacles = false;
    ASSERT_TRUE(checker.check(mv.traj, o, r));
    const double travel = 0.01;
    const auto brute = mv.brute_force(r.end_s, travel);
    for (std::size_t k = 0; k < brute.size(); ++k) {
      const PairOutcome& p = r.robot_pairs[k];
      // Brute force lies above the true minimum by at most the travel between its instants; the
      // advancing report is a true clearance, and within its precision of the minimum below 1 mm.
      EXPECT_GE(p.min_clearance_mm, brute[k] - 2 * travel - 1e-9) << "seed " << seed << " pair " << k;
      EXPECT_GE(brute[k], std::min(p.min_clearance_mm, 1.0) - 0.05 - 1e-9) << "seed " << seed << " pair " << k;
      if (brute[k] < 0) {
        EXPECT_TRUE(p.collided) << "seed " << seed << " pair " << k;
      }
      if (p.collided) {
        EXPECT_LT(brute[k], 2 * travel) << "seed " << seed << " pair " << k;
      }
      contacts += brute[k] < 0 ? 1 : 0;
      close += brute[k] >= 0 && brute[k] < 1.0 ? 1 : 0;
    }
  }
  // The moves exercise both cases.
  EXPECT_GT(contacts, 20u * seeds.size() / 3);
  EXPECT_GT(close, 10u * seeds.size() / 3);
}

TEST(PlanChecker, AdvancingGivesTheSameReportWithOneOrTwoThreadsAndFewerEvaluations) {
  RandomPatchMove mv(7);
  TrajectoryChecker checker(mv.model);
  CheckReport one, two, by_samples;
  CheckOptions o;
  o.threads = 1;
  ASSERT_TRUE(checker.check(mv.traj, o, one));
  o.threads = 2;
  ASSERT_TRUE(checker.check(mv.traj, o, two));
  ASSERT_GT(mv.model.robot_pairs().size(), 512u);  // enough pairs to be split
  ASSERT_EQ(one.robot_pairs.size(), two.robot_pairs.size());
  for (std::size_t k = 0; k < one.robot_pairs.size(); ++k) {
    EXPECT_EQ(one.robot_pairs[k].collided, two.robot_pairs[k].collided);
    EXPECT_EQ(one.robot_pairs[k].min_clearance_mm, two.robot_pairs[k].min_clearance_mm);
    EXPECT_EQ(one.robot_pairs[k].min_clearance_s, two.robot_pairs[k].min_clearance_s);
  }
  EXPECT_EQ(one.evaluations(), two.evaluations());
  EXPECT_EQ(one.collided_pairs, two.collided_pairs);
  // The same verdict as dense sampling with a tenth of the pair evaluations or fewer.
  ASSERT_TRUE(checker.check(mv.traj, dense(), by_samples));
  EXPECT_EQ(one.collided_pairs, by_samples.collided_pairs);
  EXPECT_LT(one.evaluations() * 10, by_samples.evaluations());
}

TEST(PlanChecker, ClearMoveReportsItsClearance) {
  // Robot 2 moved to (30, 0): closest approach hypot(30, 7.4) - 22.1 = 8.799, clearance 4.799.
  auto model = build({{1, {0, 0}, {}, {}, 2.0}, {2, {30, 0}, {}, {}, 2.0}});
  std::vector<RobotTrajectory> traj{RobotTrajectory::linear({-60, 0}, {60, 0}, 0, 10), RobotTrajectory::hold({90, 0})};
  TrajectoryChecker checker(model);
  CheckReport r;
  ASSERT_TRUE(checker.check(traj, dense(), r));
  EXPECT_TRUE(r.ok());
  EXPECT_FALSE(r.robot_pairs[0].collided);
  EXPECT_TRUE(std::isnan(r.robot_pairs[0].first_collision_s));
  EXPECT_NEAR(r.min_clearance_mm, std::hypot(30.0, 7.4) - 22.1 - 4, 1e-3);
}

TEST(PlanChecker, SweepOverFiducialAndStaticCheck) {
  // A fiducial at radius 15 mm, 30 deg: robot 1's stretched arm passes right over it.
  const Vec2 fid{15 * std::cos(std::numbers::pi / 6), 15 * std::sin(std::numbers::pi / 6)};
  auto model = build({{1, {0, 0}, {}, {}, 2.0}}, {{3, fid, 3.0}});
  TrajectoryChecker checker(model);
  CheckReport r;
  ASSERT_TRUE(checker.check(std::vector{RobotTrajectory::linear({-60, 0}, {-20, 0}, 0, 5)}, {}, r));
  EXPECT_TRUE(r.ok());
  ASSERT_TRUE(checker.check(std::vector{RobotTrajectory::linear({-60, 0}, {60, 0}, 0, 10)}, {}, r));
  EXPECT_FALSE(r.ok());
  ASSERT_EQ(r.obstacle_pairs.size(), 1u);
  EXPECT_TRUE(r.obstacle_pairs[0].collided);
  // Right through it (-5 mm); the samples miss the exact instant by at most one step (0.05 mm).
  EXPECT_NEAR(r.obstacle_pairs[0].min_clearance_mm, -5.0, 0.05);
  // Nothing moves: a single sample, still checked.
  ASSERT_TRUE(checker.check(std::vector{RobotTrajectory::hold({30, 0})}, {}, r));
  EXPECT_EQ(r.samples, 1u);
  EXPECT_FALSE(r.ok());
  // Obstacles can be left out.
  CheckOptions o;
  o.obstacles = false;
  ASSERT_TRUE(checker.check(std::vector{RobotTrajectory::hold({30, 0})}, o, r));
  EXPECT_TRUE(r.ok());
}

TEST(PlanChecker, MatchesBruteForceOnRandomHexMoves) {
  // Seven robots (a centre and its hex ring) move between random poses; the report must equal a
  // plain evaluation of every pair at the same sample times.
  std::vector<RobotSpec> robots{{1, {0, 0}, {}, {}, 2.0}};
  for (int k = 0; k < 6; ++k)
    robots.push_back({2 + k, {22.4 * std::cos(k * std::numbers::pi / 3), 22.4 * std::sin(k * std::numbers::pi / 3)},
                      {}, {}, 2.0});
  const auto model = build(robots);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> a(0, 360), b(0, 180), dur(2, 8);
  for (int round = 0; round < 5; ++round) {
    std::vector<RobotTrajectory> traj;
    for (std::size_t i = 0; i < model.size(); ++i)
      traj.push_back(RobotTrajectory::linear({a(rng), b(rng)}, {a(rng), b(rng)}, 0, dur(rng)));
    TrajectoryChecker checker(model);
    CheckReport r;
    CheckOptions o = dense();
    o.threads = 1;
    o.max_step_mm = 0.2;
    ASSERT_TRUE(checker.check(traj, o, r));
    std::vector<PairOutcome> expect(model.robot_pairs().size());
    std::vector<Pose> poses(model.size());
    std::vector<Segment> segs(model.size());
    for (std::size_t s = 0; s < r.samples; ++s) {
      const double t = s + 1 == r.samples ? r.end_s : r.start_s + static_cast<double>(s) * r.step_s;
      for (std::size_t i = 0; i < model.size(); ++i) poses[i] = {angle_at(traj[i].alpha, t), angle_at(traj[i].beta, t)};
      model.segments(poses, segs);
      for (std::size_t k = 0; k < expect.size(); ++k) {
        const double c = model.clearance(model.robot_pairs()[k], segs);
        if (c < expect[k].min_clearance_mm) expect[k].min_clearance_mm = c, expect[k].min_clearance_s = t;
        if (c < 0 && !expect[k].collided) expect[k].collided = true, expect[k].first_collision_s = t;
      }
    }
    // The checker sees at least what the samples show (and, where it halves an interval to
    // prove it clear, possibly more: never less).
    for (std::size_t k = 0; k < expect.size(); ++k) {
      EXPECT_LE(r.robot_pairs[k].min_clearance_mm, expect[k].min_clearance_mm + 1e-9) << k;
      if (expect[k].collided) {
        EXPECT_TRUE(r.robot_pairs[k].collided) << k;
        EXPECT_LE(r.robot_pairs[k].first_collision_s, expect[k].first_collision_s + 1e-12) << k;
      }
    }
  }
}

// With samples far apart (max_step_mm chosen so that every sample of the sweep is clear), the
// contact between two samples is still found: the interval cannot be proven clear, so it is halved
// until the contact shows. A sampling checker steps over it.
TEST(PlanChecker, AContactBetweenSamplesIsFoundNotSteppedOver) {
  Sweep s;
  TrajectoryChecker checker(s.model);
  CheckReport r;
  CheckOptions o = dense();
  o.threads = 1;
  bool found_gap = false;
  for (double step = 3.0; step < 12.0 && !found_gap; step += 0.25) {
    o.max_step_mm = step;
    ASSERT_TRUE(checker.check(s.traj, o, r));
    // The samples alone, evaluated here.
    double sampled = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < r.samples; ++k) {
      const double t = k + 1 == r.samples ? r.end_s : r.start_s + static_cast<double>(k) * r.step_s;
      sampled = std::min(sampled, static_clearance(s.model, {{angle_at(s.traj[0].alpha, t), 0}, {90, 0}}));
    }
    if (sampled < 0) continue;  // this step happens to sample the contact: try another
    found_gap = true;
    EXPECT_FALSE(r.ok()) << "step " << step;
    EXPECT_TRUE(r.robot_pairs[0].collided);
    EXPECT_LT(r.robot_pairs[0].min_clearance_mm, 0.0);
    EXPECT_NEAR(r.robot_pairs[0].first_collision_s, 6.43, 0.6);
    EXPECT_GT(r.halvings, 0u);
  }
  EXPECT_TRUE(found_gap) << "no step between 3 and 12 mm samples the sweep clear";
}

TEST(PlanChecker, RejectsBadTrajectories) {
  Sweep s;
  TrajectoryChecker checker(s.model);
  CheckReport r;
  EXPECT_EQ(checker.check(std::span(s.traj).first(1), {}, r).error(), PlanErrc::bad_trajectory);
  auto bad = s.traj;
  bad[1].beta = {{2, 0}, {1, 5}};
  auto e = checker.check(bad, {}, r);
  ASSERT_FALSE(e);
  EXPECT_EQ(e.error(), PlanErrc::bad_trajectory);
  EXPECT_NE(e.error().detail.find("robot 2"), std::string::npos);
  bad[1].beta.clear();
  EXPECT_EQ(checker.check(bad, {}, r).error(), PlanErrc::bad_trajectory);
  // Settings under which the advancing method could not move on from a touching pair.
  for (auto set : {+[](CheckOptions& o) { o.min_step_s = 0; }, +[](CheckOptions& o) { o.precision_mm = 0; },
                   +[](CheckOptions& o) { o.precision_mm = std::numeric_limits<double>::quiet_NaN(); },
                   +[](CheckOptions& o) { o.precise_below_mm = -1; }}) {
    CheckOptions o;
    set(o);
    EXPECT_EQ(checker.check(s.traj, o, r).error(), PlanErrc::bad_trajectory);
  }
}

TEST(PlanTrajectory, InterpolationAndCursor) {
  const std::vector<TimedAngle> pts{{1, 10}, {3, 30}, {4, 0}};
  EXPECT_DOUBLE_EQ(angle_at(pts, 0), 10);
  EXPECT_DOUBLE_EQ(angle_at(pts, 2), 20);
  EXPECT_DOUBLE_EQ(angle_at(pts, 3.5), 15);
  EXPECT_DOUBLE_EQ(angle_at(pts, 9), 0);
  EXPECT_DOUBLE_EQ(max_speed(pts), 30);
  AngleCursor c(pts);
  for (double t = 0; t <= 5; t += 0.25) EXPECT_DOUBLE_EQ(c.at(t), angle_at(pts, t)) << t;
  EXPECT_DOUBLE_EQ(c.at(2), 20);  // going back restarts
  // Speed and the next point from where the cursor stands.
  c.at(0.5);
  EXPECT_EQ(c.speed(), 0.0);
  EXPECT_EQ(c.next_point(), 1.0);
  c.at(1);
  EXPECT_DOUBLE_EQ(c.speed(), 10);
  EXPECT_EQ(c.next_point(), 3.0);
  c.at(3);
  EXPECT_DOUBLE_EQ(c.speed(), 30);
  EXPECT_EQ(c.next_point(), 4.0);
  c.at(4);
  EXPECT_EQ(c.speed(), 0.0);
  EXPECT_EQ(c.next_point(), std::numeric_limits<double>::infinity());
}

TEST(PlanTrajectory, EndTimeAndWindow) {
  const RobotTrajectory t{{{0, 10}, {3, 30}, {4, 0}}, {{0, 100}, {6, 160}}};
  EXPECT_EQ(end_time(t), 6.0);
  EXPECT_EQ(end_time(RobotTrajectory::hold({1, 2})), 0.0);
  // 2..5 s: the ends interpolated, the points in between kept, times from 0.
  const RobotTrajectory w = window(t, 2, 5);
  auto pairs = [](const std::vector<TimedAngle>& arm) {
    std::vector<std::pair<double, double>> out;
    for (const auto& p : arm) out.emplace_back(p.t_s, p.deg);
    return out;
  };
  using P = std::vector<std::pair<double, double>>;
  EXPECT_DOUBLE_EQ(w.alpha.front().deg, angle_at(t.alpha, 2));
  EXPECT_EQ(pairs({w.alpha.begin() + 1, w.alpha.end()}), (P{{1, 30}, {2, 0}, {3, 0}}));
  EXPECT_EQ(pairs(w.beta), (P{{0, 120}, {3, 150}}));
  EXPECT_TRUE(validate(w));
  // A window on a point keeps no duplicate time.
  const RobotTrajectory on = window(t, 3, 4);
  EXPECT_EQ(pairs(on.alpha), (P{{0, 30}, {1, 0}}));
}

}  // namespace
}  // namespace axon::fps::plan

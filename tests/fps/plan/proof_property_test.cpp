// Issue 16, point 2: a plan the planner calls verified is contact-free at every instant, not only
// at the checker's samples. Sixty small random problems (150 and more in a developer's run: change the count) (a triangle of robots around a
// fiducial, random clear starts and targets) are planned, and every verified plan is checked
// again by a brute-force evaluation written here, independently of the planner's checker: its own
// segment distance, its own (much finer) time grid. Every clearance it sees must be >= 0, since
// the checker claims a proof, not a sampling result.
#include "axon/fps/plan/planner.hpp"
#include "model_util.hpp"
#include "support/short_run.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace axon::fps::plan::proof_test {
namespace {

double bf_cross(Vec2 a, Vec2 b) { return a.x * b.y - a.y * b.x; }
double bf_dot(Vec2 a, Vec2 b) { return a.x * b.x + a.y * b.y; }

double point_to_segment(Vec2 p, const Segment& s) {
  const Vec2 d = s.b - s.a;
  const double len2 = bf_dot(d, d);
  const double u = len2 > 0 ? std::clamp(bf_dot(p - s.a, d) / len2, 0.0, 1.0) : 0.0;
  const Vec2 q = s.a + u * d;
  return std::hypot(p.x - q.x, p.y - q.y);
}

// Two segments cross when each one's ends lie on both sides of the other's line.
bool cross_each_other(const Segment& s, const Segment& t) {
  const double d1 = bf_cross(s.b - s.a, t.a - s.a), d2 = bf_cross(s.b - s.a, t.b - s.a);
  const double d3 = bf_cross(t.b - t.a, s.a - t.a), d4 = bf_cross(t.b - t.a, s.b - t.a);
  return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

double brute_distance(const Segment& s, const Segment& t) {
  if (cross_each_other(s, t)) return 0;
  return std::min({point_to_segment(s.a, t), point_to_segment(s.b, t), point_to_segment(t.a, s), point_to_segment(t.b, s)});
}

// The smallest clearance of any pair at any instant of a fine grid (every arm point moves at most
// 0.02 mm between two instants), by brute force over all robot pairs and robot-obstacle pairs.
double brute_min_clearance(const CollisionModel& m, const std::vector<RobotTrajectory>& traj) {
  double end = 0, speed = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    end = std::max({end, traj[i].alpha.back().t_s, traj[i].beta.back().t_s});
    speed = std::max(speed, (max_speed(traj[i].alpha) + max_speed(traj[i].beta)) * std::numbers::pi / 180 *
                                (m.robot(i).reach_mm() + m.robot(i).collision_length_mm()));
  }
  const double dt = speed > 0 ? 0.02 / speed : end + 1;
  double worst = std::numeric_limits<double>::infinity();
  std::vector<Segment> seg(m.size());
  for (double t = 0;; t = std::min(t + dt, end)) {
    for (std::size_t i = 0; i < m.size(); ++i)
      seg[i] = m.robot(i).collision_segment({angle_at(traj[i].alpha, t), angle_at(traj[i].beta, t)});
    for (std::size_t i = 0; i < m.size(); ++i) {
      for (std::size_t j = i + 1; j < m.size(); ++j)
        worst = std::min(worst, brute_distance(seg[i], seg[j]) - m.robot(i).buffer_mm() - m.robot(j).buffer_mm());
      for (const auto& ob : m.obstacles())
        worst = std::min(worst, brute_distance(seg[i], ob.shape) - m.robot(i).buffer_mm() - ob.buffer_mm);
    }
    if (t >= end) break;
  }
  return worst;
}

TEST(PlanProof, VerifiedPlansOfRandomSmallProblemsAreContactFreeUnderAnIndependentBruteForceCheck) {
  const double pitch = 22.4;
  const auto m = test::build({RobotSpec{1, {0, 0}, {}, {}, 2.0}, RobotSpec{2, {pitch, 0}, {}, {}, 2.0},
                              RobotSpec{3, {pitch / 2, pitch * std::sqrt(3.0) / 2}, {}, {}, 2.0}},
                             {{9, {pitch / 2, pitch * std::sqrt(3.0) / 6}, 3.0}});
  std::mt19937 rng(16);
  std::uniform_real_distribution<double> alpha(0, 360), beta(0, 180);
  auto clear_poses = [&] {
    for (;;) {
      std::vector<Pose> p;
      for (std::size_t i = 0; i < m.size(); ++i) p.push_back({alpha(rng), beta(rng)});
      std::vector<Segment> s(m.size());
      m.segments(p, s);
      std::vector<Contact> c;
      if (m.find_contacts(s, c) >= 0 && c.empty()) return p;
    }
  };
  int verified = 0, moved = 0, errors = 0;
  double plan_s = 0;
  double closest = std::numeric_limits<double>::infinity();
  const int problems = test_support::cases(60);
  for (int k = 0; k < problems; ++k) {
    PlanRequest req;
    req.current = clear_poses();
    req.target = clear_poses();
    PlannerOptions o;
    o.seed = static_cast<std::uint64_t>(k) + 1;
    o.parallel = false;
    const auto t0 = std::chrono::steady_clock::now();
    auto r = plan_moves(m, req, o);
    plan_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!r) {  // the planner gave up on the problem (reported, nothing to check)
      ++errors;
      continue;
    }
    if (!r.value().verified) continue;
    ++verified;
    moved += r.value().ok() ? 1 : 0;
    const double c = brute_min_clearance(m, r.value().trajectories);
    closest = std::min(closest, c);
    EXPECT_GE(c, -1e-9) << "problem " << k << ": the verified plan touches (" << c << " mm)";
  }
  // Most problems are solved and verified; a contact-free proof on none would prove nothing.
  EXPECT_GE(verified, problems - problems / 12) << verified << " of " << problems << " verified";
  EXPECT_GE(moved, problems / 2) << moved << " of " << problems << " fully solved";
  RecordProperty("closest_mm", std::to_string(closest));
  std::printf("planning %.2f s, closest %.4f mm, verified %d, solved %d, planner errors %d\n", plan_s, closest, verified,
              moved, errors);
}

}  // namespace
}  // namespace axon::fps::plan::proof_test

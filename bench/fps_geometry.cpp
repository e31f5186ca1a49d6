// Collision-geometry throughput for a 500-robot focal plane on a 22.4 mm hex grid.
//
// 1. Static check of a random configuration: exact segment distances over all neighbour pairs
//    (pairs per second), against a naive distance that samples points along both segments
//    (0.5 mm apart) and takes the closest pair of points, measured in the same run.
//    ratio = exact pairs/s / naive pairs/s (how much the exact primitive saves).
// 2. The trajectory checker on a random move of every robot (12 deg/s), with one thread and with
//    two: dense sampling (pair evaluations per second) and the advancing method (the default);
//    check_ratio = dense time / advancing time with two threads.
#include "axon/fps/plan/checker.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

using namespace axon::fps::plan;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The `count` grid points closest to the origin, pitch 22.4 mm, rows 19.399 mm apart.
std::vector<RobotSpec> hex_grid(std::size_t count) {
  const double pitch = 22.4, row = pitch * std::sqrt(3.0) / 2;
  std::vector<Vec2> pts;
  for (int j = -20; j <= 20; ++j)
    for (int i = -20; i <= 20; ++i) pts.push_back({(i + (j % 2 != 0 ? 0.5 : 0.0)) * pitch, j * row});
  std::sort(pts.begin(), pts.end(), [](Vec2 a, Vec2 b) { return norm2(a) < norm2(b); });
  std::vector<RobotSpec> out;
  for (std::size_t k = 0; k < count; ++k) out.push_back({static_cast<std::int32_t>(k + 1), pts[k], {}, {}, 2.0});
  return out;
}

double naive_distance(const Segment& s, const Segment& t, int n) {
  double best = 1e300;
  for (int i = 0; i <= n; ++i) {
    const Vec2 p = s.a + (static_cast<double>(i) / n) * (s.b - s.a);
    for (int j = 0; j <= n; ++j) {
      const Vec2 q = t.a + (static_cast<double>(j) / n) * (t.b - t.a);
      best = std::min(best, norm2(p - q));
    }
  }
  return std::sqrt(best);
}

}  // namespace

int main() {
  const auto robots = hex_grid(500);
  const auto model = CollisionModel::build(robots).value();
  std::size_t max_nb = 0, min_nb = 1000;
  for (std::size_t i = 0; i < model.size(); ++i) {
    max_nb = std::max(max_nb, model.neighbours(i).size());
    min_nb = std::min(min_nb, model.neighbours(i).size());
  }
  fmt::print("focal plane: {} robots, {} neighbour pairs ({}..{} neighbours each)\n", model.size(),
             model.robot_pairs().size(), min_nb, max_nb);

  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> alpha(0, 360), beta(0, 180);
  std::vector<Pose> poses(model.size());
  for (auto& p : poses) p = {alpha(rng), beta(rng)};
  std::vector<Segment> segs(model.size());
  model.segments(poses, segs);
  const auto pairs = model.robot_pairs();

  // Exact: segment distances of every pair, repeated for at least 0.5 s.
  double sink = 0;
  std::size_t exact_pairs = 0;
  auto t0 = Clock::now();
  do {
    for (const auto& p : pairs) sink += model.clearance(p, segs);
    exact_pairs += pairs.size();
  } while (seconds_since(t0) < 0.5);
  const double exact_rate = static_cast<double>(exact_pairs) / seconds_since(t0);

  // Naive: 0.5 mm point spacing along the 14.7 mm segments (30 intervals).
  const int n = 30;
  std::size_t naive_pairs = 0;
  double worst_error = 0;
  t0 = Clock::now();
  do {
    for (const auto& p : pairs) {
      const double d = naive_distance(segs[p.a], segs[p.b], n);
      sink += d;
      if (naive_pairs < pairs.size()) worst_error = std::max(worst_error, d - segment_distance(segs[p.a], segs[p.b]));
      ++naive_pairs;
    }
  } while (seconds_since(t0) < 0.5);
  const double naive_rate = static_cast<double>(naive_pairs) / seconds_since(t0);
  std::vector<Contact> contacts;
  const double min_clear = model.find_contacts(segs, contacts);
  fmt::print("static: exact {:.3g} pairs/s, naive point-sampled {:.3g} pairs/s (worst overestimate {:.3f} mm), "
             "{} contacts in the random configuration, min clearance {:.2f} mm\n",
             exact_rate, naive_rate, worst_error, contacts.size(), min_clear);

  // A random move of every robot at 12 deg/s per arm.
  std::vector<RobotTrajectory> traj;
  double longest = 0;
  for (std::size_t i = 0; i < model.size(); ++i) {
    const Pose to{alpha(rng), beta(rng)};
    const double t_a = std::abs(to.alpha_deg - poses[i].alpha_deg) / 12.0;
    const double t_b = std::abs(to.beta_deg - poses[i].beta_deg) / 12.0;
    RobotTrajectory t;
    t.alpha = {{0, poses[i].alpha_deg}, {std::max(t_a, 0.01), to.alpha_deg}};
    t.beta = {{0, poses[i].beta_deg}, {std::max(t_b, 0.01), to.beta_deg}};
    longest = std::max({longest, t_a, t_b});
    traj.push_back(std::move(t));
  }
  TrajectoryChecker checker(model);
  CheckReport report;
  double rates[2] = {0, 0};
  double check_s[2][2] = {{0, 0}, {0, 0}};  // [dense, advancing][threads - 1]
  for (const CheckMethod method : {CheckMethod::dense, CheckMethod::advancing})
    for (unsigned threads : {1u, 2u}) {
      CheckOptions o;
      o.method = method;
      o.threads = threads;
      t0 = Clock::now();
      if (!checker.check(traj, o, report)) return 1;
      const double s = seconds_since(t0);
      const bool dense = method == CheckMethod::dense;
      check_s[dense ? 0 : 1][threads - 1] = s;
      if (dense) rates[threads - 1] = static_cast<double>(report.evaluations()) / s;
      fmt::print("checker, {} ({} thread{}): {:.1f} s move, {} pair evaluations in {:.3f} s = {:.3g}/s; {} pairs "
                 "collided, min clearance {:.3f} mm\n",
                 dense ? "dense" : "advancing", threads, threads > 1 ? "s" : "", longest, report.evaluations(), s,
                 static_cast<double>(report.evaluations()) / s, report.collided_pairs, report.min_clearance_mm);
    }
  if (sink == 42.4242) std::puts("");  // keep the loops from being optimised away
  fmt::print("BENCH fps_geometry pairs_per_s={:.0f} naive_pairs_per_s={:.0f} ratio={:.2f} checker_evals_per_s_1t={:.0f} "
             "checker_evals_per_s_2t={:.0f} dense_check_s={:.4f} advancing_check_s={:.4f} check_ratio={:.1f} robots={} pairs={}\n",
             exact_rate, naive_rate, exact_rate / naive_rate, rates[0], rates[1], check_s[0][1], check_s[1][1],
             check_s[1][1] > 0 ? check_s[0][1] / check_s[1][1] : 0.0, model.size(), pairs.size());
  std::fflush(stdout);
  return 0;
}

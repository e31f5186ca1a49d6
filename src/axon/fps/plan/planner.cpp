#include "axon/fps/plan/planner.hpp"

#include "axon/fps/plan/phases.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <span>

namespace axon::fps::plan {

std::string_view to_string(RobotPlan::Status s) noexcept {
  switch (s) {
    case RobotPlan::Status::reached: return "reached";
    case RobotPlan::Status::frozen: return "frozen";
    case RobotPlan::Status::parked: return "parked";
    case RobotPlan::Status::held: return "held";
  }
  return "?";
}

std::string Plan::summary(const CollisionModel& model) const {
  std::string out;
  for (std::size_t i = 0; i < robots.size(); ++i) {
    const RobotPlan& r = robots[i];
    if (r.status != RobotPlan::Status::parked && r.status != RobotPlan::Status::held) continue;
    out += fmt::format("robot {}: {}: {}", model.robot(i).id(), to_string(r.status), r.reason);
    if (!r.blockers.empty()) {
      out += " (blocked by";
      for (auto id : r.blockers) out += fmt::format(" {}", id);
      out += ")";
    }
    out += "\n";
  }
  return out;
}

std::vector<TimedAngle> simplify_arm(std::span<const TimedAngle> points, double tolerance_deg) {
  if (points.size() <= 2 || tolerance_deg <= 0) return {points.begin(), points.end()};
  std::vector<bool> keep(points.size(), false);
  keep.front() = keep.back() = true;
  std::vector<std::pair<std::size_t, std::size_t>> todo{{0, points.size() - 1}};
  while (!todo.empty()) {
    const auto [a, b] = todo.back();
    todo.pop_back();
    if (b <= a + 1) continue;
    double worst = -1;
    std::size_t at = a;
    const TimedAngle& pa = points[a];
    const TimedAngle& pb = points[b];
    for (std::size_t k = a + 1; k < b; ++k) {
      const double f = (points[k].t_s - pa.t_s) / (pb.t_s - pa.t_s);
      const double d = std::abs(pa.deg + f * (pb.deg - pa.deg) - points[k].deg);
      if (d > worst) {
        worst = d;
        at = k;
      }
    }
    if (worst > tolerance_deg) {
      keep[at] = true;
      todo.push_back({a, at});
      todo.push_back({at, b});
    }
  }
  std::vector<TimedAngle> out;
  for (std::size_t k = 0; k < points.size(); ++k)
    if (keep[k]) out.push_back(points[k]);
  return out;
}

namespace {

bool same_arm(const std::vector<TimedAngle>& a, const std::vector<TimedAngle>& b) noexcept {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(),
                    [](const TimedAngle& x, const TimedAngle& y) { return x.t_s == y.t_s && x.deg == y.deg; });
}

}  // namespace

Result<std::size_t> verify_with_fallbacks(const CollisionModel& model, std::span<const std::vector<RobotTrajectory>> layers,
                                   const CheckOptions& options, std::vector<RobotTrajectory>& out,
                                   std::vector<std::size_t>& level, CheckReport& report, int max_passes) {
  const std::size_t n = model.size();
  if (layers.empty()) return make_error(PlanErrc::bad_trajectory, "no trajectories to verify");
  for (const auto& layer : layers)
    if (layer.size() != n)
      return make_error(PlanErrc::bad_trajectory,
                        fmt::format("{} trajectories for {} robots", layer.size(), n));
  out = layers.front();
  level.assign(n, 0);
  TrajectoryChecker checker(model);
  std::vector<bool> flagged(n, false);
  std::size_t checks = 0;
  for (int pass = 0; pass < std::max(1, max_passes); ++pass) {
    AXON_TRY(checker.check(out, options, report));
    ++checks;
    if (report.ok()) break;
    std::fill(flagged.begin(), flagged.end(), false);
    const auto rp = model.robot_pairs();
    for (std::size_t k = 0; k < rp.size(); ++k)
      if (report.robot_pairs[k].move_collided(options)) flagged[rp[k].a] = flagged[rp[k].b] = true;
    const auto op = model.obstacle_pairs();
    for (std::size_t k = 0; k < op.size(); ++k)
      if (report.obstacle_pairs[k].move_collided(options)) flagged[op[k].robot] = true;
    bool reverted = false;
    for (std::size_t i = 0; i < n; ++i) {
      if (!flagged[i]) continue;
      std::size_t l = level[i] + 1;
      while (l < layers.size() && same_arm(layers[l][i].alpha, out[i].alpha) && same_arm(layers[l][i].beta, out[i].beta)) ++l;
      if (l >= layers.size()) continue;  // already on the last layer (or one equal to it)
      level[i] = l;
      out[i] = layers[l][i];
      reverted = true;
    }
    if (!reverted) break;
  }
  return checks;
}

// The driver: the phases (phases.hpp) in order; each phase's own comment says what it decides.
Result<Plan> plan_moves(const CollisionModel& model, const PlanRequest& request, const PlannerOptions& o) {
  using Clock = std::chrono::steady_clock;
  const auto t_start = Clock::now();
  auto since_start = [&] { return std::chrono::duration<double>(Clock::now() - t_start).count(); };
  AXON_TRY(phases::check_request(model, request, o));
  const phases::Context ctx = phases::make_context(model, request, o, t_start);
  phases::Work w = phases::prepare(ctx);
  phases::settle_targets(ctx, w);
  w.plan.stats.setup_s = since_start();
  phases::Search search;
  AXON_TRY(phases::search_rounds(ctx, w, search));
  const phases::Finish finish = phases::finish_parked(ctx, w, search);
  phases::join_halves(ctx, w, search, finish);
  phases::Layers layers = phases::smooth_and_simplify(ctx, w);
  AXON_TRY(phases::verify_layers(ctx, w, layers));
  phases::collect_stats(w, layers);
  w.plan.stats.plan_s = since_start();
  return std::move(w.plan);
}

}  // namespace axon::fps::plan

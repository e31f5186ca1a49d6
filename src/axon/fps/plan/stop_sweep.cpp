#include "axon/fps/plan/stop_sweep.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace axon::fps::plan {

namespace {

// The angles from the stop (below `lo` by the overtravel) up to `from`, `grid` apart, both ends
// included; just `from` when the arm does not move.
std::vector<double> angles_down(double from, double lo, double overtravel, double grid, bool moves) {
  if (!moves) return {from};
  const double stop = std::min(from, lo - overtravel);
  std::vector<double> out;
  for (double a = from; a > stop; a -= grid) out.push_back(a);
  out.push_back(stop);
  return out;
}

}  // namespace

StopSweep check_sweep_to_stops(const CollisionModel& model, std::size_t i, std::span<const Pose> poses,
                               const StopSweepOptions& o) {
  const Positioner& r = model.robot(i);
  const auto nb = model.neighbours(i);
  const auto pairs = model.pairs_of(i);
  const auto all_pairs = model.robot_pairs();
  const auto obstacles = model.obstacles();
  const auto opairs = model.obstacle_pairs();
  struct Body {
    std::string name;
    Segment seg;
    double limit;
    double worst = std::numeric_limits<double>::infinity();
  };
  std::vector<Body> bodies;
  for (std::size_t k = 0; k < nb.size(); ++k)
    bodies.push_back({fmt::format("robot {}", model.robot(nb[k]).id()), model.robot(nb[k]).collision_segment(poses[nb[k]]),
                      all_pairs[pairs[k]].limit_mm});
  for (const std::uint32_t k : model.obstacle_pairs_of(i))
    bodies.push_back({obstacles[opairs[k].obstacle].name, obstacles[opairs[k].obstacle].shape, opairs[k].limit_mm});

  const AngleLimits& l = r.limits();
  const auto alphas = angles_down(poses[i].alpha_deg, l.alpha_min_deg, o.overtravel_deg, o.grid_deg, o.alpha);
  const auto betas = angles_down(poses[i].beta_deg, l.beta_min_deg, o.overtravel_deg, o.grid_deg, o.beta);
  auto visit = [&](double a, double b) {
    const Segment s = r.collision_segment({a, b});
    for (Body& body : bodies) body.worst = std::min(body.worst, segment_distance(s, body.seg) - body.limit);
  };
  if (o.simultaneous) {  // down the diagonal, then the arm that is not at its stop yet alone
    for (std::size_t k = 0; k < std::max(alphas.size(), betas.size()); ++k)
      visit(alphas[std::min(k, alphas.size() - 1)], betas[std::min(k, betas.size() - 1)]);
  } else {
    for (double a : alphas)
      for (double b : betas) visit(a, b);
  }
  // Any pose of the region lies within half a grid step (per arm) of a grid pose.
  const double slack = 0.5 * o.grid_deg * kRad * (r.reach_mm() + r.collision_length_mm());
  StopSweep out;
  out.min_clearance_mm = std::numeric_limits<double>::infinity();
  std::sort(bodies.begin(), bodies.end(), [](const Body& x, const Body& y) { return x.worst < y.worst; });
  for (const Body& body : bodies) {
    const double bound = body.worst - slack;
    out.min_clearance_mm = std::min(out.min_clearance_mm, bound);
    if (bound < 0) out.in_the_way.push_back(fmt::format("{} ({:.3f} mm)", body.name, bound));
  }
  out.clear = out.in_the_way.empty();
  return out;
}

}  // namespace axon::fps::plan

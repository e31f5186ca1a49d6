#include "axon/fps/plan/stop_sweep.hpp"
#include "axon/fps/plan/arm_name.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace axon::fps::plan {

namespace {

// What robot i can touch while it moves alone: its neighbours where they stand and the fixed
// obstacles near it, each with the clearance limit of the pair.
struct Body {
  std::string name;
  Segment seg;
  double limit;
  double worst = std::numeric_limits<double>::infinity();
};

std::vector<Body> standing_bodies(const CollisionModel& model, std::size_t i, std::span<const Pose> poses) {
  const auto nb = model.neighbours(i);
  const auto pairs = model.pairs_of(i);
  const auto all_pairs = model.robot_pairs();
  const auto obstacles = model.obstacles();
  const auto opairs = model.obstacle_pairs();
  std::vector<Body> bodies;
  for (std::size_t k = 0; k < nb.size(); ++k)
    bodies.push_back({fmt::format("robot {}", model.robot(nb[k]).id()), model.robot(nb[k]).collision_segment(poses[nb[k]]),
                      all_pairs[pairs[k]].limit_mm});
  for (const std::uint32_t k : model.obstacle_pairs_of(i))
    bodies.push_back({obstacles[opairs[k].obstacle].name, obstacles[opairs[k].obstacle].shape, opairs[k].limit_mm});
  return bodies;
}

// How far any pose lies from the nearest grid pose, in mm of robot r's collision segment.
double grid_slack(const Positioner& r, double grid_deg) {
  return 0.5 * grid_deg * kRad * (r.reach_mm() + r.collision_length_mm());
}

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

// Any pose of a region lies within `slack` (mm of the moving segment) of a grid pose: each body is
// clear when its worst grid clearance exceeds that.
StopSweep sweep_verdict(std::vector<Body>& bodies, double slack) {
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

}  // namespace

StopSweep check_sweep_to_stops(const CollisionModel& model, std::size_t i, std::span<const Pose> poses,
                               const StopSweepOptions& o) {
  const Positioner& r = model.robot(i);
  auto bodies = standing_bodies(model, i, poses);

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
  return sweep_verdict(bodies, grid_slack(r, o.grid_deg));
}

StopSweep check_arm_sweep(const CollisionModel& model, std::size_t i, std::span<const Pose> poses, char arm,
                          double to_deg, double grid_deg, double approach_deg) {
  const Positioner& r = model.robot(i);
  auto bodies = standing_bodies(model, i, poses);
  const Pose from = poses[i];
  const double start = arm == 'a' ? from.alpha_deg : from.beta_deg;
  const double other = arm == 'a' ? from.beta_deg : from.alpha_deg;
  // Grid points from lo to hi, both ends included.
  auto span = [grid_deg](double lo, double hi) {
    const int n = std::max(1, static_cast<int>(std::ceil((hi - lo) / grid_deg)));
    std::vector<double> v;
    for (int k = 0; k <= n; ++k) v.push_back(lo + (hi - lo) * k / n);
    return v;
  };
  const auto turning = span(std::min(start, to_deg) - approach_deg, std::max(start, to_deg) + approach_deg);
  const auto standing = span(other - approach_deg, other + approach_deg);
  for (const double d : turning) {
    for (const double e : standing) {
      const Segment s = r.collision_segment(arm == 'a' ? Pose{d, e} : Pose{e, d});
      for (Body& body : bodies) body.worst = std::min(body.worst, segment_distance(s, body.seg) - body.limit);
    }
  }
  auto out = sweep_verdict(bodies, grid_slack(r, grid_deg));
  const AngleLimits& l = r.limits();
  const bool inside = arm == 'a' ? to_deg >= l.alpha_min_deg && to_deg <= l.alpha_max_deg
                                 : to_deg >= l.beta_min_deg && to_deg <= l.beta_max_deg;
  if (!inside) {
    out.in_the_way.insert(out.in_the_way.begin(), fmt::format("angle limit ({} {:.1f} deg)", arm_name(arm), to_deg));
    out.clear = false;
  }
  return out;
}

// ---- Backing off ---------------------------------------------------------------------------------

namespace {

struct Candidate {
  bool certified = false;
  double end_clearance = 0;  // the smallest over every body at the end pose
};

// Robot r turning one arm from `from` by `step` degrees, checked against `bodies` (their start
// clearances in `start`) on the grid: near bodies never closer than before, the others clear.
Candidate walk(const Positioner& r, std::span<const Body> bodies, std::span<const double> start, Pose from, char arm,
               double step, double grid, double slack) {
  const int n = static_cast<int>(std::ceil(std::abs(step) / grid));
  std::vector<double> last(start.begin(), start.end());
  Candidate c{true, std::numeric_limits<double>::infinity()};
  for (int k = 1; k <= n; ++k) {
    const double d = step * k / n;
    const Pose p = arm == 'a' ? Pose{from.alpha_deg + d, from.beta_deg} : Pose{from.alpha_deg, from.beta_deg + d};
    const Segment s = r.collision_segment(p);
    double smallest = std::numeric_limits<double>::infinity();
    for (std::size_t b = 0; b < bodies.size(); ++b) {
      const double now = segment_distance(s, bodies[b].seg) - bodies[b].limit;
      const bool near = start[b] < slack;
      if (near ? now < last[b] - 1e-9 : now < slack) return {};
      last[b] = now;
      smallest = std::min(smallest, now);
    }
    c.end_clearance = smallest;
  }
  return c;
}

bool within(const AngleLimits& l, const Pose& p) {
  return p.alpha_deg >= l.alpha_min_deg && p.alpha_deg <= l.alpha_max_deg && p.beta_deg >= l.beta_min_deg &&
         p.beta_deg <= l.beta_max_deg;
}

}  // namespace

BackOff plan_back_off(const CollisionModel& model, std::size_t i, std::span<const Pose> poses, const BackOffOptions& o) {
  const Positioner& r = model.robot(i);
  auto bodies = standing_bodies(model, i, poses);
  const double slack = grid_slack(r, o.grid_deg);
  const Segment here = r.collision_segment(poses[i]);
  for (Body& b : bodies) b.worst = segment_distance(here, b.seg) - b.limit;
  std::sort(bodies.begin(), bodies.end(), [](const Body& x, const Body& y) { return x.worst < y.worst; });
  std::vector<double> start;
  BackOff out;
  out.from = out.to = poses[i];
  out.clearance_before_mm = std::numeric_limits<double>::infinity();
  for (const Body& b : bodies) {
    start.push_back(b.worst);
    out.clearance_before_mm = std::min(out.clearance_before_mm, b.worst);
    if (b.worst < slack) out.in_contact.push_back(fmt::format("{} ({:.3f} mm)", b.name, b.worst));
  }
  for (const double size : o.steps_deg) {
    for (const char arm : {'b', 'a'}) {
      for (const double step : {size, -size}) {
        const Pose to = arm == 'a' ? Pose{poses[i].alpha_deg + step, poses[i].beta_deg}
                                   : Pose{poses[i].alpha_deg, poses[i].beta_deg + step};
        if (!within(r.limits(), to)) continue;
        const auto c = walk(r, bodies, start, poses[i], arm, step, o.grid_deg, slack);
        if (!c.certified) continue;
        const bool clear = c.end_clearance >= 0;
        const bool better = !out.found || (clear && !out.clear) ||
                            (clear == out.clear && c.end_clearance > out.clearance_after_mm);
        if (!better) continue;
        out.found = true;
        out.clear = clear;
        out.to = to;
        out.arm = arm;
        out.step_deg = step;
        out.clearance_after_mm = c.end_clearance;
      }
    }
    if (out.clear) break;  // the smallest step that ends clear
  }
  return out;
}

}  // namespace axon::fps::plan

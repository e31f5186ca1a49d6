#include "axon/fps/plan/untangle.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <functional>
#include <numbers>
#include <queue>
#include <tuple>
#include <string>
#include <unordered_map>

namespace axon::fps::plan {

namespace {

constexpr double kFineMargin = 0.01;  // mm: margin of the finer grids (the certificate still holds)

struct Fixed {
  Segment s;
  double limit;
};

class RobotGrid {
 public:
  RobotGrid(const Positioner& r, std::vector<Fixed> fixed, Pose start, double sa, double sb, double margin)
      : r_(r), fixed_(std::move(fixed)), start_(start), sa_(sa), sb_(sb), margin_(margin) {}

  // Path of poses from the start to a fold at beta `fold`, empty when none within `max_cells`.
  // Breadth-first (the quickest way out at this resolution); `greedy`: the cells nearest the fold
  // first, which finds *a* way out visiting far fewer cells (reachability only).
  std::vector<Pose> search(double fold, std::size_t max_cells, bool greedy = false) {
    const AngleLimits& l = r_.limits();
    // The outermost cell on each side may be a partial step that lands exactly on the limit
    // (pose() clamps): robots caught against a stop often get out only along it.
    const int a_lo = -static_cast<int>(std::ceil((start_.alpha_deg - l.alpha_min_deg) / sa_ - 1e-9));
    const int a_hi = static_cast<int>(std::ceil((l.alpha_max_deg - start_.alpha_deg) / sa_ - 1e-9));
    const int b_lo = -static_cast<int>(std::ceil((start_.beta_deg - l.beta_min_deg) / sb_ - 1e-9));
    const int b_hi = static_cast<int>(std::ceil((l.beta_max_deg - start_.beta_deg) / sb_ - 1e-9));
    auto key = [](int a, int b) { return (static_cast<std::int64_t>(a) << 32) ^ static_cast<std::uint32_t>(b); };
    std::unordered_map<std::int64_t, std::int64_t> parent;  // cell -> previous cell
    std::deque<std::pair<int, int>> q;
    std::priority_queue<std::tuple<double, int, int>, std::vector<std::tuple<double, int, int>>, std::greater<>> near;
    auto push = [&](int a, int b) {
      if (greedy) near.push({std::abs(pose(a, b).beta_deg - fold), a, b});
      else q.push_back({a, b});
    };
    auto pop = [&] {
      std::pair<int, int> c;
      if (greedy) {
        c = {std::get<1>(near.top()), std::get<2>(near.top())};
        near.pop();
      } else {
        c = q.front();
        q.pop_front();
      }
      return c;
    };
    auto empty = [&] { return greedy ? near.empty() : q.empty(); };
    parent.reserve(4096);
    parent[key(0, 0)] = key(0, 0);
    push(0, 0);
    const double c_start = clearance(start_);
    auto cell_clear = [&](int a, int b) {
      auto it = clr_.find(key(a, b));
      if (it != clr_.end()) return it->second;
      const double c = clearance(pose(a, b));
      clr_[key(a, b)] = c;
      return c;
    };
    clr_[key(0, 0)] = c_start;
    exhausted_ = false;
    while (!empty() && parent.size() < max_cells) {
      const auto [a, b] = pop();
      const Pose p = pose(a, b);
      const double cp = cell_clear(a, b);
      // Within one step of the fold: finish there if that last step is clear.
      if (std::abs(p.beta_deg - fold) <= sb_ + 1e-9) {
        const Pose f{p.alpha_deg, fold};
        const double cf = clearance(f);
        if (p == f || (cf >= std::min(margin_, cp) && edge_ok(p, f, cp, cf))) {
          std::vector<Pose> path{f};
          if (!(p == f)) path.push_back(p);
          for (std::int64_t k = key(a, b); k != key(0, 0);) {
            k = parent[k];
            const int ka = static_cast<int>(k >> 32), kb = static_cast<int>(static_cast<std::int32_t>(k & 0xffffffff));
            path.push_back(pose(ka, kb));
          }
          std::reverse(path.begin(), path.end());
          return path;
        }
      }
      for (int da = -1; da <= 1; ++da)
        for (int db = -1; db <= 1; ++db) {
          if (da == 0 && db == 0) continue;
          const int a2 = a + da, b2 = b + db;
          if (a2 < a_lo || a2 > a_hi || b2 < b_lo || b2 > b_hi) continue;
          if (parent.count(key(a2, b2))) continue;
          const double c2 = cell_clear(a2, b2);
          if (c2 < std::min(margin_, cp) || !edge_ok(p, pose(a2, b2), cp, c2)) continue;
          parent[key(a2, b2)] = key(a, b);
          push(a2, b2);
        }
    }
    exhausted_ = empty();
    return {};
  }


  // Whether the last search() ran out of cells to visit (a closed region at this resolution), as
  // opposed to reaching its cell limit or a fold.
  [[nodiscard]] bool exhausted() const noexcept { return exhausted_; }

  // Moves from the start straight towards `goal` (each angle at most one step per step), step by
  // certified step, as far as it is clear; the poses passed (just the start when it cannot move).
  std::vector<Pose> walk_to(Pose goal) const {
    std::vector<Pose> path{start_};
    double c = clearance(start_);
    auto toward = [](double from, double to, double step) {
      const double next = from + std::clamp(to - from, -step, step);
      return std::abs(to - next) < 1e-9 ? to : next;
    };
    while (!(path.back() == goal)) {
      const Pose p = path.back();
      const Pose q{toward(p.alpha_deg, goal.alpha_deg, sa_), toward(p.beta_deg, goal.beta_deg, sb_)};
      const double cq = clearance(q);
      if (cq < std::min(margin_, c) || !edge_ok(p, q, c, cq)) break;
      path.push_back(q);
      c = cq;
    }
    return path;
  }
 private:
  [[nodiscard]] Pose pose(int a, int b) const noexcept {
    const AngleLimits& l = r_.limits();
    return {std::clamp(start_.alpha_deg + a * sa_, l.alpha_min_deg, l.alpha_max_deg),
            std::clamp(start_.beta_deg + b * sb_, l.beta_min_deg, l.beta_max_deg)};
  }
  [[nodiscard]] double clearance(Pose p) const noexcept {
    const Segment s = r_.collision_segment(p);
    double c = std::numeric_limits<double>::infinity();
    for (const Fixed& f : fixed_) c = std::min(c, segment_distance(s, f.s) - f.limit);
    return c;
  }
  // Certified step from p0 to p1 (clearances c0, c1), halved where the bound is not enough.
  [[nodiscard]] bool edge_ok(Pose p0, Pose p1, double c0, double c1, int depth = 0) const noexcept {
    const double s = (std::abs(p1.alpha_deg - p0.alpha_deg) * r_.reach_mm() +
                      std::abs(p1.beta_deg - p0.beta_deg) * r_.collision_length_mm()) * kRad;
    if (c0 + c1 - s >= 2 * kCertifyTinyMm) return true;
    if (c0 < 0 || c1 < 0) return false;
    if (s <= kCertifyResolutionMm) return true;  // a dip of at most kCertifyResolutionMm / 2 between two clear ends
    if (depth >= 8) return false;
    const Pose m{0.5 * (p0.alpha_deg + p1.alpha_deg), 0.5 * (p0.beta_deg + p1.beta_deg)};
    const double cm = clearance(m);
    return edge_ok(p0, m, c0, cm, depth + 1) && edge_ok(m, p1, cm, c1, depth + 1);
  }

  const Positioner& r_;
  std::vector<Fixed> fixed_;
  Pose start_;
  double sa_, sb_, margin_;
  std::unordered_map<std::int64_t, double> clr_;
  bool exhausted_ = false;
};

// Appends robot i's fixed obstacles, each with its pair's limit.
void add_obstacles(const CollisionModel& model, std::size_t i, std::vector<Fixed>& fixed) {
  for (const std::uint32_t k : model.obstacle_pairs_of(i)) {
    const ObstaclePair& p = model.obstacle_pairs()[k];
    fixed.push_back({model.obstacles()[p.obstacle].shape, p.limit_mm});
  }
}

// A way to a fold and the time of each of its steps.
struct GridPath {
  std::vector<Pose> poses;  // empty: none found
  double dt = 0;
};

// The grids searched, coarse to fine: (fraction of the engine's step, margin kept).
std::array<std::pair<double, double>, 3> grid_levels(const StepperOptions& o) {
  const double fine_margin = std::min(o.margin_mm, kFineMargin);
  return {{{1.0, o.margin_mm}, {0.5, fine_margin}, {0.25, fine_margin}}};
}

// The search on the engine's grid first; where that finds no way out, on grids of half and a
// quarter of the step (each step then takes as much less time, the speed stays the same) that
// keep a smaller margin. The robots left after the engine are mostly caught in narrow passages
// between a fixed obstacle and an alpha stop, which the coarse grid with the full margin cannot
// thread (they are not closed pockets: with only the obstacles present, every start pose of the
// bench problems reaches a fold on a 0.25 deg grid).
GridPath find_fold(const Positioner& r, const std::vector<Fixed>& fixed, Pose start, double fold, const StepperOptions& o,
                   std::size_t max_cells) {
  for (const auto& [f, margin] : grid_levels(o)) {
    RobotGrid g(r, fixed, start, o.alpha_step_deg * f, o.beta_step_deg * f, margin);
    std::vector<Pose> p = g.search(fold, max_cells);
    if (!p.empty()) return {std::move(p), o.dt_s * f};
  }
  return {};
}

// Appends a path of poses, one per step of dt from t0, keeping only the points where an arm's
// speed changes.
void append_path(RobotTrajectory& t, const std::vector<Pose>& path, double t0, double dt) {
  for (int arm_index = 0; arm_index < 2; ++arm_index) {
    std::vector<TimedAngle>& arm = arm_index == 0 ? t.alpha : t.beta;
    auto get = [arm_index](Pose p) { return arm_index == 0 ? p.alpha_deg : p.beta_deg; };
    if (arm.back().t_s < t0) arm.push_back({t0, arm.back().deg});
    for (std::size_t k = 1; k < path.size(); ++k) {
      const bool last = k + 1 == path.size();
      if (!last) {
        const double d0 = get(path[k]) - get(path[k - 1]), d1 = get(path[k + 1]) - get(path[k]);
        if (std::abs(d0 - d1) < 1e-9) continue;  // same speed on both sides: not a corner
      }
      arm.push_back({t0 + static_cast<double>(k) * dt, get(path[k])});
    }
  }
}

}  // namespace

std::size_t untangle_to_fold(const CollisionModel& model, std::span<const StepperRobot> robots, StepperResult& result,
                             const StepperOptions& o, std::size_t max_cells) {
  const std::size_t n = model.size();
  std::vector<std::uint32_t> stuck;
  for (std::size_t i = 0; i < n; ++i)
    if (!result.reached[i] && !robots[i].frozen && !robots[i].script) stuck.push_back(static_cast<std::uint32_t>(i));
  if (stuck.empty()) return 0;
  double t = result.duration_s;
  for (const auto& p : result.paths) t = std::max({t, p.alpha.back().t_s, p.beta.back().t_s});
  std::vector<Pose> poses = result.end;
  std::vector<Segment> segs(n);
  model.segments(poses, segs);
  const auto all_pairs = model.robot_pairs();
  std::size_t done = 0;
  std::vector<bool> moving(n, false);
  for (bool progress = true; progress && !stuck.empty();) {
    progress = false;
    std::fill(moving.begin(), moving.end(), false);
    double wave = 0;
    std::vector<std::uint32_t> left;
    for (const std::uint32_t i : stuck) {
      const auto nb = model.neighbours(i);
      if (std::any_of(nb.begin(), nb.end(), [&](std::uint32_t j) { return moving[j]; })) {
        left.push_back(i);
        continue;
      }
      std::vector<Fixed> fixed;
      const auto pairs = model.pairs_of(i);
      if (std::any_of(nb.begin(), nb.end(), [&](std::uint32_t j) { return moving[j]; })) {
        left.push_back(i);
        continue;
      }
      for (std::size_t k = 0; k < nb.size(); ++k) fixed.push_back({segs[nb[k]], all_pairs[pairs[k]].limit_mm});
      add_obstacles(model, i, fixed);
      const double fold = robots[i].goal.beta_deg;
      GridPath path = find_fold(model.robot(i), fixed, poses[i], fold, o, max_cells);
      if (path.poses.empty() && !std::any_of(moving.begin(), moving.end(), [](bool b) { return b; })) {
        // Folded neighbours can turn freely (folded robots never touch): turn each so that its
        // folded capsule lies across the line to this robot's centre, as far as the unfolded
        // robots around it allow, all at once while everyone else stands still; then search again.
        std::vector<Segment> sweep;
        for (double b = poses[i].beta_deg;; b += (fold > b ? 5.0 : -5.0)) {
          const bool end = std::abs(fold - b) <= 5.0;
          sweep.push_back(model.robot(i).collision_segment({poses[i].alpha_deg, end ? fold : b}));
          if (end) break;
        }
        auto folded = [&](std::size_t j) {
          return result.reached[j] && !robots[j].frozen && !robots[j].script && poses[j].beta_deg == robots[j].goal.beta_deg &&
                 std::find(stuck.begin(), stuck.end(), j) == stuck.end();
        };
        double slot = 0;
        std::vector<std::pair<std::uint32_t, std::vector<Pose>>> turns;
        for (const std::uint32_t j : nb) {
          if (!folded(j)) continue;
          const Positioner& rj = model.robot(j);
          const AngleLimits& lj = rj.limits();
          // Clearance of the folded capsule to this robot's straight fold (beta alone, sampled).
          auto sweep_clearance = [&](const Segment& sj) {
            double c = std::numeric_limits<double>::infinity();
            for (const Segment& si : sweep) c = std::min(c, segment_distance(si, sj));
            return c;
          };
          std::vector<Fixed> fj;
          const auto nbj = model.neighbours(j);
          const auto pj = model.pairs_of(j);
          for (std::size_t k = 0; k < nbj.size(); ++k)
            if (!folded(nbj[k])) fj.push_back({segs[nbj[k]], all_pairs[pj[k]].limit_mm});
          add_obstacles(model, j, fj);
          RobotGrid gj(rj, std::move(fj), poses[j], o.alpha_step_deg, o.beta_step_deg, o.margin_mm);
          // How far it can turn either way (the unfolded robots, often this one, may stop it);
          // the best alpha within that range.
          const double lo = gj.walk_to({lj.alpha_min_deg, poses[j].beta_deg}).back().alpha_deg;
          const double hi = gj.walk_to({lj.alpha_max_deg, poses[j].beta_deg}).back().alpha_deg;
          double best_a = poses[j].alpha_deg, best_d = sweep_clearance(segs[j]);
          auto consider = [&](double a) {
            const double d = sweep_clearance(rj.collision_segment({a, poses[j].beta_deg}));
            if (d > best_d + 0.5 || (d > best_d - 1e-6 && std::abs(a - poses[j].alpha_deg) < std::abs(best_a - poses[j].alpha_deg))) {
              best_d = d;
              best_a = a;
            }
          };
          for (double a = std::ceil(lo / 5) * 5; a <= hi; a += 5) consider(a);
          consider(lo);
          consider(hi);
          if (best_a == poses[j].alpha_deg) continue;
          std::vector<Pose> w = gj.walk_to({best_a, poses[j].beta_deg});
          if (w.size() < 2) continue;
          slot = std::max(slot, static_cast<double>(w.size() - 1) * o.dt_s);
          turns.emplace_back(j, std::move(w));
        }
        if (!turns.empty()) {
          std::vector<Fixed> fixed2;
          std::vector<Segment> segs2 = segs;
          for (const auto& [j, w] : turns) segs2[j] = model.robot(j).collision_segment(w.back());
          for (std::size_t k = 0; k < nb.size(); ++k) fixed2.push_back({segs2[nb[k]], all_pairs[pairs[k]].limit_mm});
          add_obstacles(model, i, fixed2);
          path = find_fold(model.robot(i), fixed2, poses[i], fold, o, max_cells);
          if (!path.poses.empty()) {
            for (const auto& [j, w] : turns) {
              append_path(result.paths[j], w, t, o.dt_s);
              poses[j] = w.back();
              segs[j] = segs2[j];
              result.end[j] = poses[j];
              moving[j] = true;
            }
            t += slot;
          }
        }
      }
      if (path.poses.empty()) {
        left.push_back(i);
        continue;
      }
      append_path(result.paths[i], path.poses, t, path.dt);
      wave = std::max(wave, static_cast<double>(path.poses.size() - 1) * path.dt);
      poses[i] = path.poses.back();
      segs[i] = model.robot(i).collision_segment(poses[i]);
      result.end[i] = poses[i];
      result.reached[i] = true;
      result.blockers[i].clear();
      moving[i] = true;
      progress = true;
      ++done;
    }
    stuck = std::move(left);
    t += wave;
  }
  result.duration_s = std::max(result.duration_s, t);
  return done;
}

std::vector<std::string> fold_blocked_by_obstacles(const CollisionModel& model, std::size_t i, Pose from, double fold_beta,
                                                   const StepperOptions& o, std::size_t max_cells) {
  std::vector<Fixed> fixed;
  add_obstacles(model, i, fixed);
  if (fixed.empty()) return {};
  const Positioner& r = model.robot(i);
  // Most robots fold straight (beta alone): no search needed.
  if (RobotGrid(r, fixed, from, o.alpha_step_deg, o.beta_step_deg, o.margin_mm).walk_to({from.alpha_deg, fold_beta}).back() ==
      Pose{from.alpha_deg, fold_beta})
    return {};
  for (const auto& [f, margin] : grid_levels(o)) {
    RobotGrid g(r, fixed, from, o.alpha_step_deg * f, o.beta_step_deg * f, margin);
    if (!g.search(fold_beta, max_cells, true).empty() || !g.exhausted()) return {};  // a way out, or undecided
  }
  std::vector<std::string> around;
  for (const std::uint32_t k : model.obstacle_pairs_of(i))
    around.push_back(model.obstacles()[model.obstacle_pairs()[k].obstacle].name);
  return around;
}

}  // namespace axon::fps::plan

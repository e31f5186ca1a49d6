#include "axon/fps/plan/untangle.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <functional>
#include <numbers>
#include <optional>
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
  // Breadth-first: the quickest way out at this resolution or, with `aim` (the planned fold's alpha),
  // the way out that is quickest counting the folded turn to `aim` still to come after it (at one
  // alpha step per step, as the middle phase turns). `greedy`: the cells nearest the fold first,
  // which finds *a* way out visiting far fewer cells (reachability only).
  std::vector<Pose> search(double fold, std::size_t max_cells, bool greedy = false, std::optional<double> aim = {}) {
    const AngleLimits& l = r_.limits();
    // The outermost cell on each side may be a partial step that lands exactly on the limit
    // (pose() clamps): robots caught against a stop often get out only along it.
    const int a_lo = -static_cast<int>(std::ceil((start_.alpha_deg - l.alpha_min_deg) / sa_ - 1e-9));
    const int a_hi = static_cast<int>(std::ceil((l.alpha_max_deg - start_.alpha_deg) / sa_ - 1e-9));
    const int b_lo = -static_cast<int>(std::ceil((start_.beta_deg - l.beta_min_deg) / sb_ - 1e-9));
    const int b_hi = static_cast<int>(std::ceil((l.beta_max_deg - start_.beta_deg) / sb_ - 1e-9));
    parent_.clear();
    parent_.reserve(4096);
    Frontier frontier(greedy);
    parent_[key(0, 0)] = key(0, 0);
    frontier.push({0, 0, 0}, 0.0);
    clr_[key(0, 0)] = clearance(start_);
    exhausted_ = false;
    Finish best;
    while (!frontier.empty() && parent_.size() < max_cells) {
      const Cell c = frontier.pop();
      if (c.depth >= best.cost) break;  // nothing deeper finishes sooner
      const Pose p = pose(c.a, c.b);
      const double cp = cell_clear(c.a, c.b);
      // Within one step of the fold: finish there if that last step is clear.
      if (std::abs(p.beta_deg - fold) <= sb_ + 1e-9) {
        const Pose f{p.alpha_deg, fold};
        const double cf = p == f ? cp : clearance(f);
        if (p == f || (cf >= std::min(margin_, cp) && edge_ok(p, f, cp, cf))) {
          const double cost = c.depth + (p == f ? 0 : 1) + (aim ? std::abs(p.alpha_deg - *aim) / sa_ : 0.0);
          if (cost < best.cost - 1e-9) best = {c, f, cost};
          if (!aim) break;
        }
      }
      for (int da = -1; da <= 1; ++da)
        for (int db = -1; db <= 1; ++db) {
          if (da == 0 && db == 0) continue;
          const int a2 = c.a + da, b2 = c.b + db;
          if (a2 < a_lo || a2 > a_hi || b2 < b_lo || b2 > b_hi) continue;
          if (parent_.count(key(a2, b2))) continue;
          const double c2 = cell_clear(a2, b2);
          if (c2 < std::min(margin_, cp) || !edge_ok(p, pose(a2, b2), cp, c2)) continue;
          parent_[key(a2, b2)] = key(c.a, c.b);
          frontier.push({a2, b2, c.depth + 1}, std::abs(pose(a2, b2).beta_deg - fold));
        }
    }
    if (best.cost < std::numeric_limits<double>::infinity()) return path_to(best);
    exhausted_ = frontier.empty();
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
  struct Cell {
    int a, b, depth;
  };
  // Where a search finishes: the cell, the fold pose reached from it, and its cost in steps.
  struct Finish {
    Cell cell{0, 0, 0};
    Pose fold{};
    double cost = std::numeric_limits<double>::infinity();
  };
  // The cells still to visit: first in, first out (breadth-first), or nearest the fold first.
  class Frontier {
   public:
    explicit Frontier(bool greedy) : greedy_(greedy) {}
    void push(Cell c, double to_fold) {
      if (greedy_) near_.push({to_fold, c.a, c.b, c.depth});
      else fifo_.push_back(c);
    }
    Cell pop() {
      if (!greedy_) {
        const Cell c = fifo_.front();
        fifo_.pop_front();
        return c;
      }
      const auto [d, a, b, depth] = near_.top();
      near_.pop();
      return {a, b, depth};
    }
    [[nodiscard]] bool empty() const { return greedy_ ? near_.empty() : fifo_.empty(); }

   private:
    bool greedy_;
    std::deque<Cell> fifo_;
    std::priority_queue<std::tuple<double, int, int, int>, std::vector<std::tuple<double, int, int, int>>, std::greater<>> near_;
  };

  static std::int64_t key(int a, int b) noexcept { return (static_cast<std::int64_t>(a) << 32) ^ static_cast<std::uint32_t>(b); }

  double cell_clear(int a, int b) {
    auto it = clr_.find(key(a, b));
    if (it != clr_.end()) return it->second;
    const double c = clearance(pose(a, b));
    clr_[key(a, b)] = c;
    return c;
  }

  // The poses from the start to the finish, through the last search's parents.
  std::vector<Pose> path_to(const Finish& f) const {
    std::vector<Pose> path{f.fold};
    const Pose last = pose(f.cell.a, f.cell.b);
    if (!(last == f.fold)) path.push_back(last);
    for (std::int64_t k = key(f.cell.a, f.cell.b); k != key(0, 0);) {
      k = parent_.at(k);
      path.push_back(pose(static_cast<int>(k >> 32), static_cast<int>(static_cast<std::int32_t>(k & 0xffffffff))));
    }
    std::reverse(path.begin(), path.end());
    return path;
  }

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
  std::unordered_map<std::int64_t, std::int64_t> parent_;  // cell -> previous cell, of the last search
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

// A way to a fold at `goal`'s beta, aiming at its alpha (RobotGrid::search). The search on the
// engine's grid first; where that finds no way out, on grids of half and a
// quarter of the step (each step then takes as much less time, the speed stays the same) that
// keep a smaller margin. The robots left after the engine are mostly caught in narrow passages
// between a fixed obstacle and an alpha stop, which the coarse grid with the full margin cannot
// thread (they are not closed pockets: with only the obstacles present, every start pose of the
// bench problems reaches a fold on a 0.25 deg grid).
GridPath find_fold(const Positioner& r, const std::vector<Fixed>& fixed, Pose start, Pose goal, const StepperOptions& o,
                   std::size_t max_cells) {
  const double fold = goal.beta_deg;
  for (const auto& [f, margin] : grid_levels(o)) {
    RobotGrid g(r, fixed, start, o.alpha_step_deg * f, o.beta_step_deg * f, margin);
    std::vector<Pose> p = g.search(fold, max_cells, false, goal.alpha_deg);
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

// Robot i's trajectory ends at time t: each arm at its angle then (the engine's pose at that
// instant, inside its certificate), the points after it dropped.
void cut_at(RobotTrajectory& path, double t) {
  for (auto* arm : {&path.alpha, &path.beta}) {
    if (arm->back().t_s <= t) continue;
    const double deg = angle_at(*arm, t);
    std::erase_if(*arm, [t](const TimedAngle& p) { return p.t_s >= t; });
    arm->push_back({t, deg});
  }
}

// Robot i and the robots within two rings of neighbours around it.
std::vector<std::uint32_t> two_rings(const CollisionModel& model, std::uint32_t i) {
  std::vector<std::uint32_t> out{i};
  for (const std::uint32_t j : model.neighbours(i)) {
    out.push_back(j);
    for (const std::uint32_t k : model.neighbours(j)) out.push_back(k);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// The stuck robots in zones: a stuck robot and everything within two rings of it (what its own
// move and its folded neighbours' turns can touch), zones merged where they overlap. No robot of
// one zone's untangle is then a neighbour of one of another's, so each zone keeps its own clock.
struct Zone {
  std::vector<std::uint32_t> stuck;  // model order
};
std::vector<Zone> zones_of(const CollisionModel& model, const std::vector<std::uint32_t>& stuck) {
  std::vector<std::size_t> parent(stuck.size());
  for (std::size_t k = 0; k < stuck.size(); ++k) parent[k] = k;
  std::function<std::size_t(std::size_t)> root = [&](std::size_t k) { return parent[k] == k ? k : parent[k] = root(parent[k]); };
  std::vector<std::ptrdiff_t> owner(model.size(), -1);
  for (std::size_t k = 0; k < stuck.size(); ++k) {
    for (const std::uint32_t r : two_rings(model, stuck[k])) {
      if (owner[r] < 0) owner[r] = static_cast<std::ptrdiff_t>(k);
      else parent[root(k)] = root(static_cast<std::size_t>(owner[r]));
    }
  }
  std::vector<Zone> out;
  std::vector<std::ptrdiff_t> index(stuck.size(), -1);
  for (std::size_t k = 0; k < stuck.size(); ++k) {
    const std::size_t r = root(k);
    if (index[r] < 0) {
      index[r] = static_cast<std::ptrdiff_t>(out.size());
      out.emplace_back();
    }
    out[static_cast<std::size_t>(index[r])].stuck.push_back(stuck[k]);
  }
  return out;
}

// The untangle of a half's stuck robots, zone by zone (untangle_to_fold).
class Untangler {
 public:
  Untangler(const CollisionModel& model, std::span<const StepperRobot> robots, StepperResult& result,
            const StepperOptions& o, std::size_t max_cells)
      : model_(model), robots_(robots), result_(result), o_(o), max_cells_(max_cells), poses_(result.end),
        segs_(model.size()), moving_(model.size(), false), stuck_(model.size(), false), cut_(model.size(), 0.0), pairs_(model.robot_pairs()) {
    model.segments(poses_, segs_);
  }

  // The zone's stuck robots in waves, while they make progress: stuck robots that are not
  // neighbours of each other move in the same wave. Each stuck robot first has its path cut (see
  // cut_clusters) and starts no earlier than that. Returns how many reached a fold.
  std::size_t run_zone(const Zone& z) {
    for (const std::uint32_t r : z.stuck) stuck_[r] = true;
    double t = cut_clusters(z);
    std::size_t done = 0;
    std::vector<std::uint32_t> left = z.stuck;
    for (bool progress = true; progress && !left.empty();) {
      std::fill(moving_.begin(), moving_.end(), false);
      const std::size_t before = left.size();
      left = wave(left, t);
      progress = left.size() < before;
      done += before - left.size();
    }
    return done;
  }

 private:
  // The engine keeps a stuck robot wandering until its stall limit, long after the robots around
  // it have stopped. A cluster of stuck robots (neighbours of each other) has its paths cut when
  // every robot next to one of them has stopped for good: that instant is certified clear, and
  // from then on nothing that can touch them moves. Returns the earliest cut of the zone.
  double cut_clusters(const Zone& z) {
    double first = std::numeric_limits<double>::infinity();
    std::vector<bool> seen(model_.size(), false);
    for (const std::uint32_t from : z.stuck) {
      if (seen[from]) continue;
      std::vector<std::uint32_t> cluster{from};
      seen[from] = true;
      double cut = 0;
      for (std::size_t k = 0; k < cluster.size(); ++k)
        for (const std::uint32_t j : model_.neighbours(cluster[k])) {
          if (!stuck_[j]) cut = std::max(cut, end_time(result_.paths[j]));
          else if (!seen[j]) {
            seen[j] = true;
            cluster.push_back(j);
          }
        }
      for (const std::uint32_t i : cluster) {
        cut_at(result_.paths[i], cut);
        cut_[i] = cut;
        poses_[i] = result_.end[i] = {result_.paths[i].alpha.back().deg, result_.paths[i].beta.back().deg};
        segs_[i] = model_.robot(i).collision_segment(poses_[i]);
      }
      first = std::min(first, cut);
    }
    return first;
  }

  // When everything within two rings of robot i is still for good (the stuck robots there cut):
  // from then on its folded neighbours may turn out of its way.
  [[nodiscard]] double rest_around(std::uint32_t i) const {
    double t = 0;
    for (const std::uint32_t r : two_rings(model_, i)) t = std::max(t, stuck_[r] ? cut_[r] : end_time(result_.paths[r]));
    return t;
  }

  // One wave from time t (t advances past it); returns the robots still stuck. A robot starts at
  // t or at its cut, whichever is later.
  std::vector<std::uint32_t> wave(const std::vector<std::uint32_t>& stuck, double& t) {
    double end = t;
    std::vector<std::uint32_t> left;
    for (const std::uint32_t i : stuck) {
      const auto nb = model_.neighbours(i);
      if (std::any_of(nb.begin(), nb.end(), [&](std::uint32_t j) { return moving_[j]; })) {
        left.push_back(i);
        continue;
      }
      const double fold = robots_[i].goal.beta_deg;
      double start = std::max(t, cut_[i]);
      GridPath path = find_fold(model_.robot(i), around(i, segs_), poses_[i], robots_[i].goal, o_, max_cells_);
      if (path.poses.empty() && std::none_of(moving_.begin(), moving_.end(), [](bool b) { return b; })) {
        // Nothing moves in this wave yet: the turns go first, the wave starts after them.
        start = std::max(start, rest_around(i));
        path = make_way(i, fold, start);
        if (!path.poses.empty()) end = t = start;
      }
      if (path.poses.empty()) {
        left.push_back(i);
        continue;
      }
      append_path(result_.paths[i], path.poses, start, path.dt);
      end = std::max(end, start + static_cast<double>(path.poses.size() - 1) * path.dt);
      poses_[i] = result_.end[i] = path.poses.back();
      segs_[i] = model_.robot(i).collision_segment(poses_[i]);
      result_.reached[i] = true;
      result_.blockers[i].clear();
      moving_[i] = true;
      stuck_[i] = false;
    }
    t = end;
    return left;
  }

  // Robot i's neighbours (at `segs`) and fixed obstacles, each with its pair's limit.
  std::vector<Fixed> around(std::size_t i, const std::vector<Segment>& segs) const {
    std::vector<Fixed> fixed;
    const auto nb = model_.neighbours(i);
    const auto pairs = model_.pairs_of(i);
    for (std::size_t k = 0; k < nb.size(); ++k) fixed.push_back({segs[nb[k]], pairs_[pairs[k]].limit_mm});
    add_obstacles(model_, i, fixed);
    return fixed;
  }

  [[nodiscard]] bool folded(std::size_t j) const {
    return result_.reached[j] && !robots_[j].frozen && !robots_[j].script && poses_[j].beta_deg == robots_[j].goal.beta_deg &&
           !stuck_[j];
  }

  // Folded neighbours can turn freely (folded robots never touch): each turns so that its folded
  // capsule lies across the line to robot i's centre, as far as the unfolded robots around it
  // allow, all at once while everyone else stands still; then robot i's way out is searched again.
  // Taken (the turns appended at t, t past them) only when that finds one.
  GridPath make_way(std::size_t i, double fold, double& t) {
    std::vector<Segment> sweep;
    for (double b = poses_[i].beta_deg;; b += (fold > b ? 5.0 : -5.0)) {
      const bool end = std::abs(fold - b) <= 5.0;
      sweep.push_back(model_.robot(i).collision_segment({poses_[i].alpha_deg, end ? fold : b}));
      if (end) break;
    }
    double slot = 0;
    std::vector<std::pair<std::uint32_t, std::vector<Pose>>> turns;
    for (const std::uint32_t j : model_.neighbours(i)) {
      if (!folded(j)) continue;
      std::vector<Pose> w = turn_aside(j, sweep);
      if (w.size() < 2) continue;
      slot = std::max(slot, static_cast<double>(w.size() - 1) * o_.dt_s);
      turns.emplace_back(j, std::move(w));
    }
    if (turns.empty()) return {};
    std::vector<Segment> segs2 = segs_;
    for (const auto& [j, w] : turns) segs2[j] = model_.robot(j).collision_segment(w.back());
    GridPath path = find_fold(model_.robot(i), around(i, segs2), poses_[i], robots_[i].goal, o_, max_cells_);
    if (path.poses.empty()) return {};
    for (const auto& [j, w] : turns) {
      append_path(result_.paths[j], w, t, o_.dt_s);
      poses_[j] = result_.end[j] = w.back();
      segs_[j] = segs2[j];
      moving_[j] = true;
    }
    t += slot;
    return path;
  }

  // Folded robot j's turn to the alpha (within the range it can reach, the unfolded robots around
  // it in the way) that keeps its capsule farthest from `sweep`; just its pose when none is better.
  std::vector<Pose> turn_aside(std::uint32_t j, const std::vector<Segment>& sweep) const {
    const Positioner& rj = model_.robot(j);
    const AngleLimits& lj = rj.limits();
    auto sweep_clearance = [&](const Segment& sj) {
      double c = std::numeric_limits<double>::infinity();
      for (const Segment& si : sweep) c = std::min(c, segment_distance(si, sj));
      return c;
    };
    std::vector<Fixed> fj;
    const auto nbj = model_.neighbours(j);
    const auto pj = model_.pairs_of(j);
    for (std::size_t k = 0; k < nbj.size(); ++k)
      if (!folded(nbj[k])) fj.push_back({segs_[nbj[k]], pairs_[pj[k]].limit_mm});
    add_obstacles(model_, j, fj);
    RobotGrid gj(rj, std::move(fj), poses_[j], o_.alpha_step_deg, o_.beta_step_deg, o_.margin_mm);
    const double lo = gj.walk_to({lj.alpha_min_deg, poses_[j].beta_deg}).back().alpha_deg;
    const double hi = gj.walk_to({lj.alpha_max_deg, poses_[j].beta_deg}).back().alpha_deg;
    double best_a = poses_[j].alpha_deg, best_d = sweep_clearance(segs_[j]);
    auto consider = [&](double a) {
      const double d = sweep_clearance(rj.collision_segment({a, poses_[j].beta_deg}));
      if (d > best_d + 0.5 || (d > best_d - 1e-6 && std::abs(a - poses_[j].alpha_deg) < std::abs(best_a - poses_[j].alpha_deg))) {
        best_d = d;
        best_a = a;
      }
    };
    for (double a = std::ceil(lo / 5) * 5; a <= hi; a += 5) consider(a);
    consider(lo);
    consider(hi);
    if (best_a == poses_[j].alpha_deg) return {poses_[j]};
    return gj.walk_to({best_a, poses_[j].beta_deg});
  }

  const CollisionModel& model_;
  std::span<const StepperRobot> robots_;
  StepperResult& result_;
  const StepperOptions& o_;
  std::size_t max_cells_;
  std::vector<Pose> poses_;
  std::vector<Segment> segs_;
  std::vector<bool> moving_;  // moving in the current wave
  std::vector<bool> stuck_;   // of the zone, not yet untangled
  std::vector<double> cut_;   // per stuck robot: where its path was cut (it starts no earlier)
  std::span<const RobotPair> pairs_;
};

}  // namespace

std::size_t untangle_to_fold(const CollisionModel& model, std::span<const StepperRobot> robots, StepperResult& result,
                             const StepperOptions& o, std::size_t max_cells) {
  std::vector<std::uint32_t> stuck;
  for (std::size_t i = 0; i < model.size(); ++i)
    if (!result.reached[i] && !robots[i].frozen && !robots[i].script) stuck.push_back(static_cast<std::uint32_t>(i));
  if (stuck.empty()) return 0;
  Untangler u(model, robots, result, o, max_cells);
  std::size_t done = 0;
  for (const Zone& z : zones_of(model, stuck)) done += u.run_zone(z);
  result.duration_s = 0;
  for (const auto& p : result.paths) result.duration_s = std::max(result.duration_s, end_time(p));
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

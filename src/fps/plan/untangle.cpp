#include "fps/plan/untangle.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <numbers>
#include <unordered_map>

namespace axon::fps::plan {

namespace {

constexpr double kRad = std::numbers::pi / 180.0;
constexpr double kTiny = 2e-4;

struct Fixed {
  Segment s;
  double limit;
};

class RobotGrid {
 public:
  RobotGrid(const Positioner& r, std::vector<Fixed> fixed, Pose start, double sa, double sb, double margin)
      : r_(r), fixed_(std::move(fixed)), start_(start), sa_(sa), sb_(sb), margin_(margin) {}

  // Path of poses from the start to a fold at beta `fold`, empty when none within `max_cells`.
  std::vector<Pose> search(double fold, std::size_t max_cells) {
    const AngleLimits& l = r_.limits();
    const int a_lo = -static_cast<int>(std::floor((start_.alpha_deg - l.alpha_min_deg) / sa_ + 1e-9));
    const int a_hi = static_cast<int>(std::floor((l.alpha_max_deg - start_.alpha_deg) / sa_ + 1e-9));
    const int b_lo = -static_cast<int>(std::floor((start_.beta_deg - l.beta_min_deg) / sb_ + 1e-9));
    const int b_hi = static_cast<int>(std::floor((l.beta_max_deg - start_.beta_deg) / sb_ + 1e-9));
    auto key = [](int a, int b) { return (static_cast<std::int64_t>(a) << 32) ^ static_cast<std::uint32_t>(b); };
    std::unordered_map<std::int64_t, std::int64_t> parent;  // cell -> previous cell
    std::deque<std::pair<int, int>> q;
    parent.reserve(4096);
    parent[key(0, 0)] = key(0, 0);
    q.push_back({0, 0});
    const double c_start = clearance(start_);
    auto cell_clear = [&](int a, int b) {
      auto it = clr_.find(key(a, b));
      if (it != clr_.end()) return it->second;
      const double c = clearance(pose(a, b));
      clr_[key(a, b)] = c;
      return c;
    };
    clr_[key(0, 0)] = c_start;
    while (!q.empty() && parent.size() < max_cells) {
      const auto [a, b] = q.front();
      q.pop_front();
      const Pose p = pose(a, b);
      const double cp = cell_clear(a, b);
      // Within one step of the fold: finish there if that last step is clear.
      if (std::abs(p.beta_deg - fold) <= sb_ + 1e-9) {
        const Pose f{p.alpha_deg, fold};
        const double cf = clearance(f);
        if (p == f || (cf >= margin_ && edge_ok(cp, cf, 0, std::abs(fold - p.beta_deg)))) {
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
          if (c2 < margin_ || !edge_ok(cp, c2, std::abs(da) * sa_, std::abs(db) * sb_)) continue;
          parent[key(a2, b2)] = key(a, b);
          q.push_back({a2, b2});
        }
    }
    return {};
  }

 private:
  [[nodiscard]] Pose pose(int a, int b) const noexcept { return {start_.alpha_deg + a * sa_, start_.beta_deg + b * sb_}; }
  [[nodiscard]] double clearance(Pose p) const noexcept {
    const Segment s = r_.collision_segment(p);
    double c = std::numeric_limits<double>::infinity();
    for (const Fixed& f : fixed_) c = std::min(c, segment_distance(s, f.s) - f.limit);
    return c;
  }
  [[nodiscard]] bool edge_ok(double c0, double c1, double da_deg, double db_deg) const noexcept {
    const double s = (da_deg * r_.reach_mm() + db_deg * r_.collision_length_mm()) * kRad;
    return c0 >= 0 && c1 >= 0 && c0 + c1 - s >= 2 * kTiny;
  }

  const Positioner& r_;
  std::vector<Fixed> fixed_;
  Pose start_;
  double sa_, sb_, margin_;
  std::unordered_map<std::int64_t, double> clr_;
};

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
  const auto obstacles = model.obstacles();
  const auto opairs = model.obstacle_pairs();
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
      for (std::size_t k = 0; k < nb.size(); ++k) fixed.push_back({segs[nb[k]], all_pairs[pairs[k]].limit_mm});
      for (const std::uint32_t k : model.obstacle_pairs_of(i))
        fixed.push_back({obstacles[opairs[k].obstacle].shape, opairs[k].limit_mm});
      const double fold = robots[i].goal.beta_deg;
      RobotGrid grid(model.robot(i), std::move(fixed), poses[i], o.alpha_step_deg, o.beta_step_deg, o.margin_mm);
      const std::vector<Pose> path = grid.search(fold, max_cells);
      if (path.empty()) {
        left.push_back(i);
        continue;
      }
      append_path(result.paths[i], path, t, o.dt_s);
      wave = std::max(wave, static_cast<double>(path.size() - 1) * o.dt_s);
      poses[i] = path.back();
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

}  // namespace axon::fps::plan

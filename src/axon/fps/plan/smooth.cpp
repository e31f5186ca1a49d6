#include "axon/fps/plan/smooth.hpp"

#include "axon/fps/plan/distance.hpp"
#include "axon/fps/plan/moving_segment.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace axon::fps::plan {

namespace {

// Certifies one robot's changed motion over an interval against its neighbours' and obstacles'
// current motion (conservative advancement, see smooth.hpp).
class ShortcutCertifier {
 public:
  ShortcutCertifier(const CollisionModel& model, const std::vector<RobotTrajectory>& trajectories,
                    const SmoothOptions& o)
      : m_(model), traj_(trajectories), o_(o) {}

  // Robot i with arm `alpha_arm ? alpha : beta` following `piece` (two or more points, linear in
  // between; the other arm as in its trajectory): clear of everything over the piece's interval?
  bool clear(std::size_t i, bool alpha_arm, std::span<const TimedAngle> piece) const {
    const RobotTrajectory& ti = traj_[i];
    MovingSegment mi(m_.robot(i), alpha_arm ? piece : std::span<const TimedAngle>(ti.alpha),
                     alpha_arm ? std::span<const TimedAngle>(ti.beta) : piece);
    const double t0 = piece.front().t_s, t1 = piece.back().t_s;
    const auto nb = m_.neighbours(i);
    const auto pairs = m_.pairs_of(i);
    const auto all = m_.robot_pairs();
    for (std::size_t k = 0; k < nb.size(); ++k) {
      const RobotTrajectory& tj = traj_[nb[k]];
      MovingRobotPair pair{mi, {m_.robot(nb[k]), tj.alpha, tj.beta}, all[pairs[k]].limit_mm};
      if (!advance(t0, t1, pair)) return false;
    }
    const auto obstacles = m_.obstacles();
    const auto opairs = m_.obstacle_pairs();
    for (const std::uint32_t k : m_.obstacle_pairs_of(i)) {
      const ObstaclePair& op = opairs[k];
      MovingObstaclePair pair{mi, obstacles[op.obstacle].shape, op.limit_mm};
      if (!advance(t0, t1, pair)) return false;
    }
    return true;
  }

 private:
  // The pair from t0 to t1: every evaluation keeps min_clearance_mm, and the next one is where the
  // clearance could first fall below it (within the stretch where both bodies keep their speeds).
  template <class Pair>
  bool advance(double t0, double t1, Pair& pair) const {
    for (double t = t0;;) {
      const double c = pair.clearance(t);
      if (!(c >= o_.min_clearance_mm)) return false;
      if (t >= t1) return true;
      const double v = pair.rate();
      const double stretch_end = std::min(pair.next(), t1);
      if (v <= 0) {
        t = stretch_end;
        continue;
      }
      const double step = (c - o_.min_clearance_mm) / v;
      if (step < o_.min_step_s) return false;
      t = std::min(t + step, stretch_end);
    }
  }

  const CollisionModel& m_;
  const std::vector<RobotTrajectory>& traj_;
  SmoothOptions o_;
};

}  // namespace

SmoothStats smooth_arms(const CollisionModel& model, std::vector<RobotTrajectory>& trajectories,
                        const SmoothOptions& options, std::vector<bool>& changed) {
  SmoothStats stats;
  const std::size_t n = model.size();
  changed.assign(n, false);
  if (trajectories.size() != n) return stats;
  ShortcutCertifier cert(model, trajectories, options);
  // A later sweep sees the neighbours' shortened arms: a dither that answered a neighbour's dither
  // may go once that one is gone.
  for (int sweep = 0; sweep < std::max(1, options.sweeps); ++sweep) {
    // The arms to shorten, most points first (ties: model order, alpha before beta).
    std::vector<std::tuple<std::size_t, std::size_t, bool>> arms;  // points, robot, alpha?
    for (std::size_t i = 0; i < n; ++i)
      for (const bool alpha : {true, false}) {
        const std::size_t pts = (alpha ? trajectories[i].alpha : trajectories[i].beta).size();
        if (pts > 0 && pts - 1 > options.min_points) arms.emplace_back(pts, i, alpha);
      }
    std::stable_sort(arms.begin(), arms.end(), [](const auto& a, const auto& b) { return std::get<0>(a) > std::get<0>(b); });
    std::size_t shortened = 0;
    for (const auto& arm : arms) {
      // Named copies, not structured bindings: clang 14 cannot capture those in the lambda below.
      const std::size_t i = std::get<1>(arm);
      const bool alpha = std::get<2>(arm);
      // A copy: the certifier reads the robot's current trajectory (the other arm) while this one is
      // rebuilt; the arm being edited is described to it by the shortcut's own points.
      const std::vector<TimedAngle> pts = alpha ? trajectories[i].alpha : trajectories[i].beta;
      const std::size_t m = pts.size();
      const double vmax = max_speed(pts);
      // Shortcuts from point a to point b: straight, else holding at the lowest or the highest angle
      // the arm had in between (reached and left at the arm's top speed: a dither around a pose a
      // neighbour squeezes is replaced by waiting on the side where it was clear).
      std::vector<TimedAngle> piece, best_piece;
      auto shortcut = [&](std::size_t a, std::size_t b) {
        ++stats.shortcuts_tried;
        piece.assign({pts[a], pts[b]});
        if (cert.clear(i, alpha, piece)) return true;
        if (b <= a + 1 || vmax <= 0) return false;
        double lo = pts[a].deg, hi = pts[a].deg;
        for (std::size_t k = a + 1; k <= b; ++k) {
          lo = std::min(lo, pts[k].deg);
          hi = std::max(hi, pts[k].deg);
        }
        for (const double hold : {lo, hi}) {
          if (hold == pts[a].deg && hold == pts[b].deg) continue;  // the straight piece, tried
          const double ta = pts[a].t_s + std::abs(hold - pts[a].deg) / vmax;
          const double tb = pts[b].t_s - std::abs(pts[b].deg - hold) / vmax;
          if (tb < ta - 1e-9) continue;  // cannot happen for angles the arm reached in between
          piece.assign({pts[a]});
          if (ta > pts[a].t_s + 1e-9) piece.push_back({ta, hold});
          if (tb > piece.back().t_s + 1e-9 && tb < pts[b].t_s - 1e-9) piece.push_back({tb, hold});
          piece.push_back(pts[b]);
          if (cert.clear(i, alpha, piece)) return true;
        }
        return false;
      };
      std::vector<TimedAngle> out{pts.front()};
      std::size_t at = 0;
      while (at + 1 < m) {
        // The segment to the next point is the arm's own (certified by the planner); farther ones
        // are tried by doubling the span, then bisecting between the last success and the failure.
        std::size_t good = at + 1, bad = m;
        best_piece.assign({pts[at], pts[at + 1]});
        auto attempt = [&](std::size_t j) {
          if (!shortcut(at, j)) return false;
          good = j;
          best_piece = piece;
          return true;
        };
        for (std::size_t span = 2;; span *= 2) {
          const std::size_t j = std::min(at + span, m - 1);
          if (j <= good) break;
          if (!attempt(j)) {
            bad = j;
            break;
          }
          if (j == m - 1) break;
        }
        while (bad < m && bad - good > 1) {
          const std::size_t mid = good + (bad - good) / 2;
          if (!attempt(mid)) bad = mid;
        }
        out.insert(out.end(), best_piece.begin() + 1, best_piece.end());
        at = good;
      }
      if (out.size() < m) {
        ++shortened;
        ++stats.arms;
        stats.points_before += m - 1;
        stats.points_after += out.size() - 1;
        (alpha ? trajectories[i].alpha : trajectories[i].beta) = std::move(out);
        changed[i] = true;
      }
    }
    if (shortened == 0) break;
  }
  return stats;
}

}  // namespace axon::fps::plan

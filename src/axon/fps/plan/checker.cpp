#include "axon/fps/plan/checker.hpp"

#include "axon/fps/plan/moving_segment.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <thread>

namespace axon::fps::plan {

namespace checker_detail {

void merge(PairOutcome& into, const PairOutcome& from) {
  if (from.collided && (!into.collided || from.first_collision_s < into.first_collision_s)) {
    into.collided = true;
    into.first_collision_s = from.first_collision_s;
  }
  if (from.min_clearance_mm < into.min_clearance_mm) {
    into.min_clearance_mm = from.min_clearance_mm;
    into.min_clearance_s = from.min_clearance_s;
  }
}

void note(PairOutcome& o, double clearance, double t) {
  if (clearance < o.min_clearance_mm) {
    o.min_clearance_mm = clearance;
    o.min_clearance_s = t;
  }
  if (clearance < 0 && !o.collided) {
    o.collided = true;
    o.first_collision_s = t;
  }
}

// Halvings of one sample interval before the checker gives up proving it clear.
constexpr int kMaxHalvings = 12;

// Proves the interval [t0, t1] between two samples clear for one pair, or finds the contact. The
// clearance cannot change faster than `rate` (the sum of both bodies' fastest point speeds), so it
// stays >= (c0 + c1 - rate * (t1 - t0)) / 2 in between; where that is negative the interval is
// halved (exact clearance at the midpoint) until it is proven, a contact shows, or the halvings
// run out: then the bound itself is noted (a contact the checker cannot rule out).
template <class Clearance>
void certify(PairOutcome& o, const Clearance& at, double rate, double t0, double c0, double t1, double c1, int depth,
             std::size_t& halvings) {
  if (c0 < 0 || c1 < 0 || c0 + c1 >= rate * (t1 - t0)) return;  // a contact is noted where sampled
  const double tm = 0.5 * (t0 + t1);
  if (depth >= kMaxHalvings) {
    note(o, 0.5 * (c0 + c1 - rate * (t1 - t0)), tm);
    return;
  }
  ++halvings;
  const double cm = at(tm);
  note(o, cm, tm);
  certify(o, at, rate, t0, c0, tm, cm, depth + 1, halvings);
  certify(o, at, rate, tm, cm, t1, c1, depth + 1, halvings);
}

struct Walked {
  std::size_t evaluations = 0;
  std::size_t forced = 0;
};

// One pair's time line from `start` to `end` (the advancing method, checker.hpp). `clearance(t)`
// reads both bodies at t (after which `rate()` and `next()` describe the stretch from t on).
template <class Pair>
Walked walk(PairOutcome& o, Pair& pair, double start, double end, const CheckOptions& opt) {
  Walked w;
  double t = start;
  for (;;) {
    // Also read where nothing moved since the last evaluation: it moves the bodies' cursors on.
    const double c = pair.clearance(t);
    ++w.evaluations;
    note(o, c, t);
    if (t >= end) break;
    const double stretch_end = std::min(pair.next(), end);
    const double v = pair.rate();
    if (v <= 0) {  // neither body moves until stretch_end: the clearance stays c
      t = stretch_end;
      continue;
    }
    // Precision: the bound over the step stays at or above min(smallest so far, precise_below) -
    // precision; proof: never below 0 from a clear evaluation.
    const double floor = std::min(o.min_clearance_mm, opt.precise_below_mm) - opt.precision_mm;
    double step = (c - floor) / v;
    if (c >= 0) step = std::min(step, c / v);
    if (step < opt.min_step_s) {
      step = opt.min_step_s;
      note(o, c - v * step, t);  // not proven: the bound counts (a contact when below 0)
      ++w.forced;
    }
    t = std::min(t + step, stretch_end);
  }
  return w;
}

}  // namespace checker_detail

using checker_detail::certify;
using checker_detail::merge;
using checker_detail::note;

void TrajectoryChecker::advance(Worker& w, std::span<const RobotTrajectory> trajectories, std::size_t first,
                                std::size_t last, const CheckOptions& options, CheckReport& out) const {
  const CollisionModel& m = *model_;
  const auto rp = m.robot_pairs();
  const auto op = m.obstacle_pairs();
  w.evaluations = w.busiest = w.forced = 0;
  auto tally = [&](const checker_detail::Walked& k) {
    w.evaluations += k.evaluations;
    w.busiest = std::max(w.busiest, k.evaluations);
    w.forced += k.forced;
  };
  for (std::size_t k = first; k < last; ++k) {
    if (k < rp.size()) {
      const RobotPair& p = rp[k];
      MovingRobotPair pair{{m.robot(p.a), trajectories[p.a].alpha, trajectories[p.a].beta},
                           {m.robot(p.b), trajectories[p.b].alpha, trajectories[p.b].beta}, p.limit_mm};
      tally(checker_detail::walk(out.robot_pairs[k], pair, out.start_s, out.end_s, options));
    } else {
      const ObstaclePair& p = op[k - rp.size()];
      MovingObstaclePair pair{{m.robot(p.robot), trajectories[p.robot].alpha, trajectories[p.robot].beta},
                              m.obstacles()[p.obstacle].shape, p.limit_mm};
      tally(checker_detail::walk(out.obstacle_pairs[k - rp.size()], pair, out.start_s, out.end_s, options));
    }
  }
}

Result<void> TrajectoryChecker::check(std::span<const RobotTrajectory> trajectories, const CheckOptions& options,
                                      CheckReport& out) {
  const CollisionModel& m = *model_;
  const std::size_t n = m.size();
  if (trajectories.size() != n)
    return make_error(PlanErrc::bad_trajectory,
                      fmt::format("{} trajectories for {} robots", trajectories.size(), n));
  if (!(options.max_step_mm > 0))
    return make_error(PlanErrc::bad_trajectory, fmt::format("max_step_mm must be > 0, not {}", options.max_step_mm));
  // The advancing method's steps are at least min_step_s long and precision_mm of travel: with
  // either at 0 (or not a number) a pair touching at 0 clearance would never move on.
  if (!(options.precision_mm > 0) || !(options.min_step_s > 0) || !(options.precise_below_mm >= 0))
    return make_error(PlanErrc::bad_trajectory,
                      fmt::format("precision_mm and min_step_s must be > 0 and precise_below_mm >= 0, not {}, {} and {}",
                                  options.precision_mm, options.min_step_s, options.precise_below_mm));

  // Time span and the fastest-moving point of any robot.
  double start = std::numeric_limits<double>::infinity();
  double end = -std::numeric_limits<double>::infinity();
  double point_speed = 0;  // mm/s
  speed_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const RobotTrajectory& t = trajectories[i];
    if (auto v = validate(t); !v)
      return make_error(PlanErrc::bad_trajectory, fmt::format("robot {} {}", m.robot(i).id(), v.error().detail));
    start = std::min({start, t.alpha.front().t_s, t.beta.front().t_s});
    end = std::max({end, t.alpha.back().t_s, t.beta.back().t_s});
    const Positioner& p = m.robot(i);
    speed_[i] = max_speed(t.alpha) * kRad * p.reach_mm() + max_speed(t.beta) * kRad * p.collision_length_mm();
    point_speed = std::max(point_speed, speed_[i]);
  }
  if (n == 0) start = end = 0;

  out.start_s = start;
  out.end_s = end;
  out.step_s = 0;
  out.samples = 1;
  out.halvings = out.forced_steps = out.pair_evaluations = 0;
  out.robot_pairs.assign(m.robot_pairs().size(), PairOutcome{});
  out.obstacle_pairs.assign(options.obstacles ? m.obstacle_pairs().size() : 0, PairOutcome{});
  const unsigned threads = options.threads ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  if (options.method == CheckMethod::dense)
    check_dense(trajectories, options, point_speed, threads, out);
  else
    check_advancing(trajectories, options, threads, out);
  summarize(options, out);
  return ok();
}

// Runs `work(k, first, last)` on `threads` contiguous blocks of [0, count).
template <class Work>
void TrajectoryChecker::split(std::size_t count, unsigned threads, const Work& work) {
  if (workers_.size() < threads) workers_.resize(threads);
  if (threads <= 1) {
    work(0u, std::size_t{0}, count);
    return;
  }
  const std::size_t per = (count + threads - 1) / threads;
  std::vector<std::thread> pool;
  pool.reserve(threads);
  for (unsigned k = 0; k < threads; ++k) {
    const std::size_t first = std::min(count, k * per);
    const std::size_t last = std::min(count, first + per);
    pool.emplace_back([&work, k, first, last] { work(k, first, last); });
  }
  for (auto& t : pool) t.join();
}

void TrajectoryChecker::check_dense(std::span<const RobotTrajectory> trajectories, const CheckOptions& options,
                                    double point_speed, unsigned threads, CheckReport& out) {
  if (out.end_s > out.start_s && point_speed > 0) {
    const double dt = options.max_step_mm / point_speed;
    const auto intervals = static_cast<std::size_t>(std::ceil((out.end_s - out.start_s) / dt));
    out.samples = std::max<std::size_t>(intervals, 1) + 1;
    out.step_s = (out.end_s - out.start_s) / static_cast<double>(out.samples - 1);
  }
  // Below a few hundred samples threads cost more than they save.
  threads = static_cast<unsigned>(std::min<std::size_t>(threads, std::max<std::size_t>(1, out.samples / 256)));
  split(out.samples, threads, [&](unsigned k, std::size_t first, std::size_t last) {
    run(workers_[k], trajectories, first, last, out, options.obstacles);
  });
  for (unsigned k = 0; k < threads; ++k) {
    for (std::size_t p = 0; p < out.robot_pairs.size(); ++p) merge(out.robot_pairs[p], workers_[k].robot_pairs[p]);
    for (std::size_t p = 0; p < out.obstacle_pairs.size(); ++p)
      merge(out.obstacle_pairs[p], workers_[k].obstacle_pairs[p]);
    out.halvings += workers_[k].halvings;
  }
  out.pair_evaluations = out.samples * (out.robot_pairs.size() + out.obstacle_pairs.size()) + out.halvings;
}

void TrajectoryChecker::check_advancing(std::span<const RobotTrajectory> trajectories, const CheckOptions& options,
                                        unsigned threads, CheckReport& out) {
  const std::size_t pairs = out.robot_pairs.size() + out.obstacle_pairs.size();
  // Below a few hundred pairs threads cost more than they save.
  threads = static_cast<unsigned>(std::min<std::size_t>(threads, std::max<std::size_t>(1, pairs / 256)));
  split(pairs, threads, [&](unsigned k, std::size_t first, std::size_t last) {
    advance(workers_[k], trajectories, first, last, options, out);
  });
  out.samples = 0;
  for (unsigned k = 0; k < threads; ++k) {
    out.pair_evaluations += workers_[k].evaluations;
    out.forced_steps += workers_[k].forced;
    out.samples = std::max(out.samples, workers_[k].busiest);
  }
  out.samples = std::max<std::size_t>(out.samples, 1);
}

void TrajectoryChecker::summarize(const CheckOptions& options, CheckReport& out) const {
  const CollisionModel& m = *model_;
  out.collided_pairs = 0;
  out.standing_contacts = 0;
  out.min_clearance_mm = std::numeric_limits<double>::infinity();
  auto standing = [&](std::size_t i) { return speed_[i] == 0; };
  for (std::size_t p = 0; p < out.robot_pairs.size(); ++p)
    out.robot_pairs[p].standing = standing(m.robot_pairs()[p].a) && standing(m.robot_pairs()[p].b);
  for (std::size_t p = 0; p < out.obstacle_pairs.size(); ++p) out.obstacle_pairs[p].standing = standing(m.obstacle_pairs()[p].robot);
  for (const auto* v : {&out.robot_pairs, &out.obstacle_pairs})
    for (const auto& o : *v) {
      if (o.standing && options.allow_standing_contacts) {
        out.standing_contacts += o.collided ? 1 : 0;
        continue;
      }
      out.collided_pairs += o.move_collided(options) ? 1 : 0;
      out.min_clearance_mm = std::min(out.min_clearance_mm, o.min_clearance_mm);
    }
}

void TrajectoryChecker::run(Worker& w, std::span<const RobotTrajectory> trajectories, std::size_t first,
                            std::size_t last, const CheckReport& shape, bool obstacles) const {
  const CollisionModel& m = *model_;
  const std::size_t n = m.size();
  w.poses.assign(n, Pose{std::numeric_limits<double>::quiet_NaN(), 0});
  w.segs.resize(n);
  w.mid.resize(n);
  w.half.resize(n);
  for (std::size_t i = 0; i < n; ++i) w.half[i] = 0.5 * m.robot(i).collision_length_mm();
  w.alpha.resize(n);
  w.beta.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    w.alpha[i] = AngleCursor(trajectories[i].alpha);
    w.beta[i] = AngleCursor(trajectories[i].beta);
  }
  w.robot_pairs.assign(shape.robot_pairs.size(), PairOutcome{});
  w.obstacle_pairs.assign(shape.obstacle_pairs.size(), PairOutcome{});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  w.prev_robot.assign(shape.robot_pairs.size(), nan);
  w.prev_obstacle.assign(shape.obstacle_pairs.size(), nan);
  w.halvings = 0;
  const auto rp = m.robot_pairs();
  const auto op = m.obstacle_pairs();
  auto segment_at = [&](std::size_t i, double t) {
    return m.robot(i).collision_segment({angle_at(trajectories[i].alpha, t), angle_at(trajectories[i].beta, t)});
  };

  // Each block also proves the interval that ends at its first sample (from the sample before).
  const std::size_t begin = first > 0 ? first - 1 : first;
  double t_prev = nan;
  for (std::size_t s = begin; s < last; ++s) {
    const double t = s + 1 == shape.samples ? shape.end_s : shape.start_s + static_cast<double>(s) * shape.step_s;
    const bool record = s >= first;  // the sample before the block is the previous block's to note
    const double dt = s > begin ? t - t_prev : 0;
    for (std::size_t i = 0; i < n; ++i) {
      const Pose p{w.alpha[i].at(t), w.beta[i].at(t)};
      if (p != w.poses[i]) {  // a robot standing still keeps its segment (NaN at start: always differs)
        w.poses[i] = p;
        w.segs[i] = m.robot(i).collision_segment(p);
        w.mid[i] = 0.5 * (w.segs[i].a + w.segs[i].b);
      }
    }
    for (std::size_t k = 0; k < rp.size(); ++k) {
      // Each segment lies within half its length of its midpoint, so the midpoints' distance minus
      // both half lengths and the limit is a lower bound of the clearance. When that bound beats
      // both the pair's smallest clearance so far and what the interval needs (its clearance can
      // shrink by at most the pair's travel), the exact distance can change nothing: skipped, and
      // the bound kept for the next interval.
      const RobotPair& p = rp[k];
      PairOutcome& o = w.robot_pairs[k];
      const double rate = speed_[p.a] + speed_[p.b];
      const double reach = w.half[p.a] + w.half[p.b] + p.limit_mm;
      const double need = std::max(rate * dt, o.min_clearance_mm);
      double& prev = w.prev_robot[k];
      if (prev >= 0 && need < std::numeric_limits<double>::infinity() && norm2(w.mid[p.a] - w.mid[p.b]) > (reach + need) * (reach + need) &&
          (o.collided || o.min_clearance_mm >= 0)) {
        prev = need;
        continue;
      }
      const double c = m.clearance(p, w.segs);
      if (record) note(o, c, t);
      if (s > begin) {
        const double c0 = prev >= 0 && prev + c < rate * dt ? segment_distance(segment_at(p.a, t_prev), segment_at(p.b, t_prev)) - p.limit_mm : prev;
        certify(o, [&](double tm) { return segment_distance(segment_at(p.a, tm), segment_at(p.b, tm)) - p.limit_mm; }, rate,
                t_prev, c0, t, c, 0, w.halvings);
      }
      prev = c;
    }
    if (obstacles)
      for (std::size_t k = 0; k < op.size(); ++k) {
        const ObstaclePair& p = op[k];
        PairOutcome& o = w.obstacle_pairs[k];
        const Segment& shape_k = m.obstacles()[p.obstacle].shape;
        const double c = m.clearance(p, w.segs);
        if (record) note(o, c, t);
        double& prev = w.prev_obstacle[k];
        if (s > begin)
          certify(o, [&](double tm) { return segment_distance(segment_at(p.robot, tm), shape_k) - p.limit_mm; },
                  speed_[p.robot], t_prev, prev, t, c, 0, w.halvings);
        prev = c;
      }
    t_prev = t;
  }
}

}  // namespace axon::fps::plan

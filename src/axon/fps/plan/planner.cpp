#include "axon/fps/plan/planner.hpp"

#include "axon/fps/plan/smooth.hpp"
#include "axon/fps/plan/stepper.hpp"
#include "axon/fps/plan/untangle.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <span>
#include <random>
#include <set>
#include <thread>

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

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

bool finite(Pose p) { return std::isfinite(p.alpha_deg) && std::isfinite(p.beta_deg); }

// The A half (forward) and the reversed B half, joined at the fold: B's points mirrored in time
// and shifted after A's duration.
std::vector<TimedAngle> join(const std::vector<TimedAngle>& a, double ta, const std::vector<TimedAngle>& b, double tb) {
  std::vector<TimedAngle> out = a;
  for (auto it = b.rbegin(); it != b.rend(); ++it) {
    const double t = ta + (tb - it->t_s);
    if (out.back().t_s >= t - 1e-9) {
      // Same instant (an arm that stopped exactly at the fold time): the angles agree.
      continue;
    }
    // An arm that holds still across the join needs no point where it does not change.
    if (out.size() >= 2 && out.back().deg == it->deg && out[out.size() - 2].deg == it->deg) {
      out.back().t_s = t;
      continue;
    }
    out.push_back({t, it->deg});
  }
  return out;
}

// Drops points in the middle of a run of equal angles (a still arm needs only both ends).
void drop_still_points(std::vector<TimedAngle>& pts) {
  std::vector<TimedAngle> out;
  for (std::size_t k = 0; k < pts.size(); ++k) {
    if (k > 0 && k + 1 < pts.size() && pts[k - 1].deg == pts[k].deg && pts[k + 1].deg == pts[k].deg) continue;
    out.push_back(pts[k]);
  }
  // A trailing point that repeats the angle before it adds nothing (the arm holds its last angle).
  while (out.size() >= 2 && out.back().deg == out[out.size() - 2].deg) out.pop_back();
  pts = std::move(out);
}

std::size_t count_unreached(const StepperResult& r) {
  return static_cast<std::size_t>(std::count(r.reached.begin(), r.reached.end(), false));
}

void repair_locally(const CollisionModel& model, std::vector<StepperRobot>& robots, StepperResult& best,
                    StepperOptions so, int tries, int rings, double fold_spread, std::size_t& runs);

// One half, re-run while robots get stuck: each retry puts every robot stuck so far in front (it
// steps first, the others yield to it) and draws a new seed; from the `relax_after`-th retry on, a
// stuck robot also gives up turning alpha in this half (its goal alpha becomes its start alpha:
// a pure beta fold), leaving the turn to the other half or to the middle phase. The run with the
// fewest robots stuck (then the shortest) is kept; `robots` holds the goals of that run.
StepperResult drive_with_retries(const CollisionModel& model, std::vector<StepperRobot>& robots, StepperOptions so,
                                 int retries, int relax_after, int local_tries, int local_rings, double fold_spread, bool untangle, std::size_t& runs) {
  StepperResult best = drive_to_goals(model, robots, so);
  ++runs;
  std::vector<StepperRobot> best_robots = robots;
  std::vector<bool> listed(robots.size(), false);
  for (int k = 0; k < retries && count_unreached(best) > 0; ++k) {
    for (std::size_t i = 0; i < robots.size(); ++i) {
      if (best.reached[i]) continue;
      if (!listed[i]) {
        listed[i] = true;
        so.first.push_back(static_cast<std::uint32_t>(i));
      }
      if (k >= relax_after) robots[i].goal.alpha_deg = robots[i].start.alpha_deg;
    }
    so.seed = so.seed * 6364136223846793005ULL + 1442695040888963407ULL;
    StepperResult r = drive_to_goals(model, robots, so);
    ++runs;
    const std::size_t a = count_unreached(r), b = count_unreached(best);
    if (a < b || (a == b && r.duration_s < best.duration_s)) {
      best = std::move(r);
      best_robots = robots;
    }
  }
  robots = std::move(best_robots);
  if (local_tries > 0 && count_unreached(best) > 0) {
    so.seed ^= 0x9e3779b97f4a7c15ULL;
    repair_locally(model, robots, best, so, local_tries, local_rings, fold_spread, runs);
  }
  if (untangle && count_unreached(best) > 0) untangle_to_fold(model, robots, best, so);
  return best;
}

// Local repair of a half: the robots still stuck and every robot within `rings` neighbour rings of
// them are planned again from their starts, with new seeds and the stuck robots in front, while
// the robots bordering that patch follow their paths of `best` (scripted: moving obstacles) and
// the rest do not matter. A run is taken over when it is clean (no scripted robot had to be run
// into) and leaves fewer of the patch stuck; its paths replace the patch's paths in `best`.
void repair_locally(const CollisionModel& model, std::vector<StepperRobot>& robots, StepperResult& best,
                    StepperOptions so, int tries, int rings, double fold_spread, std::size_t& runs) {
  const std::size_t n = robots.size();
  auto stuck_in = [&](const StepperResult& r, const std::vector<bool>& in) {
    std::size_t c = 0;
    for (std::size_t i = 0; i < n; ++i) c += (in[i] && !r.reached[i]) ? 1 : 0;
    return c;
  };
  for (int k = 0; k < tries && count_unreached(best) > 0; ++k) {
    // The patch (recomputed: it grows when a repair leaves robots stuck elsewhere).
    std::vector<bool> in(n, false), border(n, false);
    so.first.clear();
    for (std::size_t i = 0; i < n; ++i)
      if (!best.reached[i]) {
        in[i] = true;
        so.first.push_back(static_cast<std::uint32_t>(i));
      }
    for (int ring = 0; ring < rings; ++ring) {
      std::vector<bool> next = in;
      for (std::size_t i = 0; i < n; ++i)
        if (in[i])
          for (const std::uint32_t j : model.neighbours(i)) next[j] = true;
      in = std::move(next);
    }
    for (std::size_t i = 0; i < n; ++i)
      if (in[i])
        for (const std::uint32_t j : model.neighbours(i))
          if (!in[j]) border[j] = true;
    std::vector<StepperRobot> sub(n);
    std::mt19937_64 rng(so.seed);
    for (std::size_t i = 0; i < n; ++i) {
      if (robots[i].frozen || in[i]) {
        sub[i] = robots[i];
        // Any alpha is a fold: from the second try on, a stuck robot folds towards a random alpha
        // within `fold_spread` of where it starts (the turn to its other fold happens while folded).
        if (!robots[i].frozen && !best.reached[i] && k >= 1 && fold_spread > 0) {
          const AngleLimits& l = model.robot(i).limits();
          std::uniform_real_distribution<double> d(-fold_spread, fold_spread);
          sub[i].goal.alpha_deg = std::clamp(robots[i].start.alpha_deg + d(rng), l.alpha_min_deg, l.alpha_max_deg);
        }
      } else if (border[i]) {
        sub[i] = {robots[i].start, robots[i].goal, false, &best.paths[i]};
      } else {
        sub[i] = {robots[i].start, robots[i].start, true};
      }
    }
    so.seed = so.seed * 6364136223846793005ULL + 1442695040888963407ULL;
    StepperResult r = drive_to_goals(model, sub, so);
    ++runs;
    best.escapes += r.escapes;
    if (r.violations > 0 || stuck_in(r, in) >= stuck_in(best, in)) continue;
    double duration = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (in[i] && !robots[i].frozen) {
        robots[i].goal = sub[i].goal;
        best.paths[i] = std::move(r.paths[i]);
        best.end[i] = r.end[i];
        best.reached[i] = r.reached[i];
        best.blockers[i] = std::move(r.blockers[i]);
      }
      duration = std::max({duration, best.paths[i].alpha.back().t_s, best.paths[i].beta.back().t_s});
    }
    best.duration_s = duration;
  }
}

constexpr const char* kReverseStuck = "its target cannot be reached from the fold without a collision";

std::size_t firmware_points(const std::vector<TimedAngle>& pts) { return pts.empty() ? 0 : pts.size() - 1; }

// Where every robot stands still (frozen or held) and aims, while the problem is set up.
struct Setup {
  Plan& plan;
  std::vector<Pose>& target;
  std::vector<bool>& still;
  std::span<const Pose> current;

  void hold(std::size_t i, const std::string& why, std::vector<std::int32_t> blockers = {}) {
    RobotPlan& r = plan.robots[i];
    if (r.status == RobotPlan::Status::held) {
      r.reason += "; " + why;
      r.blockers.insert(r.blockers.end(), blockers.begin(), blockers.end());
    } else if (r.status != RobotPlan::Status::frozen) {
      r = {RobotPlan::Status::held, {}, why, std::move(blockers)};
    }
    still[i] = true;
    target[i] = current[i];
  }
};

// Robots that start in contact (with each other or with a fixed obstacle) are held where they
// are: no move out of a contact can be certified, and standing still keeps it from getting worse.
// Both robots of a pair are held; everyone else is planned around them.
void hold_start_contacts(const CollisionModel& model, Setup& s) {
  std::vector<Segment> segs(model.size());
  std::vector<Contact> contacts;
  model.segments(s.current, segs);
  model.find_contacts(segs, contacts);
  for (const auto& c : contacts) {
    if (c.kind == Contact::Kind::robot) {
      const auto ia = model.robot(c.a).id(), ib = model.robot(c.b).id();
      s.hold(c.a, fmt::format("starts in contact with robot {} (clearance {:.3f} mm at the full buffer)", ib, c.clearance_mm), {ib});
      s.hold(c.b, fmt::format("starts in contact with robot {} (clearance {:.3f} mm at the full buffer)", ia, c.clearance_mm), {ia});
    } else {
      s.hold(c.a, fmt::format("starts in contact with {} (clearance {:.3f} mm at the full buffer)", model.obstacles()[c.b].name,
                              c.clearance_mm));
    }
  }
}

// Robots boxed in by fixed obstacles (a flood fill of their own angle space finds no fold with only
// the obstacles present): boxed in at the start, held; at the target, parked at the fold.
void set_aside_boxed_in(const CollisionModel& model, Setup& s, const StepperOptions& so, const std::function<Pose(std::size_t)>& park_pose) {
  for (std::size_t i = 0; i < model.size(); ++i) {
    if (s.still[i]) continue;
    const double fold = park_pose(i).beta_deg;
    if (auto around = fold_blocked_by_obstacles(model, i, s.current[i], fold, so); !around.empty()) {
      s.hold(i, fmt::format("no fold is reachable from its start: boxed in by {} and its angle limits (flood fill of its "
                            "angle space with only the fixed obstacles)",
                            fmt::join(around, ", ")));
    } else if (s.plan.robots[i].status == RobotPlan::Status::reached) {
      if (auto around_t = fold_blocked_by_obstacles(model, i, s.target[i], fold, so); !around_t.empty()) {
        s.plan.robots[i] = {RobotPlan::Status::parked, {},
                            fmt::format("its target cannot be reached from any fold: boxed in by {} and its angle "
                                        "limits (flood fill of its angle space with only the fixed obstacles)",
                                        fmt::join(around_t, ", ")),
                            {}};
        s.target[i] = park_pose(i);
      }
    }
  }
}

}  // namespace

Result<Plan> plan_moves(const CollisionModel& model, const PlanRequest& request, const PlannerOptions& o) {
  const auto t_start = Clock::now();
  const std::size_t n = model.size();
  if (request.current.size() != n || request.target.size() != n || (!request.frozen.empty() && request.frozen.size() != n))
    return make_error(PlanErrc::bad_trajectory,
                      fmt::format("plan request: {} current poses, {} targets, {} frozen flags for {} robots",
                                  request.current.size(), request.target.size(), request.frozen.size(), n));
  for (std::size_t i = 0; i < n; ++i)
    if (!finite(request.current[i]) || !finite(request.target[i]))
      return make_error(PlanErrc::bad_trajectory, fmt::format("plan request: robot {}: angle not finite", model.robot(i).id()));
  if (!(o.speed.alpha_deg_s > 0) || !(o.speed.beta_deg_s > 0) || !(o.step_deg > 0))
    return make_error(PlanErrc::bad_trajectory, "plan request: speeds and step must be positive");

  Plan plan;
  plan.robots.resize(n);
  std::vector<Pose> target = request.target;
  std::vector<bool> still(n, false);  // frozen or held: stays at the current pose throughout
  for (std::size_t i = 0; i < n; ++i) {
    plan.robots[i].status = RobotPlan::Status::reached;
    if (!request.frozen.empty() && request.frozen[i]) {
      plan.robots[i].status = RobotPlan::Status::frozen;
      still[i] = true;
      target[i] = request.current[i];
    }
  }
  Setup setup{plan, target, still, request.current};
  hold_start_contacts(model, setup);
  if (o.safe_zone) plan.safe_zone = check_safe_zone(model, request.target, {still, request.point_fibre}, *o.safe_zone);
  std::vector<Segment> segs(n);
  std::vector<Contact> contacts;

  const double dt = o.step_deg / std::max(o.speed.alpha_deg_s, o.speed.beta_deg_s);
  auto fold_beta = [&](std::size_t i) {
    const AngleLimits& l = model.robot(i).limits();
    return std::clamp(o.fold_beta_deg, l.beta_min_deg, l.beta_max_deg);
  };
  auto park_pose = [&](std::size_t i) { return Pose{request.current[i].alpha_deg, fold_beta(i)}; };
  auto ids_of = [&](const std::vector<std::uint32_t>& v) {
    std::vector<std::int32_t> out;
    for (auto j : v) out.push_back(model.robot(j).id());
    return out;
  };

  // Targets outside the limits or in contact with each other, with obstacles or with robots that
  // stay: the later robot (or the one that moves) is parked; a parked robot whose fold still
  // touches a robot that stays is held.
  for (std::size_t i = 0; i < n; ++i) {
    if (still[i]) continue;
    if (!model.robot(i).within_limits(target[i])) {
      plan.robots[i] = {RobotPlan::Status::parked, {}, "target outside the angle limits", {}};
      target[i] = park_pose(i);
    }
  }
  StepperOptions so;
  so.dt_s = dt;
  so.alpha_step_deg = o.speed.alpha_deg_s * dt;
  so.beta_step_deg = o.speed.beta_deg_s * dt;
  so.margin_mm = o.margin_mm;
  so.max_duration_s = o.max_half_s;
  so.stop_avoid_deg = o.stop_avoid_deg;
  so.give_up_after = o.give_up_after;
  so.stall_s = o.stall_s;
  set_aside_boxed_in(model, setup, so, park_pose);
  auto settle_targets = [&]() {
    for (std::size_t guard = 0; guard < 4 * n + 4; ++guard) {
      model.segments(target, segs);
      model.find_contacts(segs, contacts);
      // Bodies that all stay: a contact they started in (held), nothing to settle.
      std::erase_if(contacts, [&](const Contact& c) { return still[c.a] && (c.kind != Contact::Kind::robot || still[c.b]); });
      if (contacts.empty()) return;
      for (const auto& c : contacts) {
        std::size_t victim = c.a;
        std::string why;
        std::vector<std::int32_t> blockers;
        if (c.kind == Contact::Kind::robot) {
          victim = still[c.b] ? c.a : c.b;
          const std::size_t other = victim == c.a ? c.b : c.a;
          why = fmt::format("target collides with robot {} ({:.3f} mm)", model.robot(other).id(), c.clearance_mm);
          blockers.push_back(model.robot(other).id());
        } else {
          why = fmt::format("target collides with {} ({:.3f} mm)", model.obstacles()[c.b].name, c.clearance_mm);
        }
        if (still[victim]) continue;  // two robots that stay: a contact they started in (held)
        if (target[victim] == park_pose(victim)) {
          // Already folded: the other one gives way if it can.
          const std::size_t other = victim == c.a ? c.b : c.a;
          if (c.kind == Contact::Kind::robot && !still[other] && target[other] != park_pose(other)) {
            plan.robots[other] = {RobotPlan::Status::parked, {},
                                  fmt::format("target collides with robot {} (parked)", model.robot(victim).id()),
                                  {model.robot(victim).id()}};
            target[other] = park_pose(other);
            break;
          }
          plan.robots[victim] = {RobotPlan::Status::held, {}, "its folded pose collides with a robot that stays", blockers};
          still[victim] = true;
          target[victim] = request.current[victim];
        } else {
          plan.robots[victim] = {RobotPlan::Status::parked, {}, why, blockers};
          target[victim] = park_pose(victim);
        }
        break;  // re-evaluate after each change
      }
    }
  };
  settle_targets();
  plan.stats.setup_s = seconds_since(t_start);


  StepperResult ra, rb, rm;
  std::vector<StepperRobot> fa(n), fb(n);
  double search_s = 0;
  const int max_rounds = std::max(1, o.retries + 1) + 8;
  // Robots whose fold alpha was given up in a half (a pure beta fold from the start or the target):
  // the fold is then at the current (A) or the target (B) alpha.
  std::vector<bool> relax_a(n, false), relax_b(n, false);
  for (int round = 0;; ++round) {
    // The fold's alpha: alpha turns towards the target during B (as far as B's beta work allows)
    // and the rest during A.
    double tb = 0;
    for (std::size_t i = 0; i < n; ++i)
      if (!still[i]) tb = std::max(tb, std::abs(target[i].beta_deg - fold_beta(i)) / o.speed.beta_deg_s);
    const double alpha_budget = tb * o.speed.alpha_deg_s;
    for (std::size_t i = 0; i < n; ++i) {
      if (still[i]) {
        fa[i] = fb[i] = {request.current[i], request.current[i], true};
        continue;
      }
      const double at = target[i].alpha_deg, ac = request.current[i].alpha_deg;
      double f = at + std::clamp(ac - at, -alpha_budget, alpha_budget);
      if (o.fold_stop_gap_deg > 0) {
        // A fold alpha right at a stop leaves a robot that must dodge only one way to turn.
        const AngleLimits& l = model.robot(i).limits();
        if (l.alpha_max_deg - l.alpha_min_deg > 2 * o.fold_stop_gap_deg)
          f = std::clamp(f, l.alpha_min_deg + o.fold_stop_gap_deg, l.alpha_max_deg - o.fold_stop_gap_deg);
      }
      if (relax_b[i]) f = at;
      if (relax_a[i]) f = ac;
      fa[i] = {request.current[i], {f, fold_beta(i)}, false};
      fb[i] = {target[i], {relax_b[i] ? at : f, fold_beta(i)}, false};
    }
    StepperOptions sa = so, sb = so;
    sa.seed = o.seed * 2 + 1 + static_cast<std::uint64_t>(round) * 7919;
    sb.seed = o.seed * 2 + 2 + static_cast<std::uint64_t>(round) * 7919;
    const auto t0 = Clock::now();
    std::size_t runs_a = 0, runs_b = 0;
    if (o.parallel) {
      std::thread worker([&] { ra = drive_with_retries(model, fa, sa, o.half_retries, o.relax_after, o.local_retries, o.local_rings, o.fold_spread_deg, o.untangle, runs_a); });
      rb = drive_with_retries(model, fb, sb, o.half_retries, o.relax_after, o.local_retries, o.local_rings, o.fold_spread_deg, o.untangle, runs_b);
      worker.join();
    } else {
      ra = drive_with_retries(model, fa, sa, o.half_retries, o.relax_after, o.local_retries, o.local_rings, o.fold_spread_deg, o.untangle, runs_a);
      rb = drive_with_retries(model, fb, sb, o.half_retries, o.relax_after, o.local_retries, o.local_rings, o.fold_spread_deg, o.untangle, runs_b);
    }
    // Folds given up by B: A turns those robots to the target alpha instead (one more A run), so
    // that no middle phase is needed for them unless A gives up the turn as well.
    bool rerun_a = false;
    for (std::size_t i = 0; i < n; ++i) {
      if (still[i]) continue;
      if (fa[i].goal.alpha_deg == request.current[i].alpha_deg && fa[i].goal.alpha_deg != target[i].alpha_deg &&
          fb[i].goal.alpha_deg != fa[i].goal.alpha_deg)
        relax_a[i] = true;
      if (fb[i].goal.alpha_deg == target[i].alpha_deg && fb[i].goal.alpha_deg != fa[i].goal.alpha_deg && !relax_a[i]) {
        relax_b[i] = true;
        fa[i].goal.alpha_deg = target[i].alpha_deg;
        rerun_a = true;
      }
    }
    if (rerun_a) {
      sa.seed += 104729;
      ra = drive_with_retries(model, fa, sa, o.half_retries, o.relax_after, o.local_retries, o.local_rings, o.fold_spread_deg, o.untangle, runs_a);
      for (std::size_t i = 0; i < n; ++i)
        if (!still[i] && fa[i].goal.alpha_deg == request.current[i].alpha_deg &&
            fb[i].goal.alpha_deg != fa[i].goal.alpha_deg)
          relax_a[i] = true;
    }
    search_s += seconds_since(t0);
    plan.stats.rounds = static_cast<std::size_t>(round) + 1;
    plan.stats.escapes += ra.escapes + rb.escapes;

    bool changed = false;
    for (std::size_t i = 0; i < n; ++i) {
      if (still[i]) continue;
      if (!ra.reached[i]) {
        plan.robots[i] = {RobotPlan::Status::held, {}, "cannot fold from its current pose without a collision",
                          ids_of(ra.blockers[i])};
        still[i] = true;
        target[i] = request.current[i];
        changed = true;
      } else if (!rb.reached[i]) {
        plan.robots[i] = {RobotPlan::Status::parked, {}, kReverseStuck, ids_of(rb.blockers[i])};
        target[i] = park_pose(i);
        changed = true;
      }
    }
    if (!changed) {
      // Middle phase: robots whose A and B folds differ turn alpha from one to the other while
      // folded. Folded robots cannot touch each other, but a held or frozen neighbour may stand
      // unfolded, so this runs through the engine too (everyone else stands still).
      std::vector<StepperRobot> fm(n);
      bool any_m = false;
      for (std::size_t i = 0; i < n; ++i) {
        const Pose from{ra.paths[i].alpha.back().deg, ra.paths[i].beta.back().deg};
        const Pose to{rb.paths[i].alpha.back().deg, rb.paths[i].beta.back().deg};
        fm[i] = {from, to, still[i] || from == to};
        any_m = any_m || !fm[i].frozen;
      }
      rm = {};
      if (any_m) {
        StepperOptions sm = so;
        sm.seed = o.seed * 2 + 77 + static_cast<std::uint64_t>(round) * 7919;
        const auto tm0 = Clock::now();
        rm = drive_to_goals(model, fm, sm);
        search_s += seconds_since(tm0);
        for (std::size_t i = 0; i < n; ++i)
          if (!rm.reached[i]) {
            plan.robots[i] = {RobotPlan::Status::parked, {}, "cannot turn to its fold alpha while folded",
                              ids_of(rm.blockers[i])};
            target[i] = park_pose(i);
            relax_a[i] = relax_b[i] = false;
            changed = true;
          }
      }
    }
    if (!changed) break;
    if (round + 1 >= max_rounds)
      return make_error(PlanErrc::robot_collision,
                        fmt::format("planner did not settle after {} rounds: robots keep blocking each other", max_rounds));
    settle_targets();
  plan.stats.setup_s = seconds_since(t_start);
  }

  // Third phase for robots parked because the reverse half got stuck: with everyone else at rest
  // at the end, each tries forwards from its fold to its target. Robots that do not get there
  // stay folded, and the others are re-planned without them (they were certified against it).
  // Append the middle phase to A.
  const double ta0 = ra.duration_s, tb = rb.duration_s;
  const double tm = rm.paths.empty() ? 0.0 : rm.duration_s;
  if (!rm.paths.empty())
    for (std::size_t i = 0; i < n; ++i)
      for (auto [arm, m] : {std::pair{&ra.paths[i].alpha, &rm.paths[i].alpha}, std::pair{&ra.paths[i].beta, &rm.paths[i].beta}}) {
        if (m->size() < 2) continue;
        if (arm->back().t_s < ta0) arm->push_back({ta0, arm->back().deg});
        for (std::size_t k = 1; k < m->size(); ++k) arm->push_back({ta0 + (*m)[k].t_s, (*m)[k].deg});
      }
  const double ta = ta0 + tm;
  plan.stats.middle_s = tm;
  std::vector<bool> in_c(n, false);
  for (std::size_t i = 0; i < n; ++i)
    in_c[i] = plan.robots[i].status == RobotPlan::Status::parked && plan.robots[i].reason == kReverseStuck &&
              model.robot(i).within_limits(request.target[i]);
  StepperResult rc;
  bool any_c = std::find(in_c.begin(), in_c.end(), true) != in_c.end();
  for (int pass = 0; any_c && pass < 4; ++pass) {
    std::vector<StepperRobot> fc(n);
    for (std::size_t i = 0; i < n; ++i) {
      const Pose end{rb.paths[i].alpha.front().deg, rb.paths[i].beta.front().deg};  // B starts at the end pose
      fc[i] = in_c[i] ? StepperRobot{end, request.target[i], false} : StepperRobot{end, end, true};
    }
    StepperOptions sc = so;
    sc.seed = o.seed * 2 + 99 + static_cast<std::uint64_t>(pass);
    const auto t0 = Clock::now();
    rc = drive_to_goals(model, fc, sc);
    search_s += seconds_since(t0);
    plan.stats.escapes += rc.escapes;
    bool dropped = false;
    for (std::size_t i = 0; i < n; ++i)
      if (in_c[i] && !rc.reached[i]) {
        in_c[i] = false;
        dropped = true;
      }
    any_c = std::find(in_c.begin(), in_c.end(), true) != in_c.end();
    if (!dropped) break;
    if (!any_c) rc = {};
  }
  if (!any_c) rc = {};

  // Join the halves (and the third phase).
  plan.trajectories.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    RobotTrajectory& t = plan.trajectories[i];
    t.alpha = join(ra.paths[i].alpha, ta, rb.paths[i].alpha, tb);
    t.beta = join(ra.paths[i].beta, ta, rb.paths[i].beta, tb);
    if (any_c && in_c[i]) {
      for (auto [arm, c] : {std::pair{&t.alpha, &rc.paths[i].alpha}, std::pair{&t.beta, &rc.paths[i].beta}})
        for (const auto& pt : *c) {
          const double when = ta + tb + pt.t_s;  // after A, the middle phase and B
          if (arm->back().t_s >= when - 1e-9) continue;
          arm->push_back({when, pt.deg});
        }
      plan.robots[i] = {RobotPlan::Status::reached, {}, {}, {}};
    }
    drop_still_points(t.alpha);
    drop_still_points(t.beta);
    plan.robots[i].end = {t.alpha.back().deg, t.beta.back().deg};
    if (plan.robots[i].status == RobotPlan::Status::parked || plan.robots[i].status == RobotPlan::Status::held) ++plan.not_reached;
  }
  plan.stats.search_s = search_s;

  // Arms the engine left jagged (dithering, stop-and-go) are shortened by certified shortcuts;
  // then everything is simplified where it pays, and verified; robots in a pair the checker flags
  // fall back one layer (simplified -> smoothed -> exact, which the engine certified), until the
  // checker is satisfied.
  std::vector<std::vector<RobotTrajectory>> layers;
  layers.push_back(plan.trajectories);  // becomes the simplified layer
  std::vector<bool> smoothed(n, false);
  if (o.smooth_points > 0) {
    SmoothOptions sm;
    sm.min_points = o.smooth_points;
    sm.min_clearance_mm = o.smooth_clearance_mm;
    const auto t_smooth = Clock::now();
    smooth_arms(model, layers.front(), sm, smoothed);
    plan.stats.smooth_s = seconds_since(t_smooth);
    if (std::find(smoothed.begin(), smoothed.end(), true) != smoothed.end()) layers.push_back(layers.front());
  }
  layers.push_back(plan.trajectories);  // exact
  const std::vector<RobotTrajectory>& base = layers[1];  // smoothed, or exact when nothing was
  std::vector<bool> simplified(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    RobotTrajectory& t = layers.front()[i];
    const bool over = firmware_points(t.alpha) > o.max_points || firmware_points(t.beta) > o.max_points;
    if (o.simplify_deg <= 0 && !over) continue;
    double tol = std::max(o.simplify_deg, 1e-3);
    for (;;) {
      auto a = simplify_arm(base[i].alpha, tol), b = simplify_arm(base[i].beta, tol);
      if ((firmware_points(a) <= o.max_points && firmware_points(b) <= o.max_points) || tol > 10) {
        if (a.size() < t.alpha.size() || b.size() < t.beta.size()) {
          t.alpha = std::move(a);
          t.beta = std::move(b);
          simplified[i] = true;
        }
        break;
      }
      tol *= 2;
    }
  }

  const auto t_check = Clock::now();
  std::vector<std::size_t> level(n, 0);
  if (o.verify) {
    CheckOptions check = o.check;
    check.allow_standing_contacts = true;  // robots held where they started in contact
    AXON_TRY(checks, verify_with_fallbacks(model, layers, check, plan.trajectories, level, plan.check));
    plan.stats.checks = checks;
    plan.verified = plan.check.ok();
  } else {
    plan.trajectories = layers.front();
  }
  const std::size_t exact_level = layers.size() - 1;
  for (std::size_t i = 0; i < n; ++i) {
    simplified[i] = simplified[i] && level[i] == 0;
    smoothed[i] = smoothed[i] && level[i] < exact_level;
  }
  plan.stats.check_s = seconds_since(t_check);

  std::vector<std::size_t> counts;
  for (std::size_t i = 0; i < n; ++i) {
    const RobotTrajectory& t = plan.trajectories[i];
    plan.stats.simplified += simplified[i] ? 1 : 0;
    plan.stats.smoothed += smoothed[i] ? 1 : 0;
    for (const auto* arm : {&t.alpha, &t.beta}) {
      const std::size_t c = firmware_points(*arm);
      if (c == 0) continue;
      counts.push_back(c);
      plan.stats.max_points = std::max(plan.stats.max_points, c);
    }
    plan.stats.max_alpha_speed = std::max(plan.stats.max_alpha_speed, max_speed(t.alpha));
    plan.stats.max_beta_speed = std::max(plan.stats.max_beta_speed, max_speed(t.beta));
    plan.stats.duration_s = std::max({plan.stats.duration_s, t.alpha.back().t_s, t.beta.back().t_s});
  }
  if (!counts.empty()) {
    std::nth_element(counts.begin(), counts.begin() + static_cast<std::ptrdiff_t>(counts.size() / 2), counts.end());
    plan.stats.median_points = counts[counts.size() / 2];
  }
  plan.stats.plan_s = seconds_since(t_start);
  return plan;
}

}  // namespace axon::fps::plan

#include "axon/fps/plan/phases.hpp"
#include "axon/core/clock.hpp"

#include "axon/fps/plan/half.hpp"
#include "axon/fps/plan/smooth.hpp"
#include "axon/fps/plan/untangle.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <span>
#include <string>
#include <thread>

// Helpers of this file only. A named namespace: in a unity build this file shares a translation
// unit with the other planner sources, whose anonymous namespaces would merge with one here.
namespace axon::fps::plan::phases::detail {

using Clock = std::chrono::steady_clock;

bool finite(Pose p) { return std::isfinite(p.alpha_deg) && std::isfinite(p.beta_deg); }

bool any_of(const std::vector<bool>& v) { return std::find(v.begin(), v.end(), true) != v.end(); }

std::size_t firmware_points(const std::vector<TimedAngle>& pts) { return pts.empty() ? 0 : pts.size() - 1; }

// The seed of a run: 2s + offset, plus the round's stride.
std::uint64_t run_seed(std::uint64_t seed, std::uint64_t offset, int round) {
  return seed * 2 + offset + static_cast<std::uint64_t>(round) * kRoundSeedStride;
}

// The A half (forwards) and the B half reversed, joined at the fold: B's points mirrored in time
// and shifted to start at `ta`, A's duration.
std::vector<TimedAngle> join(const std::vector<TimedAngle>& a, double ta, const std::vector<TimedAngle>& b, double tb) {
  std::vector<TimedAngle> out = a;
  for (auto it = b.rbegin(); it != b.rend(); ++it) {
    const double t = ta + (tb - it->t_s);
    // At the same instant as the last point (an arm stopped right at the fold time): same angle.
    if (out.back().t_s >= t - kSameInstantS) continue;
    // An arm that keeps still over the join: move the end of its still run instead of adding a point.
    if (out.size() >= 2 && out.back().deg == it->deg && out[out.size() - 2].deg == it->deg) {
      out.back().t_s = t;
      continue;
    }
    out.push_back({t, it->deg});
  }
  return out;
}

// Every robot's A (with the middle) and reversed B, B from `tb_start` on.
std::vector<RobotTrajectory> joined_paths(const Search& s, double tb_start, double tb) {
  std::vector<RobotTrajectory> out(s.a.paths.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i].alpha = join(s.a.paths[i].alpha, tb_start, s.b.paths[i].alpha, tb);
    out[i].beta = join(s.a.paths[i].beta, tb_start, s.b.paths[i].beta, tb);
  }
  return out;
}

// The largest shift of reversed B before `ta` that moves no robot in B before it has arrived in A.
double most_shift(const Search& s, double ta, double tb) {
  double most = ta;
  for (std::size_t i = 0; i < s.a.paths.size(); ++i)
    most = std::min(most, ta - end_time(s.a.paths[i]) + (tb - end_time(s.b.paths[i])));
  return std::max(0.0, most);
}

// Removes the inner points of every run of equal angles, and a last point that only repeats the
// one before it (the arm keeps its last angle anyway).
void drop_still_points(std::vector<TimedAngle>& pts) {
  std::vector<TimedAngle> out;
  for (std::size_t k = 0; k < pts.size(); ++k) {
    if (k > 0 && k + 1 < pts.size() && pts[k - 1].deg == pts[k].deg && pts[k + 1].deg == pts[k].deg) continue;
    out.push_back(pts[k]);
  }
  while (out.size() >= 2 && out.back().deg == out[out.size() - 2].deg) out.pop_back();
  pts = std::move(out);
}

// Where robots stand still (frozen or held) and aim while the problem is prepared.
struct Setup {
  Plan& plan;
  std::vector<Pose>& target;
  std::vector<bool>& still;
  std::span<const Pose> current;

  // Robot i stays at its current pose (a second reason is appended to the first).
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

// Both robots of a pair that starts in contact, and a robot that starts in contact with an
// obstacle, are held: a move out of a contact cannot be certified, standing still keeps it as it is.
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

// Robots the fixed obstacles box in (with only the obstacles present, a flood fill of the robot's
// angle space reaches no fold): at the start, held; at the target, parked at the fold.
void set_aside_boxed_in(const Context& ctx, Setup& s) {
  const CollisionModel& model = ctx.model;
  for (std::size_t i = 0; i < model.size(); ++i) {
    if (s.still[i]) continue;
    const double fold = ctx.park_pose(i).beta_deg;
    if (auto around = fold_blocked_by_obstacles(model, i, s.current[i], fold, ctx.engine); !around.empty()) {
      s.hold(i, fmt::format("no fold is reachable from its start: boxed in by {} and its angle limits (flood fill of its "
                            "angle space with only the fixed obstacles)",
                            fmt::join(around, ", ")));
    } else if (s.plan.robots[i].status == RobotPlan::Status::reached) {
      if (auto around_t = fold_blocked_by_obstacles(model, i, s.target[i], fold, ctx.engine); !around_t.empty()) {
        s.plan.robots[i] = {RobotPlan::Status::parked, {},
                            fmt::format("its target cannot be reached from any fold: boxed in by {} and its angle "
                                        "limits (flood fill of its angle space with only the fixed obstacles)",
                                        fmt::join(around_t, ", ")),
                            {}};
        s.target[i] = ctx.park_pose(i);
      }
    }
  }
}

// One target contact settled, if its robot can change (returns whether it did): see settle_targets.
bool settle_contact(const Context& ctx, Work& w, const Contact& c) {
  const CollisionModel& model = ctx.model;
  std::size_t victim = c.a;
  std::string why;
  std::vector<std::int32_t> blockers;
  if (c.kind == Contact::Kind::robot) {
    victim = w.still[c.b] ? c.a : c.b;
    const std::size_t other = victim == c.a ? c.b : c.a;
    why = fmt::format("target collides with robot {} ({:.3f} mm)", model.robot(other).id(), c.clearance_mm);
    blockers.push_back(model.robot(other).id());
  } else {
    why = fmt::format("target collides with {} ({:.3f} mm)", model.obstacles()[c.b].name, c.clearance_mm);
  }
  if (w.still[victim]) return false;  // two robots that stay: a contact they started in (held)
  if (w.target[victim] == ctx.park_pose(victim)) {
    // Folded already: the other robot makes way if it moves and is not folded itself.
    const std::size_t other = victim == c.a ? c.b : c.a;
    if (c.kind == Contact::Kind::robot && !w.still[other] && w.target[other] != ctx.park_pose(other)) {
      w.plan.robots[other] = {RobotPlan::Status::parked, {},
                              fmt::format("target collides with robot {} (parked)", model.robot(victim).id()),
                              {model.robot(victim).id()}};
      w.target[other] = ctx.park_pose(other);
      return true;
    }
    w.plan.robots[victim] = {RobotPlan::Status::held, {}, "its folded pose collides with a robot that stays", blockers};
    w.still[victim] = true;
    w.target[victim] = ctx.request.current[victim];
  } else {
    w.plan.robots[victim] = {RobotPlan::Status::parked, {}, why, blockers};
    w.target[victim] = ctx.park_pose(victim);
  }
  return true;
}

// Half A's fold of robot i (alpha; beta is the fold beta), before the relax flags.
double fold_alpha(const Context& ctx, const Work& w, std::size_t i, double alpha_budget) {
  const double at = w.target[i].alpha_deg, ac = ctx.request.current[i].alpha_deg;
  double f = at + std::clamp(ac - at, -alpha_budget, alpha_budget);
  const double gap = ctx.options.fold_stop_gap_deg;
  if (gap > 0) {
    // At a stop, a robot that has to dodge can only turn one way.
    const AngleLimits& l = ctx.model.robot(i).limits();
    if (l.alpha_max_deg - l.alpha_min_deg > 2 * gap) f = std::clamp(f, l.alpha_min_deg + gap, l.alpha_max_deg - gap);
  }
  return f;
}

// After both halves: robots whose A fold was given up (at the current alpha while B's differs) are
// marked relaxed in A; robots whose B fold was given up (at the target alpha) are marked relaxed
// in B, and A is to turn them to the target alpha instead. Returns whether A must run again.
bool move_given_up_folds(const Context& ctx, const Work& w, Folds& f) {
  bool rerun_a = false;
  for (std::size_t i = 0; i < ctx.size(); ++i) {
    if (w.still[i]) continue;
    const double ac = ctx.request.current[i].alpha_deg, at = w.target[i].alpha_deg;
    if (f.a[i].goal.alpha_deg == ac && f.a[i].goal.alpha_deg != at && f.b[i].goal.alpha_deg != f.a[i].goal.alpha_deg)
      f.relax_a[i] = true;
    if (f.b[i].goal.alpha_deg == at && f.b[i].goal.alpha_deg != f.a[i].goal.alpha_deg && !f.relax_a[i]) {
      f.relax_b[i] = true;
      f.a[i].goal.alpha_deg = at;
      rerun_a = true;
    }
  }
  return rerun_a;
}

// The middle phase's robots: from A's end to B's end, frozen where they agree (and the still ones).
std::vector<StepperRobot> middle_robots(const Work& w, const Search& s, bool& any) {
  const std::size_t n = w.still.size();
  std::vector<StepperRobot> fm(n);
  any = false;
  for (std::size_t i = 0; i < n; ++i) {
    const Pose from{s.a.paths[i].alpha.back().deg, s.a.paths[i].beta.back().deg};
    const Pose to{s.b.paths[i].alpha.back().deg, s.b.paths[i].beta.back().deg};
    fm[i] = {from, to, w.still[i] || from == to};
    any = any || !fm[i].frozen;
  }
  return fm;
}

// The middle phase appended to half A's paths (from A's duration on).
// Robot i's A path with its middle-phase turn appended, the turn starting at `start`.
RobotTrajectory with_middle(const RobotTrajectory& a, const RobotTrajectory& middle, double start) {
  RobotTrajectory out = a;
  for (auto [arm, m] : {std::pair{&out.alpha, &middle.alpha}, std::pair{&out.beta, &middle.beta}}) {
    if (m->size() < 2) continue;
    if (arm->back().t_s < start) arm->push_back({start, arm->back().deg});
    for (std::size_t k = 1; k < m->size(); ++k) arm->push_back({start + (*m)[k].t_s, (*m)[k].deg});
  }
  return out;
}

bool turns_in_middle(const Search& s, std::size_t i) {
  return !s.middle.paths.empty() && (s.middle.paths[i].alpha.size() > 1 || s.middle.paths[i].beta.size() > 1);
}

// The middle phase appended to A, robot i's turn from start[i] on; returns when A and the middle
// have ended (A's duration at least).
double append_middle(Search& s, const std::vector<double>& start) {
  double end = s.a.duration_s;
  for (std::size_t i = 0; i < s.a.paths.size(); ++i) {
    if (!turns_in_middle(s, i)) continue;
    s.a.paths[i] = with_middle(s.a.paths[i], s.middle.paths[i], start[i]);
    end = std::max(end, end_time(s.a.paths[i]));
  }
  return end;
}

// The finish of robot i appended to its joined trajectory (from `t0` on, after A, middle and B).
void append_finish(RobotTrajectory& t, const RobotTrajectory& finish, double t0) {
  for (auto [arm, c] : {std::pair{&t.alpha, &finish.alpha}, std::pair{&t.beta, &finish.beta}})
    for (const auto& pt : *c) {
      const double when = t0 + pt.t_s;
      if (arm->back().t_s >= when - kSameInstantS) continue;
      arm->push_back({when, pt.deg});
    }
}

// Robot i's simplified trajectory (from `base`), into `t` when it has fewer points; the tolerance
// doubles from simplify_deg while an arm has more than max_points. Returns whether it was taken.
bool simplify_robot(const PlannerOptions& o, const RobotTrajectory& base, RobotTrajectory& t) {
  const bool over = firmware_points(t.alpha) > o.max_points || firmware_points(t.beta) > o.max_points;
  if (o.simplify_deg <= 0 && !over) return false;
  for (double tol = std::max(o.simplify_deg, kSimplifyMinToleranceDeg);; tol *= 2) {
    auto a = simplify_arm(base.alpha, tol), b = simplify_arm(base.beta, tol);
    if ((firmware_points(a) <= o.max_points && firmware_points(b) <= o.max_points) || tol > kSimplifyMaxToleranceDeg) {
      if (a.size() < t.alpha.size() || b.size() < t.beta.size()) {
        t.alpha = std::move(a);
        t.beta = std::move(b);
        return true;
      }
      return false;
    }
  }
}

}  // namespace axon::fps::plan::phases::detail

namespace axon::fps::plan::phases {

using detail::Clock;

double Context::fold_beta(std::size_t i) const {
  const AngleLimits& l = model.robot(i).limits();
  return std::clamp(options.fold_beta_deg, l.beta_min_deg, l.beta_max_deg);
}

Pose Context::park_pose(std::size_t i) const { return Pose{request.current[i].alpha_deg, fold_beta(i)}; }

std::vector<std::int32_t> Context::ids_of(const std::vector<std::uint32_t>& indices) const {
  std::vector<std::int32_t> out;
  for (auto j : indices) out.push_back(model.robot(j).id());
  return out;
}

Context make_context(const CollisionModel& model, const PlanRequest& request, const PlannerOptions& o,
                     std::chrono::steady_clock::time_point started) {
  const double dt = o.step_deg / std::max(o.speed.alpha_deg_s, o.speed.beta_deg_s);
  StepperOptions so;
  so.dt_s = dt;
  so.alpha_step_deg = o.speed.alpha_deg_s * dt;
  so.beta_step_deg = o.speed.beta_deg_s * dt;
  so.margin_mm = o.margin_mm;
  so.max_duration_s = o.max_half_s;
  so.stop_avoid_deg = o.stop_avoid_deg;
  so.give_up_after = o.give_up_after;
  so.stall_s = o.stall_s;
  return Context{model, request, o, so, started};
}

Result<void> check_request(const CollisionModel& model, const PlanRequest& request, const PlannerOptions& o) {
  const std::size_t n = model.size();
  if (request.current.size() != n || request.target.size() != n || (!request.frozen.empty() && request.frozen.size() != n))
    return make_error(PlanErrc::bad_trajectory,
                      fmt::format("plan request: {} current poses, {} targets, {} frozen flags for {} robots",
                                  request.current.size(), request.target.size(), request.frozen.size(), n));
  for (std::size_t i = 0; i < n; ++i)
    if (!detail::finite(request.current[i]) || !detail::finite(request.target[i]))
      return make_error(PlanErrc::bad_trajectory, fmt::format("plan request: robot {}: angle not finite", model.robot(i).id()));
  if (!(o.speed.alpha_deg_s > 0) || !(o.speed.beta_deg_s > 0) || !(o.step_deg > 0))
    return make_error(PlanErrc::bad_trajectory, "plan request: speeds and step must be positive");
  return ok();
}

Work prepare(const Context& ctx) {
  const std::size_t n = ctx.size();
  const PlanRequest& req = ctx.request;
  Work w;
  w.plan.robots.resize(n);
  w.target = req.target;
  w.still.assign(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    w.plan.robots[i].status = RobotPlan::Status::reached;
    if (!req.frozen.empty() && req.frozen[i]) {
      w.plan.robots[i].status = RobotPlan::Status::frozen;
      w.still[i] = true;
      w.target[i] = req.current[i];
    }
  }
  detail::Setup setup{w.plan, w.target, w.still, req.current};
  detail::hold_start_contacts(ctx.model, setup);
  // The safe zone sees the robots that stay so far (frozen, starting in contact).
  if (ctx.options.safe_zone)
    w.plan.safe_zone = check_safe_zone(ctx.model, req.target, {w.still, req.point_fibre}, *ctx.options.safe_zone);
  for (std::size_t i = 0; i < n; ++i) {
    if (w.still[i]) continue;
    if (!ctx.model.robot(i).within_limits(w.target[i])) {
      w.plan.robots[i] = {RobotPlan::Status::parked, {}, "target outside the angle limits", {}};
      w.target[i] = ctx.park_pose(i);
    }
  }
  detail::set_aside_boxed_in(ctx, setup);
  return w;
}

void settle_targets(const Context& ctx, Work& w) {
  const std::size_t n = ctx.size();
  std::vector<Segment> segs(n);
  std::vector<Contact> contacts;
  for (std::size_t guard = 0; guard < kSettleChangesPerRobot * n + kSettleChangesExtra; ++guard) {
    ctx.model.segments(w.target, segs);
    ctx.model.find_contacts(segs, contacts);
    // Bodies that all stay: a contact they started in (held), nothing to settle.
    std::erase_if(contacts, [&](const Contact& c) { return w.still[c.a] && (c.kind != Contact::Kind::robot || w.still[c.b]); });
    if (contacts.empty()) return;
    // One change, then the contacts again (the change may clear or create others).
    for (const auto& c : contacts)
      if (detail::settle_contact(ctx, w, c)) break;
  }
}

Folds no_folds(std::size_t n) {
  return Folds{std::vector<StepperRobot>(n), std::vector<StepperRobot>(n), std::vector<bool>(n, false),
               std::vector<bool>(n, false)};
}

void choose_folds(const Context& ctx, const Work& w, Folds& f) {
  const std::size_t n = ctx.size();
  const PlannerOptions& o = ctx.options;
  // B's time for its beta work: alpha can turn this far during B.
  double tb = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (!w.still[i]) tb = std::max(tb, std::abs(w.target[i].beta_deg - ctx.fold_beta(i)) / o.speed.beta_deg_s);
  const double alpha_budget = tb * o.speed.alpha_deg_s;
  for (std::size_t i = 0; i < n; ++i) {
    const Pose current = ctx.request.current[i];
    if (w.still[i]) {
      f.a[i] = f.b[i] = {current, current, true};
      continue;
    }
    const double at = w.target[i].alpha_deg;
    double fold = detail::fold_alpha(ctx, w, i, alpha_budget);
    if (f.relax_b[i]) fold = at;
    if (f.relax_a[i]) fold = current.alpha_deg;
    f.a[i] = {current, {fold, ctx.fold_beta(i)}, false};
    f.b[i] = {w.target[i], {f.relax_b[i] ? at : fold, ctx.fold_beta(i)}, false};
  }
}

void run_halves(const Context& ctx, const Work& w, Folds& f, int round, Search& s) {
  const PlannerOptions& o = ctx.options;
  StepperOptions sa = ctx.engine, sb = ctx.engine;
  sa.seed = detail::run_seed(o.seed, kHalfASeed, round);
  sb.seed = detail::run_seed(o.seed, kHalfBSeed, round);
  const auto t0 = Clock::now();
  std::size_t runs_a = 0, runs_b = 0;
  if (o.parallel) {
    // A thread per half; the cores beyond those two, and the core of a half that is done, go to
    // the other half's pairs of tries (its local re-plans and its tail).
    half::SpareCores cores(std::max(0, static_cast<int>(std::thread::hardware_concurrency()) - 2));
    std::thread worker([&] {
      s.a = half::drive_half(ctx.model, f.a, sa, o, runs_a, &cores);
      cores.give();
    });
    s.b = half::drive_half(ctx.model, f.b, sb, o, runs_b, &cores);
    cores.give();
    worker.join();
  } else {
    s.a = half::drive_half(ctx.model, f.a, sa, o, runs_a);
    s.b = half::drive_half(ctx.model, f.b, sb, o, runs_b);
  }
  // Folds B gave up: one more A run turns those robots to the target alpha, so that they need no
  // middle phase (unless A gives the turn up too: then A's fold is relaxed as well).
  if (detail::move_given_up_folds(ctx, w, f)) {
    sa.seed += kExtraASeedStep;
    s.a = half::drive_half(ctx.model, f.a, sa, o, runs_a);
    for (std::size_t i = 0; i < ctx.size(); ++i)
      if (!w.still[i] && f.a[i].goal.alpha_deg == ctx.request.current[i].alpha_deg &&
          f.b[i].goal.alpha_deg != f.a[i].goal.alpha_deg)
        f.relax_a[i] = true;
  }
  s.search_s += core::seconds_since(t0);
}

bool take_stuck_robots(const Context& ctx, Work& w, const Search& s) {
  bool changed = false;
  for (std::size_t i = 0; i < ctx.size(); ++i) {
    if (w.still[i]) continue;
    if (!s.a.reached[i]) {
      w.plan.robots[i] = {RobotPlan::Status::held, {}, "cannot fold from its current pose without a collision",
                          ctx.ids_of(s.a.blockers[i])};
      w.still[i] = true;
      w.target[i] = ctx.request.current[i];
      changed = true;
    } else if (!s.b.reached[i]) {
      w.plan.robots[i] = {RobotPlan::Status::parked, {}, kReverseStuck, ctx.ids_of(s.b.blockers[i])};
      w.target[i] = ctx.park_pose(i);
      changed = true;
    }
  }
  return changed;
}

bool run_middle(const Context& ctx, Work& w, Folds& f, int round, Search& s) {
  // Folded robots cannot touch each other, but a robot that stays may stand unfolded next to
  // one: the turn goes through the engine too.
  bool any = false;
  const std::vector<StepperRobot> fm = detail::middle_robots(w, s, any);
  s.middle = {};
  if (!any) return false;
  StepperOptions sm = ctx.engine;
  sm.seed = detail::run_seed(ctx.options.seed, kMiddleSeed, round);
  const auto t0 = Clock::now();
  s.middle = drive_to_goals(ctx.model, fm, sm);
  s.search_s += core::seconds_since(t0);
  bool changed = false;
  for (std::size_t i = 0; i < ctx.size(); ++i)
    if (!s.middle.reached[i]) {
      w.plan.robots[i] = {RobotPlan::Status::parked, {}, "cannot turn to its fold alpha while folded",
                          ctx.ids_of(s.middle.blockers[i])};
      w.target[i] = ctx.park_pose(i);
      f.relax_a[i] = f.relax_b[i] = false;
      changed = true;
    }
  return changed;
}

Result<void> search_rounds(const Context& ctx, Work& w, Search& s) {
  const int max_rounds = std::max(1, ctx.options.retries + 1) + kExtraRounds;
  Folds f = no_folds(ctx.size());
  for (int round = 0;; ++round) {
    choose_folds(ctx, w, f);
    run_halves(ctx, w, f, round, s);
    w.plan.stats.rounds = static_cast<std::size_t>(round) + 1;
    w.plan.stats.escapes += s.a.escapes + s.b.escapes;
    const bool changed = take_stuck_robots(ctx, w, s) || run_middle(ctx, w, f, round, s);
    if (!changed) return ok();
    if (round + 1 >= max_rounds)
      return make_error(PlanErrc::robot_collision,
                        fmt::format("planner did not settle after {} rounds: robots keep blocking each other", max_rounds));
    settle_targets(ctx, w);
    w.plan.stats.setup_s = core::seconds_since(ctx.started);
  }
}

Finish finish_parked(const Context& ctx, Work& w, Search& s) {
  const std::size_t n = ctx.size();
  Finish fin;
  fin.in.assign(n, false);
  for (std::size_t i = 0; i < n; ++i)
    fin.in[i] = w.plan.robots[i].status == RobotPlan::Status::parked && w.plan.robots[i].reason == kReverseStuck &&
                ctx.model.robot(i).within_limits(ctx.request.target[i]);
  fin.any = detail::any_of(fin.in);
  for (int pass = 0; fin.any && pass < kFinishPasses; ++pass) {
    std::vector<StepperRobot> fc(n);
    for (std::size_t i = 0; i < n; ++i) {
      const Pose end{s.b.paths[i].alpha.front().deg, s.b.paths[i].beta.front().deg};  // where B starts: the end
      fc[i] = fin.in[i] ? StepperRobot{end, ctx.request.target[i], false} : StepperRobot{end, end, true};
    }
    StepperOptions sc = ctx.engine;
    sc.seed = ctx.options.seed * 2 + kFinishSeed + static_cast<std::uint64_t>(pass);
    const auto t0 = Clock::now();
    fin.run = drive_to_goals(ctx.model, fc, sc);
    s.search_s += core::seconds_since(t0);
    w.plan.stats.escapes += fin.run.escapes;
    bool dropped = false;
    for (std::size_t i = 0; i < n; ++i)
      if (fin.in[i] && !fin.run.reached[i]) {
        fin.in[i] = false;
        dropped = true;
      }
    fin.any = detail::any_of(fin.in);
    if (!dropped) break;
    if (!fin.any) fin.run = {};
  }
  if (!fin.any) fin.run = {};
  return fin;
}

std::vector<double> middle_starts(const Context& ctx, const Search& s, std::size_t& checks, double& check_s) {
  const std::size_t n = ctx.size();
  const double ta0 = s.a.duration_s;
  std::vector<double> start(n, ta0);
  if (s.middle.paths.empty() || !ctx.options.overlap_halves) return start;
  bool any = false;
  for (std::size_t i = 0; i < n; ++i)
    if (detail::turns_in_middle(s, i) && ta0 - end_time(s.a.paths[i]) >= ctx.engine.dt_s) {
      start[i] = end_time(s.a.paths[i]);
      any = true;
    }
  if (!any) return start;
  const auto t0 = Clock::now();
  TrajectoryChecker checker(ctx.model);
  CheckOptions check = ctx.options.check;
  check.allow_standing_contacts = true;  // robots held where they started in contact
  CheckReport report;
  std::vector<RobotTrajectory> joined(n);
  for (int round = 0; round < kMiddleStartRounds; ++round) {
    double from = ta0, to = ta0;
    for (std::size_t i = 0; i < n; ++i)
      if (detail::turns_in_middle(s, i)) {
        from = std::min(from, start[i]);
        to = std::max(to, start[i] + end_time(s.middle.paths[i]));
      }
    for (std::size_t i = 0; i < n; ++i)
      joined[i] = window(detail::turns_in_middle(s, i) ? detail::with_middle(s.a.paths[i], s.middle.paths[i], start[i])
                                                         : s.a.paths[i],
                         from, to);
    ++checks;
    if (checker.check(joined, check, report) && report.ok()) break;
    // The early turns in a contact wait for A's end; none there: give up on early turns.
    bool changed = false;
    const auto pairs = ctx.model.robot_pairs();
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      if (!report.robot_pairs[k].move_collided(check)) continue;
      for (const std::uint32_t i : {pairs[k].a, pairs[k].b})
        if (start[i] < ta0) {
          start[i] = ta0;
          changed = true;
        }
    }
    if (!changed || round + 1 == kMiddleStartRounds) std::fill(start.begin(), start.end(), ta0);
    if (!changed) break;
  }
  check_s += core::seconds_since(t0);
  return start;
}

double overlap_shift(const Context& ctx, const Search& s, double ta, double tb, std::size_t& checks, double& check_s) {
  const double most = ctx.options.overlap_halves ? detail::most_shift(s, ta, tb) : 0.0;
  if (most < ctx.engine.dt_s) return 0;
  const auto t0 = Clock::now();
  TrajectoryChecker checker(ctx.model);
  CheckOptions check = ctx.options.check;
  check.allow_standing_contacts = true;  // robots held where they started in contact
  CheckReport report;
  std::vector<RobotTrajectory> overlap(ctx.size());
  double taken = 0;
  for (const double part : {1.0, 0.75, 0.5, 0.25}) {
    const double shift = most * part;
    const std::vector<RobotTrajectory> joined = detail::joined_paths(s, ta - shift, tb);
    for (std::size_t i = 0; i < joined.size(); ++i) overlap[i] = window(joined[i], ta - shift, ta);
    ++checks;
    if (checker.check(overlap, check, report) && report.ok()) {
      taken = shift;
      break;
    }
  }
  check_s += core::seconds_since(t0);
  return taken;
}

void join_halves(const Context& ctx, Work& w, Search& s, const Finish& fin) {
  const std::size_t n = ctx.size();
  const double ta0 = s.a.duration_s, tb = s.b.duration_s;
  const double tm = s.middle.paths.empty() ? 0.0 : s.middle.duration_s;
  double ta_end = ta0;
  if (!s.middle.paths.empty())
    ta_end = detail::append_middle(s, middle_starts(ctx, s, w.plan.stats.checks, w.plan.stats.check_s));
  const double shift = overlap_shift(ctx, s, ta_end, tb, w.plan.stats.checks, w.plan.stats.check_s);
  const double ta = ta_end - shift;
  w.plan.stats.middle_s = tm;
  w.plan.stats.overlap_s = shift;
  w.plan.trajectories = detail::joined_paths(s, ta, tb);
  for (std::size_t i = 0; i < n; ++i) {
    RobotTrajectory& t = w.plan.trajectories[i];
    if (fin.any && fin.in[i]) {
      detail::append_finish(t, fin.run.paths[i], ta + tb);
      w.plan.robots[i] = {RobotPlan::Status::reached, {}, {}, {}};
    }
    detail::drop_still_points(t.alpha);
    detail::drop_still_points(t.beta);
    w.plan.robots[i].end = {t.alpha.back().deg, t.beta.back().deg};
    const auto st = w.plan.robots[i].status;
    if (st == RobotPlan::Status::parked || st == RobotPlan::Status::held) ++w.plan.not_reached;
  }
  w.plan.stats.search_s = s.search_s;
}

Layers smooth_and_simplify(const Context& ctx, Work& w) {
  const std::size_t n = ctx.size();
  const PlannerOptions& o = ctx.options;
  Layers L;
  L.plans.push_back(w.plan.trajectories);  // becomes the simplified layer
  L.smoothed.assign(n, false);
  if (o.smooth_points > 0) {
    SmoothOptions sm;
    sm.min_points = o.smooth_points;
    sm.min_clearance_mm = o.smooth_clearance_mm;
    const auto t0 = Clock::now();
    smooth_arms(ctx.model, L.plans.front(), sm, L.smoothed);
    w.plan.stats.smooth_s = core::seconds_since(t0);
    if (detail::any_of(L.smoothed)) L.plans.push_back(L.plans.front());
  }
  L.plans.push_back(w.plan.trajectories);  // exact
  const std::vector<RobotTrajectory>& base = L.plans[1];  // smoothed, or exact when nothing was
  L.simplified.assign(n, false);
  for (std::size_t i = 0; i < n; ++i) L.simplified[i] = detail::simplify_robot(o, base[i], L.plans.front()[i]);
  L.level.assign(n, 0);
  return L;
}

Result<void> verify_layers(const Context& ctx, Work& w, Layers& layers) {
  const std::size_t n = ctx.size();
  const auto t0 = Clock::now();
  layers.level.assign(n, 0);
  if (ctx.options.verify) {
    CheckOptions check = ctx.options.check;
    check.allow_standing_contacts = true;  // robots held where they started in contact
    AXON_TRY(checks, verify_with_fallbacks(ctx.model, layers.plans, check, w.plan.trajectories, layers.level, w.plan.check));
    w.plan.stats.checks += checks;
    w.plan.verified = w.plan.check.ok();
  } else {
    w.plan.trajectories = layers.plans.front();
  }
  const std::size_t exact_level = layers.plans.size() - 1;
  for (std::size_t i = 0; i < n; ++i) {
    layers.simplified[i] = layers.simplified[i] && layers.level[i] == 0;
    layers.smoothed[i] = layers.smoothed[i] && layers.level[i] < exact_level;
  }
  w.plan.stats.check_s += core::seconds_since(t0);
  return ok();
}

void collect_stats(Work& w, const Layers& layers) {
  PlanStats& st = w.plan.stats;
  std::vector<std::size_t> counts;
  for (std::size_t i = 0; i < w.plan.trajectories.size(); ++i) {
    const RobotTrajectory& t = w.plan.trajectories[i];
    st.simplified += layers.simplified[i] ? 1 : 0;
    st.smoothed += layers.smoothed[i] ? 1 : 0;
    for (const auto* arm : {&t.alpha, &t.beta}) {
      const std::size_t c = detail::firmware_points(*arm);
      if (c == 0) continue;
      counts.push_back(c);
      st.max_points = std::max(st.max_points, c);
    }
    st.max_alpha_speed = std::max(st.max_alpha_speed, max_speed(t.alpha));
    st.max_beta_speed = std::max(st.max_beta_speed, max_speed(t.beta));
    st.duration_s = std::max(st.duration_s, end_time(t));
  }
  if (!counts.empty()) {
    std::nth_element(counts.begin(), counts.begin() + static_cast<std::ptrdiff_t>(counts.size() / 2), counts.end());
    st.median_points = counts[counts.size() / 2];
  }
}

}  // namespace axon::fps::plan::phases

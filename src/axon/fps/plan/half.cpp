#include "axon/fps/plan/half.hpp"

#include "axon/fps/plan/untangle.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <thread>

// Helpers of this file only (a named namespace, for the unity build).
namespace axon::fps::plan::half::detail {

// The engine's next seed for a re-run (a 64-bit linear congruential step).
std::uint64_t next_seed(std::uint64_t seed) { return seed * 6364136223846793005ULL + 1442695040888963407ULL; }

std::size_t count_unreached(const StepperResult& r) {
  return static_cast<std::size_t>(std::count(r.reached.begin(), r.reached.end(), false));
}

// The patch of a local repair: the robots marked in `centre` and `rings` rings of neighbours
// around them (in), and the robots bordering it (border). `first` gets the centre.
void repair_patch(const CollisionModel& model, const std::vector<bool>& centre, int rings, std::vector<bool>& in,
                  std::vector<bool>& border, std::vector<std::uint32_t>& first) {
  const std::size_t n = model.size();
  in = centre;
  border.assign(n, false);
  first.clear();
  for (std::size_t i = 0; i < n; ++i)
    if (centre[i]) first.push_back(static_cast<std::uint32_t>(i));
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
}

// run(0) and, when `both`, run(1): side by side on a core borrowed from `cores` when one is
// spare, otherwise one after the other. run(t) must not touch what run(1 - t) does.
template <class Run>
void run_pair(bool both, SpareCores* cores, const Run& run) {
  if (both && cores != nullptr && cores->take()) {
    struct Back {
      SpareCores* c;
      ~Back() { c->give(); }
    } back{cores};
    std::jthread second([&run] { run(1); });
    run(0);
    return;
  }
  run(0);
  if (both) run(1);
}

// One or two tries of a re-plan: make(t, seed) builds try t's robots from the seed chain's value
// before the try (so.seed, advanced once per try); each try runs with the next value, the two side
// by side where `cores` lends a core. Their runs and escapes are counted into `runs` and `best`.
struct Tries {
  std::array<std::vector<StepperRobot>, 2> robots;
  std::array<StepperResult, 2> result;
};
template <class Make>
Tries run_tries(const CollisionModel& model, std::size_t count, StepperOptions& so, SpareCores* cores, const Make& make,
                std::size_t& runs, StepperResult& best) {
  Tries tries;
  std::array<StepperOptions, 2> options{so, so};
  for (std::size_t t = 0; t < count; ++t) {
    tries.robots[t] = make(t, so.seed);
    so.seed = next_seed(so.seed);
    options[t].seed = so.seed;
  }
  run_pair(count == 2, cores, [&](std::size_t t) { tries.result[t] = drive_to_goals(model, tries.robots[t], options[t]); });
  for (std::size_t t = 0; t < count; ++t) {
    ++runs;
    best.escapes += tries.result[t].escapes;
  }
  return tries;
}

// How many robots of the patch `in` the run leaves short of their goal.
std::size_t stuck_in(const StepperResult& r, const std::vector<bool>& in) {
  std::size_t c = 0;
  for (std::size_t i = 0; i < in.size(); ++i) c += (in[i] && !r.reached[i]) ? 1 : 0;
  return c;
}

std::vector<bool> unreached(const StepperResult& r) {
  std::vector<bool> out(r.reached.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = !r.reached[i];
  return out;
}

// A repair's paths of the patch replace best's; best's duration follows.
void take_patch(std::vector<StepperRobot>& robots, const std::vector<StepperRobot>& sub, const std::vector<bool>& in,
                StepperResult& r, StepperResult& best) {
  double duration = 0;
  for (std::size_t i = 0; i < robots.size(); ++i) {
    if (in[i] && !robots[i].frozen) {
      robots[i].goal = sub[i].goal;
      best.paths[i] = std::move(r.paths[i]);
      best.end[i] = r.end[i];
      best.reached[i] = r.reached[i];
      best.blockers[i] = std::move(r.blockers[i]);
    }
    duration = std::max(duration, end_time(best.paths[i]));
  }
  best.duration_s = duration;
}

// The robots of one local repair try: the patch planned again (a stuck robot's fold alpha drawn
// within fold_spread of its start from the second try on), the border following its paths of
// `best` (scripted), everyone else standing at its start.
std::vector<StepperRobot> repair_robots(const CollisionModel& model, const std::vector<StepperRobot>& robots,
                                        const StepperResult& best, const std::vector<bool>& in,
                                        const std::vector<bool>& border, int attempt, double fold_spread,
                                        std::uint64_t seed) {
  const std::size_t n = robots.size();
  std::vector<StepperRobot> sub(n);
  std::mt19937_64 rng(seed);
  for (std::size_t i = 0; i < n; ++i) {
    if (robots[i].frozen || in[i]) {
      sub[i] = robots[i];
      if (!robots[i].frozen && !best.reached[i] && attempt >= 1 && fold_spread > 0) {
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
  return sub;
}

// A tail try's cluster turns a random part (drawn from `seed`) of its alpha turn in this half;
// returns how much longer the middle phase may then take (the largest rest, at `so`'s full speed).
double turn_less(std::vector<StepperRobot>& sub, const std::vector<bool>& cluster, std::uint64_t seed,
                 const StepperOptions& so) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double growth = 0;
  for (std::size_t i = 0; i < sub.size(); ++i) {
    if (!cluster[i]) continue;
    const double turn = sub[i].goal.alpha_deg - sub[i].start.alpha_deg;
    const double kept = u(rng) * turn;
    sub[i].goal.alpha_deg = sub[i].start.alpha_deg + kept;
    growth = std::max(growth, std::abs(turn - kept) / so.alpha_step_deg * so.dt_s);
  }
  return growth;
}

// The cluster of late robots around robot `from`: late robots within two neighbour steps of one
// already in it.
std::vector<bool> late_cluster(const CollisionModel& model, const std::vector<bool>& late, std::size_t from) {
  std::vector<bool> out(late.size(), false);
  std::vector<std::size_t> todo{from};
  out[from] = true;
  while (!todo.empty()) {
    const std::size_t i = todo.back();
    todo.pop_back();
    for (const std::uint32_t j : model.neighbours(i))
      for (const std::uint32_t k : model.neighbours(j))
        for (const std::uint32_t x : {j, k})
          if (late[x] && !out[x]) {
            out[x] = true;
            todo.push_back(x);
          }
  }
  return out;
}

}  // namespace axon::fps::plan::half::detail

namespace axon::fps::plan::half {

using namespace detail;

void repair_locally(const CollisionModel& model, std::vector<StepperRobot>& robots, StepperResult& best,
                    StepperOptions so, const PlannerOptions& o, std::size_t& runs, SpareCores* cores) {
  std::vector<bool> in, border;
  for (int k = 0; k < o.local_retries && count_unreached(best) > 0; k += 2) {
    // Recomputed every pair: the patch grows when a repair leaves robots stuck elsewhere.
    repair_patch(model, unreached(best), o.local_rings, in, border, so.first);
    const std::size_t count = k + 1 < o.local_retries ? 2 : 1;
    Tries tries = run_tries(model, count, so, cores, [&](std::size_t t, std::uint64_t seed) {
      return repair_robots(model, robots, best, in, border, k + static_cast<int>(t), o.fold_spread_deg, seed);
    }, runs, best);
    const auto& r = tries.result;
    std::size_t won = count;  // the clean try that leaves the fewest of the patch stuck (the first on a tie)
    for (std::size_t t = 0; t < count; ++t) {
      const std::size_t left = stuck_in(r[t], in);
      if (r[t].violations == 0 && left < stuck_in(best, in) && (won == count || left < stuck_in(r[won], in))) won = t;
    }
    if (won < count) take_patch(robots, tries.robots[won], in, tries.result[won], best);
  }
}

std::vector<bool> late_robots(const std::vector<StepperRobot>& robots, const StepperResult& best, const PlannerOptions& o) {
  std::vector<double> times;
  for (std::size_t i = 0; i < robots.size(); ++i)
    if (!robots[i].frozen && robots[i].start != robots[i].goal) times.push_back(end_time(best.paths[i]));
  std::vector<bool> late(robots.size(), false);
  if (times.empty()) return late;
  const auto at = static_cast<std::size_t>(std::clamp(o.tail_quantile, 0.0, 1.0) * static_cast<double>(times.size() - 1));
  std::nth_element(times.begin(), times.begin() + static_cast<std::ptrdiff_t>(at), times.end());
  const double limit = times[at] + o.tail_slack_s;
  for (std::size_t i = 0; i < robots.size(); ++i) {
    if (robots[i].frozen || !best.reached[i]) continue;
    // No re-plan brings a robot in before its own straight move would.
    const double own = straight_move_s(robots[i].start, robots[i].goal, o.speed);
    const double t = end_time(best.paths[i]);
    late[i] = t > limit && t > own + o.tail_slack_s;
  }
  return late;
}

void shorten_tail(const CollisionModel& model, std::vector<StepperRobot>& robots, StepperResult& best, StepperOptions so,
                  const PlannerOptions& o, std::size_t& runs, SpareCores* cores) {
  const std::size_t n = robots.size();
  std::vector<bool> in, border;
  auto patch_end = [&](const StepperResult& r) {
    double t = 0;
    for (std::size_t i = 0; i < n; ++i)
      if (in[i]) t = std::max(t, end_time(r.paths[i]));
    return t;
  };
  int fruitless = 0;
  for (int k = 0; k < o.tail_retries && fruitless < o.tail_tries_per_cluster; k += 2) {
    const std::vector<bool> late = late_robots(robots, best, o);
    std::size_t last = n;
    for (std::size_t i = 0; i < n; ++i)
      if (late[i] && (last == n || end_time(best.paths[i]) > end_time(best.paths[last]))) last = i;
    if (last == n) return;
    const std::vector<bool> cluster = late_cluster(model, late, last);
    repair_patch(model, cluster, o.tail_rings, in, border, so.first);
    // Two tries on the cluster (side by side on a borrowed core): the second has the late robots
    // turn less alpha in this half. The middle phase turns the rest and may take that much
    // longer: such a try must win more than that.
    const std::size_t count = k + 1 < o.tail_retries ? 2 : 1;
    std::array<double, 2> middle_growth{0, 0};
    Tries tries = run_tries(model, count, so, cores, [&](std::size_t t, std::uint64_t seed) {
      std::vector<StepperRobot> sub = repair_robots(model, robots, best, in, border, 0, 0, seed);
      if (t == 1) middle_growth[t] = turn_less(sub, cluster, seed, so);
      return sub;
    }, runs, best);
    const auto& r = tries.result;
    std::size_t won = count;  // the try whose patch ends first, by half a step at least
    double won_end = patch_end(best) - so.dt_s / 2;
    for (std::size_t t = 0; t < count; ++t) {
      const double end = patch_end(r[t]) + middle_growth[t];
      if (r[t].violations == 0 && stuck_in(r[t], in) <= stuck_in(best, in) && end < won_end) {
        won = t;
        won_end = end;
      }
    }
    if (won == count) {
      fruitless += static_cast<int>(count);
      continue;
    }
    fruitless = 0;
    take_patch(robots, tries.robots[won], in, tries.result[won], best);
  }
}

bool SpareCores::take() noexcept {
  int n = spare_.load();
  while (n > 0)
    if (spare_.compare_exchange_weak(n, n - 1)) return true;
  return false;
}

void SpareCores::give() noexcept { spare_.fetch_add(1); }

StepperResult drive_half(const CollisionModel& model, std::vector<StepperRobot>& robots, StepperOptions so,
                         const PlannerOptions& o, std::size_t& runs, SpareCores* cores) {
  StepperResult best = drive_to_goals(model, robots, so);
  ++runs;
  std::vector<StepperRobot> best_robots = robots;
  std::vector<bool> listed(robots.size(), false);
  for (int k = 0; k < o.half_retries && count_unreached(best) > 0; ++k) {
    for (std::size_t i = 0; i < robots.size(); ++i) {
      if (best.reached[i]) continue;
      if (!listed[i]) {
        listed[i] = true;
        so.first.push_back(static_cast<std::uint32_t>(i));
      }
      if (k >= o.relax_after) robots[i].goal.alpha_deg = robots[i].start.alpha_deg;
    }
    so.seed = next_seed(so.seed);
    StepperResult r = drive_to_goals(model, robots, so);
    ++runs;
    const std::size_t a = count_unreached(r), b = count_unreached(best);
    if (a < b || (a == b && r.duration_s < best.duration_s)) {
      best = std::move(r);
      best_robots = robots;
    }
  }
  robots = std::move(best_robots);
  if (o.local_retries > 0 && count_unreached(best) > 0) {
    so.seed ^= kLocalRepairSeedSalt;
    repair_locally(model, robots, best, so, o, runs, cores);
  }
  if (o.untangle && count_unreached(best) > 0) untangle_to_fold(model, robots, best, so);
  if (o.tail_retries > 0) {
    so.seed ^= kTailSeedSalt;
    shorten_tail(model, robots, best, so, o, runs, cores);
  }
  return best;
}

}  // namespace axon::fps::plan::half

// Path planning of whole-focal-plane reconfigurations: the default 500-robot layout, seeded random
// problems, alternately from the folded lattice and from a random clear configuration, to a random
// clear configuration (alpha 0..360, beta 0..180, as the in-service planner draws them).
//
// Per problem: planning time (engine and checker), success (every robot reaches its target and
// the independent checker finds no contact at the full buffer), robots not reached (deadlocked:
// parked or held), points per arm sent to the firmware (median, max), move duration, smallest
// clearance over the move (from the checker).
//
// The reference planner cannot run here; its figures on random 500-robot problems on this kind of
// machine (FIELD-NOTES / issue 5) are printed beside ours and give ratio = 28 s / our median.
//
// Usage: fps_plan [--problems N] [--seed S] [--step DEG] [--speed DEG_S] [--half-retries N] [--relax-after K] [--local-retries N] [--local-rings R] [--fold-spread DEG] [--untangle 0|1] [--stop-avoid DEG] [--fold-stop-gap DEG] [--give-up N] [--stall S] [--smooth-points N] [--smooth-clearance MM]
#include "axon/fps/layout/layout_generator.hpp"
#include "axon/fps/plan/layout_model.hpp"
#include "axon/fps/plan/planner.hpp"
#include "axon/fps/plan/problems.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

using namespace axon::fps;
using namespace axon::fps::plan;

namespace {

constexpr double kRefMedianS = 28.0;   // Markov-decision variant, median planning time per problem
constexpr double kRefSuccess = 0.9;    // solves 9 of 10
constexpr double kRefMedianPoints = 6; // points per arm
constexpr double kRefMaxPoints = 118;
constexpr double kRefMoveS = 37.0;     // move duration

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

}  // namespace

int main(int argc, char** argv) {
  int problems = 5;
  std::uint64_t seed = 1000;
  PlannerOptions options;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i];
    const char* v = argv[i + 1];
    if (key == "--problems") problems = std::max(1, std::atoi(v));
    else if (key == "--seed") seed = std::strtoull(v, nullptr, 10);
    else if (key == "--step") options.step_deg = std::atof(v);
    else if (key == "--half-retries") options.half_retries = std::atoi(v);
    else if (key == "--relax-after") options.relax_after = std::atoi(v);
    else if (key == "--local-retries") options.local_retries = std::atoi(v);
    else if (key == "--local-rings") options.local_rings = std::atoi(v);
    else if (key == "--fold-spread") options.fold_spread_deg = std::atof(v);
    else if (key == "--stop-avoid") options.stop_avoid_deg = std::atof(v);
    else if (key == "--fold-stop-gap") options.fold_stop_gap_deg = std::atof(v);
    else if (key == "--stall") options.stall_s = std::atof(v);
    else if (key == "--give-up") options.give_up_after = std::atoi(v);
    else if (key == "--untangle") options.untangle = std::atoi(v) != 0;
    else if (key == "--smooth-points") options.smooth_points = static_cast<std::size_t>(std::atoi(v));
    else if (key == "--smooth-clearance") options.smooth_clearance_mm = std::atof(v);
    else if (key == "--speed") options.speed = {std::atof(v), std::atof(v)};
    else {
      std::fprintf(stderr, "usage: fps_plan [--problems N] [--seed S] [--step DEG] [--speed DEG_S] [--half-retries N] [--relax-after K] [--local-retries N] [--local-rings R] [--fold-spread DEG] [--untangle 0|1] [--stop-avoid DEG] [--fold-stop-gap DEG] [--give-up N] [--stall S] [--smooth-points N] [--smooth-clearance MM]\n");
      return 2;
    }
  }

  const auto plane = generate_layout().value();
  const auto model = model_from_layout(plane).value();
  fmt::print("fps_plan: {} robots, {} fiducials, {} neighbour pairs; speed {} / {} deg/s, step {} deg, buffer 2.0 mm\n",
             model.size(), plane.fiducials().size(), model.robot_pairs().size(), options.speed.alpha_deg_s,
             options.speed.beta_deg_s, options.step_deg);
  fmt::print("{:>3} {:>7} {:>8} {:>8} {:>8} {:>8} {:>7} {:>4} {:>6} {:>5} {:>5} {:>7} {:>8} {:>7} {:>5} {:>8} {:>6} {:>6}\n", "#", "from", "plan_s",
             "setup_s", "search_s", "check_s", "success", "dead", "escape", "p_med", "p_max", "move_s", "min_clr", "rounds", "mid_s", "smooth_s", "checks", "halv");

  std::vector<double> times, moves, med_points;
  std::size_t solved = 0, max_points = 0;
  for (int k = 0; k < problems; ++k) {
    const std::uint64_t s = seed + static_cast<std::uint64_t>(k);
    const bool from_folded = k % 2 == 0;
    PlanRequest req;
    req.target = random_poses(model, s);
    req.current = from_folded ? folded_poses(model) : random_poses(model, s + 7777);
    options.seed = s;
    auto r = plan_moves(model, req, options);
    if (!r) {
      fmt::print("{:>3} {:>7} error: {}\n", k, from_folded ? "folded" : "random", r.error().message());
      continue;
    }
    const Plan& p = r.value();
    const bool ok = p.ok() && p.verified;
    solved += ok ? 1 : 0;
    times.push_back(p.stats.plan_s);
    moves.push_back(p.stats.duration_s);
    med_points.push_back(static_cast<double>(p.stats.median_points));
    max_points = std::max(max_points, p.stats.max_points);
    fmt::print("{:>3} {:>7} {:>8.3f} {:>8.3f} {:>8.3f} {:>8.3f} {:>7} {:>4} {:>6} {:>5} {:>5} {:>7.1f} {:>8.3f} {:>7} {:>5.1f} {:>8.3f} {:>6} {:>6}\n", k,
               from_folded ? "folded" : "random", p.stats.plan_s, p.stats.setup_s, p.stats.search_s, p.stats.check_s, ok ? "yes" : "no",
               p.not_reached, p.stats.escapes, p.stats.median_points, p.stats.max_points, p.stats.duration_s,
               p.check.min_clearance_mm, p.stats.rounds, p.stats.middle_s, p.stats.smooth_s, p.stats.checks, p.check.halvings);
    if (!p.ok()) std::fputs(p.summary(model).c_str(), stdout);
    std::fflush(stdout);
  }
  const double success = static_cast<double>(solved) / problems;
  const double med = median(times);
  fmt::print("\n{:<28} {:>12} {:>12}\n", "", "axon", "reference");
  fmt::print("{:<28} {:>12.2f} {:>12.2f}\n", "success", success, kRefSuccess);
  fmt::print("{:<28} {:>12.3f} {:>12.1f}\n", "median planning time, s", med, kRefMedianS);
  fmt::print("{:<28} {:>12.1f} {:>12.0f}\n", "median points per arm", median(med_points), kRefMedianPoints);
  fmt::print("{:<28} {:>12} {:>12.0f}\n", "max points per arm", max_points, kRefMaxPoints);
  fmt::print("{:<28} {:>12.1f} {:>12.0f}\n", "median move duration, s", median(moves), kRefMoveS);
  fmt::print("BENCH fps_plan problems={} success={:.2f} median_s={:.3f} median_points={} max_points={} move_s={:.1f} "
             "ref_success={} ref_median_s={} ref_move_s={} ratio={:.1f}\n",
             problems, success, med, median(med_points), max_points, median(moves), kRefSuccess, kRefMedianS, kRefMoveS,
             med > 0 ? kRefMedianS / med : 0.0);
  return 0;
}

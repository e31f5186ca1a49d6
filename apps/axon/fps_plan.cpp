// `axon fps plan`, `axon fps plot`, `axon fps goto-all`: path planning for the whole focal plane
// (docs/fps-plan.md). plan and plot work offline on a layout file; goto-all reads the current
// positions from the array, plans, uploads, starts, follows and verifies.
#include "commands.hpp"
#include "axon/fps/layout/layout_file.hpp"
#include "layout_name.hpp"
#include "axon/fps/host/plan_and_move.hpp"
#include "axon/fps/plan/layout_model.hpp"
#include "axon/fps/plan/plan_file.hpp"
#include "axon/fps/plan/planner.hpp"
#include "axon/fps/plan/problems.hpp"
#include "axon/fps/plan/svg.hpp"
#include "axon/fps/plan/targets.hpp"
#include "checks.hpp"
#include "fps_array.hpp"
#include "fps_stop.hpp"
#include "run.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <memory>

namespace axon::app {
namespace {

namespace plan = fps::plan;
namespace host = fps::host;

struct PlanArgs {
  std::string layout;
  std::string from = "folded";
  std::string to;
  std::string output;
  std::string svg;
  std::string poses;
  std::string plan_file;
  std::string targets;
  double at_s = -1;
  bool paths = false;
  bool reject = false;
  std::uint64_t seed = 1;
  double speed = 12.0;
  double buffer = 2.0;
  bool allow_partial = false;
  bool refuse_unsafe = false;
};

void write_file(const std::string& path, const std::string& text) {
  if (path == "-") {
    std::fputs(text.c_str(), stdout);
    std::fflush(stdout);
    return;
  }
  std::ofstream out(path);
  out << text;
  out.close();
  if (!out) throw Exception(Error(CoreErrc::io, fmt::format("cannot write '{}'", path)));
}

struct Loaded {
  fps::FocalPlane plane;
  plan::CollisionModel model;
};

Loaded load(const PlanArgs& a) {
  if (a.layout.empty())
    throw Exception(Error(CoreErrc::invalid_argument, "give the focal-plane layout: --layout default|benchtop|FILE|DIR"));
  auto plane = need(resolve_layout(a.layout));
  plan::LayoutModelOptions lo;
  lo.buffer_mm = a.buffer;
  auto model = need(plan::model_from_layout(plane, lo));
  return {std::move(plane), std::move(model)};
}

// Poses by name (plan::poses_by_name: a target file, or for `named` also "folded" / "random");
// what parking resolved is logged. `point_fibre`, when given, receives which robots' targets are
// fibre points (the safe zone's reach check).
std::vector<plan::Pose> poses_from(const plan::CollisionModel& model, const std::string& spec, std::uint64_t seed,
                                   plan::TargetPolicy policy, const char* what,
                                   std::vector<std::optional<std::size_t>>* point_fibre = nullptr, bool named = true) {
  auto r = named ? plan::poses_by_name(model, spec, seed, policy) : plan::poses_from_file(model, spec, policy);
  if (!r) throw Exception(Error(r.error().code, fmt::format("{} {}", what, r.error().detail)));
  if (!r.value().notes.empty()) spdlog::warn("{} '{}':\n{}", what, spec, r.value().notes);
  if (point_fibre) *point_fibre = std::move(r.value().point_fibre);
  return std::move(r.value().poses);
}

plan::PlannerOptions planner_options(const PlanArgs& a) {
  plan::PlannerOptions o;
  o.speed = {a.speed, a.speed};
  o.seed = a.seed;
  return o;
}

// The targets outside their safe zones (spec section 11), the first ten of them.
void print_safe_zone(const plan::SafeZoneReport& r) {
  if (r.ok()) return;
  constexpr std::size_t kShown = 10;
  std::fprintf(stderr, "safe zone (spec section 11): the targets of %zu robots leave it\n", r.robots().size());
  for (std::size_t i = 0; i < r.issues.size() && i < kShown; ++i) std::fprintf(stderr, "  %s\n", r.issues[i].to_string().c_str());
  if (r.issues.size() > kShown) std::fprintf(stderr, "  ... %zu more\n", r.issues.size() - kShown);
}

void print_summary(const plan::CollisionModel& model, const plan::Plan& p) {
  std::fprintf(stderr,
               "plan: %zu robots, %zu not reached, move %.1f s, planning %.3f s (search %.3f s, check %.3f s), "
               "points per arm median %zu max %zu, min clearance %.3f mm, %s\n",
               model.size(), p.not_reached, p.stats.duration_s, p.stats.plan_s, p.stats.search_s, p.stats.check_s,
               p.stats.median_points, p.stats.max_points, p.check.min_clearance_mm,
               p.verified ? "verified by the checker" : "NOT verified");
  const auto s = p.summary(model);
  if (!s.empty()) std::fputs(s.c_str(), stderr);
  print_safe_zone(p.safe_zone);
}

int run_plan(const PlanArgs& a) {
  const auto [plane, model] = load(a);
  if (a.to.empty()) throw Exception(Error(CoreErrc::invalid_argument, "give the targets: --to FILE or --to random"));
  plan::PlanRequest req;
  req.current = poses_from(model, a.from, a.seed + 1, plan::TargetPolicy::reject, "current poses");
  req.target = poses_from(model, a.to, a.seed, a.reject ? plan::TargetPolicy::reject : plan::TargetPolicy::park, "targets",
                          &req.point_fibre);
  req.frozen = plan::frozen_robots(plane);
  auto r = plan::plan_moves(model, req, planner_options(a));
  const plan::Plan p = need(std::move(r));
  print_summary(model, p);
  if (!a.output.empty()) write_file(a.output, plan::plan_to_json(model, p, planner_options(a), plane.name()));
  if (!a.svg.empty()) {
    plan::SvgOptions so;
    so.title = fmt::format("{}: plan, {:.1f} s", plane.name(), p.stats.duration_s);
    const auto paths = plan::fibre_paths(model, p.trajectories, plan::kMetrologyFibre, 0.25);
    std::vector<plan::Pose> ends;
    for (const auto& rp : p.robots) ends.push_back(rp.end);
    write_file(a.svg, plan::render_svg(model, ends, so, paths));
  }
  return p.verified && (p.not_reached == 0 || a.allow_partial) ? 0 : 1;
}

int run_plot(const PlanArgs& a) {
  const auto [plane, model] = load(a);
  std::vector<plan::Pose> poses =
      a.poses.empty() ? plan::folded_poses(model) : poses_from(model, a.poses, a.seed, plan::TargetPolicy::reject, "poses");
  std::vector<plan::SvgPath> paths;
  std::string title = fmt::format("{}: {}", plane.name(), a.poses.empty() ? "folded" : a.poses);
  if (!a.plan_file.empty()) {
    const auto traj = need(plan::load_plan_trajectories(model, a.plan_file, poses));
    double end = 0;
    for (const auto& t : traj) end = std::max({end, t.alpha.back().t_s, t.beta.back().t_s});
    const double at = a.at_s >= 0 ? a.at_s : end;
    for (std::size_t i = 0; i < model.size(); ++i)
      poses[i] = {plan::angle_at(traj[i].alpha, at), plan::angle_at(traj[i].beta, at)};
    if (a.paths) paths = plan::fibre_paths(model, traj, plan::kMetrologyFibre, 0.25);
    title = fmt::format("{}: {} at {:.2f} s of {:.2f} s", plane.name(), a.plan_file, at, end);
  }
  std::vector<plan::Segment> segs(model.size());
  std::vector<plan::Contact> contacts;
  model.segments(poses, segs);
  model.find_contacts(segs, contacts);
  plan::SvgOptions so;
  so.title = title;
  write_file(a.output.empty() ? "-" : a.output, plan::render_svg(model, poses, so, paths, contacts));
  if (!contacts.empty()) std::fprintf(stderr, "plot: %zu contacts (drawn in red)\n", contacts.size());
  return contacts.empty() ? 0 : 1;
}

asio::awaitable<int> job_goto_all(const PlanArgs& a, host::Array& array) {
  const auto loaded = load(a);
  const auto& plane = loaded.plane;  // named references, not a structured binding: clang 14 cannot
  const auto& model = loaded.model;  // capture those in the lambda below
  const auto policy = a.reject ? plan::TargetPolicy::reject : plan::TargetPolicy::park;
  host::PlanAndMoveOptions o;
  o.planner = planner_options(a);
  o.allow_partial = a.allow_partial;
  o.refuse_outside_safe_zone = a.refuse_unsafe;
  o.on_plan = [&](const plan::Plan& p) {
    print_summary(model, p);
    if (!a.output.empty()) write_file(a.output, plan::plan_to_json(model, p, o.planner, plane.name()));
    spdlog::info("goto-all: {:.1f} s move", p.stats.duration_s);
  };
  auto targets = poses_from(model, a.targets, 0, policy, "targets", &o.point_fibre, false);
  auto r = co_await host::plan_and_move(array, plane, model, std::move(targets), o);
  const auto done = need(std::move(r));
  if (!done.run) {
    std::puts("goto-all: every robot is already where it should be");
    co_return 0;
  }
  std::fputs(done.run->summary().c_str(), stdout);
  std::fputc('\n', stdout);
  std::fflush(stdout);
  co_return motion_exit_code(done.ok(), array);
}

}  // namespace

void add_fps_plan_commands(CLI::App& fps_cmd, GlobalOptions& global, FpsArrayRunner with_array) {
  const auto args = std::make_shared<PlanArgs>();  // shared with the callbacks
  auto& a = *args;
  auto common = [&a](CLI::App* c) {
    c->add_option("--layout", a.layout, "focal-plane layout: default, benchtop, a YAML file or a directory of calibration tables")
        ->required();
    c->add_option("--seed", a.seed, "seed for random poses and the planner's nudges (default 1)");
    c->add_option("--buffer", a.buffer, "collision buffer of every robot, mm (default 2.0)")->check(non_negative());
  };
  auto* pl = fps_cmd.add_subcommand("plan", "plan collision-free trajectories for the whole focal plane");
  common(pl);
  pl->add_option("--from", a.from, "current poses: a target file, 'folded' (default) or 'random'");
  pl->add_option("--to", a.to, "targets: a target file (YAML/CSV) or 'random'")->required();
  auto* out = pl->add_option("-o,--output", a.output, "plan.json to write ('-' for stdout)");
  // --json as on every command that reports: the plan document alone on stdout (the summary and
  // logs stay on stderr), i.e. `-o -`.
  pl->add_flag_callback("--json", [args] { args->output = "-"; }, "print the plan (plan.json) on stdout, nothing else")->excludes(out);
  pl->add_option("--svg", a.svg, "also draw the end poses and the fibre paths");
  pl->add_option("--speed", a.speed, "arm speed, deg/s (default 12: 2000 rpm at the motor, 1000:1)")->check(positive());
  pl->add_flag("--reject", a.reject, "fail on bad targets instead of parking those robots");
  pl->add_flag("--allow-partial", a.allow_partial, "exit 0 even when some robots cannot reach their targets");
  pl->callback([args, &global] { global.exit_code = run_plan(*args); });

  auto* pt = fps_cmd.add_subcommand("plot", "draw the focal plane as SVG: poses, a plan at an instant, or its paths");
  common(pt);
  pt->add_option("--poses", a.poses, "poses: a target file, 'folded' (default) or 'random'");
  pt->add_option("--plan", a.plan_file, "plan.json: draw the poses at --at (default: the end)");
  pt->add_option("--at", a.at_s, "seconds into the plan");
  pt->add_flag("--paths", a.paths, "draw the metrology fibre's path of every robot");
  pt->add_option("-o,--output", a.output, "SVG file (default stdout)");
  pt->callback([args, &global] { global.exit_code = run_plot(*args); });

  auto* ga = fps_cmd.add_subcommand("goto-all", "plan from the robots' current positions to targets, then run it");
  common(ga);
  ga->add_option("--targets", a.targets, "target file (YAML/CSV)")->required();
  ga->add_option("--speed", a.speed, "arm speed, deg/s (default 12)")->check(positive());
  ga->add_option("--save-plan", a.output, "also write the plan.json");
  ga->add_flag("--reject", a.reject, "fail on bad targets instead of parking those robots");
  ga->add_flag("--allow-partial", a.allow_partial, "move the others when some robots cannot reach their targets");
  ga->add_flag("--refuse-unsafe", a.refuse_unsafe,
               "refuse when targets leave their robots' safe zones (spec section 11) instead of only reporting them");
  ga->callback([args, with_array, &global] {
    global.exit_code = with_array([args](host::Array& array) { return job_goto_all(*args, array); }, true);
  });
}

}  // namespace axon::app

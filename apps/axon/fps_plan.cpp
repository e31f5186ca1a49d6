// `axon fps plan`, `axon fps plot`, `axon fps goto-all`: path planning for the whole focal plane
// (docs/fps-plan.md). plan and plot work offline on a layout file; goto-all reads the current
// positions from the array, plans, uploads, starts, follows and verifies.
#include "commands.hpp"
#include "axon/fps/layout/layout_file.hpp"
#include "layout_name.hpp"
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

namespace axon::app {
namespace {

namespace plan = fps::plan;
namespace host = fps::host;
namespace protocol = fps::protocol;

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
  if (a.layout.empty()) throw Exception(Error(CoreErrc::invalid_argument, "give the focal-plane layout: --layout default|benchtop|FILE"));
  auto plane = need(resolve_layout(a.layout));
  plan::LayoutModelOptions lo;
  lo.buffer_mm = a.buffer;
  auto model = need(plan::model_from_layout(plane, lo));
  return {std::move(plane), std::move(model)};
}

// "folded", "random" (with the seed) or a target file resolved against the model.
std::vector<plan::Pose> poses_from(const plan::CollisionModel& model, const std::string& spec, std::uint64_t seed,
                                   plan::TargetPolicy policy, const char* what) {
  if (spec == "folded") return plan::folded_poses(model);
  if (spec == "random") return plan::random_poses(model, seed);
  const auto targets = need(plan::load_targets(spec));
  plan::ValidationOptions vo;
  vo.policy = policy;
  const auto v = plan::validate_targets(model, targets, vo);
  if (!v.errors.empty() || (!v.ok() && policy == plan::TargetPolicy::reject))
    throw Exception(Error(plan::PlanErrc::bad_target_file, fmt::format("{} '{}':\n{}", what, spec, v.summary())));
  if (!v.summary().empty()) spdlog::warn("{} '{}':\n{}", what, spec, v.summary());
  return v.poses();
}

plan::PlannerOptions planner_options(const PlanArgs& a) {
  plan::PlannerOptions o;
  o.speed = {a.speed, a.speed};
  o.seed = a.seed;
  return o;
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
}

int run_plan(const PlanArgs& a) {
  const auto [plane, model] = load(a);
  if (a.to.empty()) throw Exception(Error(CoreErrc::invalid_argument, "give the targets: --to FILE or --to random"));
  plan::PlanRequest req;
  req.current = poses_from(model, a.from, a.seed + 1, plan::TargetPolicy::reject, "current poses");
  req.target = poses_from(model, a.to, a.seed, a.reject ? plan::TargetPolicy::reject : plan::TargetPolicy::park, "targets");
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
  const auto [plane, model] = load(a);
  const auto targets = need(plan::load_targets(a.targets));
  plan::ValidationOptions vo;
  vo.policy = a.reject ? plan::TargetPolicy::reject : plan::TargetPolicy::park;
  const auto v = plan::validate_targets(model, targets, vo);
  if (!v.errors.empty() || (!v.ok() && vo.policy == plan::TargetPolicy::reject))
    throw Exception(Error(plan::PlanErrc::bad_target_file, fmt::format("targets '{}':\n{}", a.targets, v.summary())));
  if (!v.summary().empty()) spdlog::warn("targets:\n{}", v.summary());

  // Where every robot of the layout is now. Robots that did not answer are refused unless the
  // layout marks them offline (assumed folded) or disabled.
  const auto table = co_await array.status_table(true);
  plan::PlanRequest req;
  req.target = v.poses();
  req.frozen = plan::frozen_robots(plane);
  std::vector<std::string> missing;
  for (std::size_t i = 0; i < model.size(); ++i) {
    const auto id = static_cast<std::uint16_t>(model.robot(i).id());
    const auto* row = table.find(id);
    if (row && row->position) {
      req.current.push_back({row->position->alpha, row->position->beta});
      if (!row->ready()) req.frozen[i] = true;
    } else if (plane.robots()[i].offline) {
      req.current.push_back(plan::kFoldedPose);
    } else {
      missing.push_back(fmt::format("{}", id));
      req.current.push_back(plan::kFoldedPose);
    }
  }
  if (!missing.empty())
    throw Exception(Error(host::HostErrc::unknown_positioner,
                          fmt::format("no position for robots {} (not offline in the layout): refusing to plan around "
                                      "unknown poses",
                                      fmt::join(missing, " "))));
  for (std::size_t i = 0; i < model.size(); ++i)
    if (req.frozen[i]) req.target[i] = req.current[i];
  auto r = plan::plan_moves(model, req, planner_options(a));
  const plan::Plan p = need(std::move(r));
  print_summary(model, p);
  if (!a.output.empty()) write_file(a.output, plan::plan_to_json(model, p, planner_options(a), plane.name()));
  if (!p.verified) throw Exception(Error(plan::PlanErrc::robot_collision, "the checker rejected the plan: not moving"));
  if (p.not_reached > 0 && !a.allow_partial)
    throw Exception(Error(plan::PlanErrc::robot_collision,
                          fmt::format("{} robots cannot reach their targets (above); --allow-partial moves the rest",
                                      p.not_reached)));

  std::map<std::uint16_t, protocol::Trajectory> uploads;
  for (std::size_t i = 0; i < model.size(); ++i) {
    const auto& t = p.trajectories[i];
    if (t.alpha.size() <= 1 && t.beta.size() <= 1) continue;  // does not move
    std::vector<protocol::ArmPoint> arms[2];
    // The first point (0 s) is where the robot is: the firmware adds it by itself.
    for (std::size_t k = 1; k < t.alpha.size(); ++k) arms[0].push_back({t.alpha[k].deg, t.alpha[k].t_s});
    for (std::size_t k = 1; k < t.beta.size(); ++k) arms[1].push_back({t.beta[k].deg, t.beta[k].t_s});
    auto tr = protocol::Trajectory::from_physical(arms[0], arms[1]);
    if (!tr) throw Exception(Error(tr.error().code, fmt::format("robot {}: {}", model.robot(i).id(), tr.error().detail)));
    uploads.emplace(static_cast<std::uint16_t>(model.robot(i).id()), std::move(tr).value());
  }
  if (uploads.empty()) {
    std::puts("goto-all: every robot is already where it should be");
    co_return 0;
  }
  spdlog::info("goto-all: uploading {} trajectories ({:.1f} s move)", uploads.size(), p.stats.duration_s);
  auto rr = co_await array.run_trajectories(std::move(uploads), host::TrajectoryOptions{});
  const auto report = need(std::move(rr));
  std::fputs(report.summary().c_str(), stdout);
  std::fputc('\n', stdout);
  std::fflush(stdout);
  co_return motion_exit_code(report.ok(), array);
}

}  // namespace

void add_fps_plan_commands(CLI::App& app, GlobalOptions&) {
  CLI::App* fps_cmd = app.get_subcommand("fps");
  static PlanArgs a;
  auto common = [](CLI::App* c) {
    c->add_option("--layout", a.layout, "focal-plane layout: default, benchtop or a YAML file")->required();
    c->add_option("--seed", a.seed, "seed for random poses and the planner's nudges (default 1)");
    c->add_option("--buffer", a.buffer, "collision buffer of every robot, mm (default 2.0)")->check(non_negative());
  };
  auto* pl = fps_cmd->add_subcommand("plan", "plan collision-free trajectories for the whole focal plane");
  common(pl);
  pl->add_option("--from", a.from, "current poses: a target file, 'folded' (default) or 'random'");
  pl->add_option("--to", a.to, "targets: a target file (YAML/CSV) or 'random'")->required();
  auto* out = pl->add_option("-o,--output", a.output, "plan.json to write ('-' for stdout)");
  // --json as on every command that reports: the plan document alone on stdout (the summary and
  // logs stay on stderr), i.e. `-o -`.
  pl->add_flag_callback("--json", [] { a.output = "-"; }, "print the plan (plan.json) on stdout, nothing else")->excludes(out);
  pl->add_option("--svg", a.svg, "also draw the end poses and the fibre paths");
  pl->add_option("--speed", a.speed, "arm speed, deg/s (default 12: 2000 rpm at the motor, 1000:1)")->check(positive());
  pl->add_flag("--reject", a.reject, "fail on bad targets instead of parking those robots");
  pl->add_flag("--allow-partial", a.allow_partial, "exit 0 even when some robots cannot reach their targets");
  pl->callback([] { exit_code() = run_plan(a); });

  auto* pt = fps_cmd->add_subcommand("plot", "draw the focal plane as SVG: poses, a plan at an instant, or its paths");
  common(pt);
  pt->add_option("--poses", a.poses, "poses: a target file, 'folded' (default) or 'random'");
  pt->add_option("--plan", a.plan_file, "plan.json: draw the poses at --at (default: the end)");
  pt->add_option("--at", a.at_s, "seconds into the plan");
  pt->add_flag("--paths", a.paths, "draw the metrology fibre's path of every robot");
  pt->add_option("-o,--output", a.output, "SVG file (default stdout)");
  pt->callback([] { exit_code() = run_plot(a); });

  auto* ga = fps_cmd->add_subcommand("goto-all", "plan from the robots' current positions to targets, then run it");
  common(ga);
  ga->add_option("--targets", a.targets, "target file (YAML/CSV)")->required();
  ga->add_option("--speed", a.speed, "arm speed, deg/s (default 12)")->check(positive());
  ga->add_option("--save-plan", a.output, "also write the plan.json");
  ga->add_flag("--reject", a.reject, "fail on bad targets instead of parking those robots");
  ga->add_flag("--allow-partial", a.allow_partial, "move the others when some robots cannot reach their targets");
  ga->callback([] { exit_code() = with_fps_array([](host::Array& array) { return job_goto_all(a, array); }, true); });
}

}  // namespace axon::app

#include "axon/fps/host/plan_and_move.hpp"

#include "axon/fps/plan/error.hpp"
#include "axon/fps/plan/layout_model.hpp"
#include "axon/fps/plan/problems.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace axon::fps::host {

Result<plan::PlanRequest> request_from_status(const FocalPlane& plane, const plan::CollisionModel& model,
                                              const StatusTable& table, std::vector<plan::Pose> targets) {
  if (targets.size() != model.size())
    return Error(HostErrc::invalid_argument,
                 fmt::format("{} targets for {} robots: give one pose per robot of the layout", targets.size(), model.size()));
  plan::PlanRequest req;
  req.target = std::move(targets);
  req.frozen = plan::frozen_robots(plane);
  std::vector<std::string> missing;
  for (std::size_t i = 0; i < model.size(); ++i) {
    const auto id = static_cast<std::uint16_t>(model.robot(i).id());
    const auto* row = table.find(id);
    if (row && row->position) {
      req.current.push_back({row->position->alpha, row->position->beta});
      if (!row->ready()) req.frozen[i] = true;
    } else {
      if (!plane.robots()[i].offline) missing.push_back(fmt::format("{}", id));
      req.current.push_back(plan::kFoldedPose);
    }
  }
  if (!missing.empty())
    return Error(HostErrc::unknown_positioner,
                 fmt::format("no position for robots {} (not offline in the layout): refusing to plan around unknown poses",
                             fmt::join(missing, " ")));
  for (std::size_t i = 0; i < model.size(); ++i)
    if (req.frozen[i]) req.target[i] = req.current[i];
  return req;
}

namespace {

// The plan may move robots only when the checker verified it, unless partial moves are allowed
// every robot reaches its target, and when asked every target lies within its safe zone.
Result<void> plan_usable(const plan::Plan& p, const PlanAndMoveOptions& o) {
  if (!p.verified) return Error(plan::PlanErrc::robot_collision, "the checker rejected the plan: not moving");
  if (p.not_reached > 0 && !o.allow_partial)
    return Error(plan::PlanErrc::robot_collision,
                 fmt::format("{} robots cannot reach their targets; allow partial moves to move the rest", p.not_reached));
  if (o.refuse_outside_safe_zone && !p.safe_zone.ok())
    return Error(plan::PlanErrc::outside_safe_zone,
                 fmt::format("robots {} (not moving):\n{}", fmt::join(p.safe_zone.robots(), " "), p.safe_zone.summary()));
  return ok();
}

}  // namespace

asio::awaitable<Result<PlanAndMoveReport>> plan_and_move(Array& array, const FocalPlane& plane,
                                                         const plan::CollisionModel& model, std::vector<plan::Pose> targets,
                                                         PlanAndMoveOptions options) {
  const auto table = co_await array.status_table(true);
  auto req = request_from_status(plane, model, table, std::move(targets));
  if (!req) co_return req.error();
  req.value().point_fibre = options.point_fibre;
  auto planned = plan::plan_moves(model, req.value(), options.planner);
  if (!planned) co_return planned.error();
  PlanAndMoveReport report{std::move(planned).value(), std::nullopt};
  if (options.on_plan) options.on_plan(report.plan);
  if (auto usable = plan_usable(report.plan, options); !usable) co_return usable.error();
  auto uploads = plan_trajectories(model, report.plan);
  if (!uploads) co_return uploads.error();
  if (uploads.value().empty()) co_return report;
  Result<TrajectoryReport> run = Error(HostErrc::cancelled);
  if (options.run) {
    run = co_await options.run(std::move(uploads).value(), options.trajectory);
  } else {
    run = co_await array.run_trajectories(std::move(uploads).value(), options.trajectory);
  }
  if (!run) co_return run.error();
  report.run = std::move(run).value();
  co_return report;
}

}  // namespace axon::fps::host

#include "axon/fps/host/back_off.hpp"
#include "axon/fps/plan/arm_name.hpp"

#include "axon/fps/plan/distance.hpp"
#include "axon/fps/plan/problems.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <optional>

namespace axon::fps::host {

namespace asio = boost::asio;

namespace {

using Poses = std::vector<std::optional<plan::Pose>>;

struct Found {
  std::uint32_t robot = 0;  // model index
  std::optional<std::uint32_t> other;  // the other robot's model index; none: an obstacle
  std::string text;
};

Poses poses_of(const StatusTable& table, const plan::CollisionModel& model) {
  Poses out(model.size());
  for (std::size_t i = 0; i < model.size(); ++i)
    if (const auto* row = table.find(static_cast<std::uint16_t>(model.robot(i).id())); row && row->position)
      out[i] = plan::Pose{row->position->alpha, row->position->beta};
  return out;
}

// Every contact at the full buffer between bodies whose poses are known.
std::vector<Found> contacts(const plan::CollisionModel& model, const Poses& poses) {
  std::vector<Found> out;
  auto seg = [&](std::uint32_t i) { return model.robot(i).collision_segment(*poses[i]); };
  for (const auto& p : model.robot_pairs()) {
    if (!poses[p.a] || !poses[p.b]) continue;
    if (const double c = plan::segment_distance(seg(p.a), seg(p.b)) - p.limit_mm; c < 0)
      out.push_back({p.a, p.b, fmt::format("robot {} / robot {} ({:.3f} mm)", model.robot(p.a).id(), model.robot(p.b).id(), c)});
  }
  for (const auto& p : model.obstacle_pairs()) {
    if (!poses[p.robot]) continue;
    const auto& o = model.obstacles()[p.obstacle];
    if (const double c = plan::segment_distance(seg(p.robot), o.shape) - p.limit_mm; c < 0)
      out.push_back({p.robot, std::nullopt, fmt::format("robot {} / {} ({:.3f} mm)", model.robot(p.robot).id(), o.name, c)});
  }
  return out;
}

std::vector<std::string> texts(const std::vector<Found>& found) {
  std::vector<std::string> out;
  for (const auto& f : found) out.push_back(f.text);
  return out;
}

// The pose of every body robot i can touch, or the neighbour whose pose is unknown.
std::optional<std::uint16_t> unknown_near(const plan::CollisionModel& model, const Poses& poses, std::size_t i) {
  if (!poses[i]) return static_cast<std::uint16_t>(model.robot(i).id());
  for (const auto j : model.neighbours(i))
    if (!poses[j]) return static_cast<std::uint16_t>(model.robot(j).id());
  return std::nullopt;
}

std::vector<plan::Pose> known(const Poses& poses) {
  std::vector<plan::Pose> out;
  for (const auto& p : poses) out.push_back(p.value_or(plan::kFoldedPose));  // only read where known
  return out;
}

// Which robots to move when none were named: per contact, the first of the pair whose certified
// move ends clear (else the first with any certified move), once each.
std::vector<std::uint32_t> choose(const plan::CollisionModel& model, const Poses& poses, const std::vector<Found>& found,
                                  const plan::BackOffOptions& o) {
  std::vector<std::uint32_t> out;
  const auto all = known(poses);
  for (const auto& f : found) {
    std::vector<std::uint32_t> pair{f.robot};
    if (f.other) pair.push_back(*f.other);
    if (std::any_of(pair.begin(), pair.end(), [&](auto i) { return std::find(out.begin(), out.end(), i) != out.end(); }))
      continue;
    std::optional<std::uint32_t> pick;
    for (const auto i : pair) {
      if (unknown_near(model, poses, i)) continue;
      const auto b = plan::plan_back_off(model, i, all, o);
      if (b.clear) {
        pick = i;
        break;
      }
      if (b.found && !pick) pick = i;
    }
    out.push_back(pick.value_or(f.robot));
  }
  return out;
}

}  // namespace

bool BackOffReport::ok() const noexcept {
  return contacts_after.empty() && std::all_of(steps.begin(), steps.end(), [](const auto& s) { return s.moved; });
}

std::string BackOffReport::summary() const {
  std::string out = contacts_before.empty() ? "no contact before\n" : "";
  for (const auto& c : contacts_before) out += fmt::format("contact before: {}\n", c);
  for (const auto& s : steps) {
    if (s.moved)
      out += fmt::format("robot {}: {} {:+.1f} deg, alpha {:.2f} beta {:.2f} -> alpha {:.2f} beta {:.2f}, nearest body {:.3f} -> "
                         "{:.3f} mm\n",
                         s.id, arm_name(s.plan.arm), s.plan.step_deg, s.plan.from.alpha_deg,
                         s.plan.from.beta_deg, s.plan.to.alpha_deg, s.plan.to.beta_deg, s.plan.clearance_before_mm,
                         s.plan.clearance_after_mm);
    else
      out += fmt::format("robot {}: not moved: {}\n", s.id, s.problem);
  }
  for (const auto& c : contacts_after) out += fmt::format("contact left: {}\n", c);
  return out;
}

asio::awaitable<Result<BackOffReport>> back_off(Array& array, const plan::CollisionModel& model, BackOffRequest request) {
  for (const auto id : request.ids)
    if (!model.index_of(id)) co_return Error(HostErrc::unknown_positioner, fmt::format("robot {} is not in the layout", id));
  const auto table = co_await array.status_table(true);
  Poses poses = poses_of(table, model);
  BackOffReport report;
  const auto before = contacts(model, poses);
  report.contacts_before = texts(before);
  std::vector<std::uint32_t> order;
  if (request.ids.empty()) order = choose(model, poses, before, request.plan);
  for (const auto id : request.ids) order.push_back(static_cast<std::uint32_t>(*model.index_of(id)));
  std::vector<std::uint16_t> ids;
  for (const auto i : order) ids.push_back(static_cast<std::uint16_t>(model.robot(i).id()));
  if (auto admitted = array.admit_all(protocol::CommandId::go_to_absolute_position, ids); !admitted)
    co_return admitted.error();
  for (const auto i : order) {
    BackOffStep step;
    step.id = static_cast<std::uint16_t>(model.robot(i).id());
    if (const auto unknown = unknown_near(model, poses, i)) {
      step.problem = fmt::format("the position of {} is unknown, so no move can be proven clear",
                                 *unknown == step.id ? "the robot itself" : fmt::format("neighbour {}", *unknown));
      report.steps.push_back(std::move(step));
      continue;
    }
    step.plan = plan::plan_back_off(model, i, known(poses), request.plan);
    if (!step.plan.found) {
      step.problem = "no certified move of 2 to 8 degrees on either arm (inside its limits, nothing closer, nothing new "
                     "touched): move it by hand";
      report.steps.push_back(std::move(step));
      continue;
    }
    std::map<std::uint16_t, ArmAngles> target;  // (a braced list inside co_await trips gcc 12)
    target[step.id] = ArmAngles{step.plan.to.alpha_deg, step.plan.to.beta_deg};
    auto moved = co_await array.goto_absolute(std::move(target));
    const Result<MoveResult>* r = moved ? &moved.value().at(step.id) : nullptr;
    if (r != nullptr && *r) {
      step.moved = true;
      poses[i] = plan::Pose{r->value().reached.alpha, r->value().reached.beta};
    } else {
      step.problem = fmt::format("the move failed: {}", moved ? r->error().message() : moved.error().message());
      poses[i].reset();  // where it stopped is not known any more
    }
    report.steps.push_back(std::move(step));
  }
  report.contacts_after = texts(contacts(model, poses));
  co_return report;
}

}  // namespace axon::fps::host

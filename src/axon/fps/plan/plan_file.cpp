#include "axon/fps/plan/plan_file.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

namespace axon::fps::plan {

namespace {
using json = nlohmann::json;

json arm_json(const std::vector<TimedAngle>& pts) {
  json a = json::array();
  for (const auto& p : pts) a.push_back(json::array({p.deg, p.t_s}));
  return a;
}
}  // namespace

std::string plan_to_json(const CollisionModel& model, const Plan& plan, const PlannerOptions& options,
                         const std::string& layout_name) {
  json j;
  j["format"] = "axon-fps-plan";
  j["version"] = 1;
  j["layout"] = layout_name;
  j["speed_deg_s"] = {{"alpha", options.speed.alpha_deg_s}, {"beta", options.speed.beta_deg_s}};
  j["duration_s"] = plan.stats.duration_s;
  j["verified"] = plan.verified;
  j["min_clearance_mm"] = plan.check.samples ? json(plan.check.min_clearance_mm) : json(nullptr);
  j["not_reached"] = plan.not_reached;
  j["stats"] = {{"plan_s", plan.stats.plan_s},         {"search_s", plan.stats.search_s},
                {"check_s", plan.stats.check_s},       {"rounds", plan.stats.rounds},
                {"escapes", plan.stats.escapes},       {"median_points", plan.stats.median_points},
                {"max_points", plan.stats.max_points}, {"max_alpha_deg_s", plan.stats.max_alpha_speed},
                {"max_beta_deg_s", plan.stats.max_beta_speed}, {"smooth_s", plan.stats.smooth_s},
                {"smoothed", plan.stats.smoothed},     {"checks", plan.stats.checks}};
  json robots = json::array();
  for (std::size_t i = 0; i < plan.trajectories.size(); ++i) {
    const auto& t = plan.trajectories[i];
    const auto& r = plan.robots[i];
    json rj{{"id", model.robot(i).id()},
            {"status", std::string(to_string(r.status))},
            {"from", {{"alpha", t.alpha.front().deg}, {"beta", t.beta.front().deg}}},
            {"to", {{"alpha", r.end.alpha_deg}, {"beta", r.end.beta_deg}}},
            {"alpha", arm_json(t.alpha)},
            {"beta", arm_json(t.beta)}};
    if (!r.reason.empty()) rj["reason"] = r.reason;
    if (!r.blockers.empty()) rj["blockers"] = r.blockers;
    robots.push_back(std::move(rj));
  }
  j["robots"] = std::move(robots);
  return j.dump() + "\n";
}

Result<std::vector<RobotTrajectory>> load_plan_trajectories(const CollisionModel& model, const std::string& path,
                                                            const std::vector<Pose>& hold) {
  std::ifstream in(path);
  if (!in) return make_error(PlanErrc::bad_trajectory, fmt::format("{}: cannot open", path));
  json j;
  try {
    j = json::parse(in);
  } catch (const std::exception& e) {
    return make_error(PlanErrc::bad_trajectory, fmt::format("{}: {}", path, e.what()));
  }
  std::vector<RobotTrajectory> out;
  for (std::size_t i = 0; i < model.size(); ++i) out.push_back(RobotTrajectory::hold(i < hold.size() ? hold[i] : Pose{}));
  if (!j.is_object() || !j.contains("robots") || !j["robots"].is_array())
    return make_error(PlanErrc::bad_trajectory, fmt::format("{}: expected an object with a list 'robots'", path));
  for (const auto& rj : j["robots"]) {
    try {
      const auto id = rj.at("id").get<std::int32_t>();
      const auto idx = model.index_of(id);
      if (!idx) return make_error(PlanErrc::unknown_robot, fmt::format("{}: robot {} is not in the layout", path, id));
      RobotTrajectory t;
      for (const char* arm : {"alpha", "beta"}) {
        auto& pts = std::string_view(arm) == "alpha" ? t.alpha : t.beta;
        for (const auto& p : rj.at(arm)) pts.push_back({p.at(1).get<double>(), p.at(0).get<double>()});
      }
      AXON_TRY(validate(t));
      out[*idx] = std::move(t);
    } catch (const std::exception& e) {
      return make_error(PlanErrc::bad_trajectory, fmt::format("{}: {}", path, e.what()));
    }
  }
  return out;
}

}  // namespace axon::fps::plan

#include "axon/fps/host/client_json.hpp"
#include "axon/fps/plan/arm_name.hpp"

namespace axon::fps {

using json = nlohmann::json;

namespace {

json angle_or_null(const std::optional<Angles>& a, double Angles::*which) { return a ? json((*a).*which) : json(nullptr); }

}  // namespace

json to_json(const RobotStatus& r) {
  json j{{"id", r.id}, {"bus", r.bus}, {"state", r.state}, {"ready", r.ready}, {"firmware", r.firmware},
         {"alpha", angle_or_null(r.position, &Angles::alpha)}, {"beta", angle_or_null(r.position, &Angles::beta)}};
  if (!r.error.empty()) j["error"] = r.error;
  return j;
}

json to_json(const MoveOutcome& out) {
  json robots = json::array();
  for (const auto& r : out.robots) {
    json j{{"id", r.id}, {"ok", r.ok}, {"state", r.state}, {"alpha", angle_or_null(r.reached, &Angles::alpha)},
           {"beta", angle_or_null(r.reached, &Angles::beta)}};
    if (!r.detail.empty()) j["detail"] = r.detail;
    robots.push_back(std::move(j));
  }
  return {{"completed", out.completed}, {"robots", std::move(robots)}};
}

json plan_result_json(const PlanAndMoveOutcome& out) {
  const auto& p = out.plan;
  return {{"verified", p.verified},   {"robots", p.robots},
          {"not_reached", p.not_reached}, {"move_s", p.move_s},
          {"plan_s", p.plan_s},       {"min_clearance_mm", p.min_clearance_mm},
          {"notes", p.notes},         {"outside_safe_zone", p.outside_safe_zone},
          {"moved", out.moved}};
}

json to_json(const BackOffOutcome& out) {
  json moves = json::array();
  for (const auto& m : out.moves)
    moves.push_back({{"id", m.id},
                     {"moved", m.moved},
                     {"arm", arm_name(m.arm)},
                     {"step_deg", m.step_deg},
                     {"clearance_before_mm", m.clearance_before_mm},
                     {"clearance_after_mm", m.clearance_after_mm},
                     {"problem", m.problem}});
  return {{"ok", out.ok}, {"contacts_before", out.contacts_before}, {"moves", moves}, {"contacts_after", out.contacts_after}};
}

json to_json(const SextantUpgrade& p) {
  return {{"sextant", p.sextant}, {"robots", p.robots},   {"done", p.done},         {"failed", p.failed},
          {"bytes", p.bytes},     {"seconds", p.seconds}, {"finished", p.finished}, {"text", p.text}};
}

json to_json(const FirmwareOutcome& out) {
  json robots = json::array();
  for (const auto& r : out.robots)
    robots.push_back({{"id", r.id}, {"sextant", r.sextant}, {"outcome", r.outcome}, {"attempts", r.attempts},
                      {"half_written", r.half_written}, {"before", r.before}, {"after", r.after}, {"reason", r.reason}});
  return {{"ok", out.ok}, {"robots", std::move(robots)}};
}

json to_json(const ColdOutcome& r) {
  json failed = json::object();
  for (const auto& [id, why] : r.failed) failed[std::to_string(id)] = why;
  return {{"motor_rpm", r.motor_rpm},
          {"alpha_holding_pct", r.alpha_holding_pct},
          {"beta_holding_pct", r.beta_holding_pct},
          {"coldest_c", r.coldest_c ? json(*r.coldest_c) : json(nullptr)},
          {"coldest_sensor", r.coldest_sensor},
          {"applied", r.applied},
          {"failed", std::move(failed)},
          {"text", r.text}};
}

}  // namespace axon::fps

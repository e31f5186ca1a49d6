#include "axon/fps/host/troubleshoot_json.hpp"
#include "axon/fps/plan/arm_name.hpp"

namespace axon::fps::host {

using json = nlohmann::json;

json to_json(const FrictionReport& rep) {
  json arms = json::array();
  for (const auto& f : rep.arms) {
    json points = json::array();
    for (const auto& p : f.points)
      points.push_back({{"speed_rpm", p.speed_rpm}, {"current_percent", p.current_percent}, {"readings", p.readings},
                        {"move_s", p.move_s}, {"eta_s", p.eta_s}});
    json fit = f.fit ? json{{"stiction_percent", f.fit->stiction_percent},
                            {"viscous_percent_per_krpm", f.fit->viscous_percent_per_krpm}, {"rms_percent", f.fit->rms_percent}}
                     : json(nullptr);
    arms.push_back({{"id", f.id}, {"arm", arm_name(f.arm)}, {"verdict", to_string(f.verdict)},
                    {"fit", fit}, {"points", points}, {"step_deg", f.step_deg}, {"move_ratio", f.move_ratio},
                    {"baseline_time_utc", f.baseline ? json(f.baseline->time_utc) : json(nullptr)},
                    {"growth", f.growth}, {"move_growth", f.move_growth}, {"problem", f.problem}, {"advice", f.advice}});
  }
  return {{"ok", rep.ok()}, {"time_utc", rep.time_utc}, {"arms", arms}};
}

json to_json(const HallTestReport& rep) {
  json arms = json::array();
  for (const auto& f : rep.arms)
    arms.push_back({{"id", f.id}, {"arm", arm_name(f.arm)}, {"verdict", to_string(f.verdict)},
                    {"step_deg", f.step_deg}, {"hall_before_deg", f.hall_before_deg}, {"hall_after_deg", f.hall_after_deg},
                    {"position_before_deg", f.position_before_deg}, {"position_after_deg", f.position_after_deg},
                    {"tracking_error_deg", f.tracking_error_deg}, {"restored", f.restored}, {"problem", f.problem},
                    {"advice", f.advice}});
  return {{"ok", rep.ok()}, {"arms", arms}};
}

}  // namespace axon::fps::host

// The troubleshooting reports (troubleshoot_types.hpp) as JSON: what `axon fps plane friction
// --json` and `halltest --json` print and what the actor's `friction` and `halltest` keywords carry
// (docs/schema/fps.json: friction, hall_test).
#pragma once

#include "axon/fps/host/troubleshoot_types.hpp"

#include <nlohmann/json.hpp>

namespace axon::fps::host {

// {ok, time_utc, arms: [{id, arm, verdict, fit, points, step_deg, move_ratio, baseline_time_utc,
//  growth, move_growth, problem, advice}]}
nlohmann::json to_json(const FrictionReport& report);
// {ok, arms: [{id, arm, verdict, step_deg, hall_before_deg, hall_after_deg, position_before_deg,
//  position_after_deg, tracking_error_deg, restored, problem, advice}]}
nlohmann::json to_json(const HallTestReport& report);

}  // namespace axon::fps::host

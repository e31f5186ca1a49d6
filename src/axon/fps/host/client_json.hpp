// What fps::Client's calls return, as JSON: the keywords of the fps actor (docs/schema/fps.json) and
// what a script reading them expects. One place for each shape, so the actor and any other front
// end say the same.
#pragma once

#include "axon/fps/host/client.hpp"

#include <nlohmann/json.hpp>

namespace axon::fps {

// {id, bus, state, ready, firmware, alpha, beta (null: not read), error (only when it failed)}
nlohmann::json to_json(const RobotStatus& robot);
// {completed, robots: [{id, ok, state, alpha, beta, detail (when set)}]}
nlohmann::json to_json(const MoveOutcome& move);
// {verified, robots, not_reached, move_s, plan_s, min_clearance_mm, notes, outside_safe_zone, moved}
nlohmann::json plan_result_json(const PlanAndMoveOutcome& out);
// {ok, contacts_before, moves: [{id, moved, arm, step_deg, clearance_before_mm, clearance_after_mm,
//  problem}], contacts_after}
nlohmann::json to_json(const BackOffOutcome& out);
// {sextant, robots, done, failed, bytes, seconds, finished, text}
nlohmann::json to_json(const SextantUpgrade& progress);
// {ok, robots: [{id, sextant, outcome, attempts, half_written, before, after, reason}]}
nlohmann::json to_json(const FirmwareOutcome& out);
// {motor_rpm, alpha_holding_pct, beta_holding_pct, coldest_c, coldest_sensor, applied, failed: {id:
//  why}, text}
nlohmann::json to_json(const ColdOutcome& out);

}  // namespace axon::fps

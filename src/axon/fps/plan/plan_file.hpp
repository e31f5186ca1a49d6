// plan.json: a planned move as a file (format in docs/fps-plan.md), written by `axon fps plan` and
// read by `axon fps plot --plan`.
#pragma once

#include "axon/fps/plan/planner.hpp"

#include <string>
#include <vector>

namespace axon::fps::plan {

// The plan as JSON text: per robot its id, status, start and end pose, reason and blockers, and
// the alpha and beta points as [deg, s] (the first at 0 s is the start pose; the firmware adds
// that one itself, the rest are what is uploaded).
std::string plan_to_json(const CollisionModel& model, const Plan& plan, const PlannerOptions& options,
                         const std::string& layout_name = {});

// The trajectories of a plan file, in model order. Robots the file does not list hold `hold`
// (their pose; one per robot). Errors: PlanErrc::bad_trajectory with the file and what is wrong,
// unknown_robot for ids the model does not have.
Result<std::vector<RobotTrajectory>> load_plan_trajectories(const CollisionModel& model, const std::string& path,
                                                            const std::vector<Pose>& hold);

}  // namespace axon::fps::plan

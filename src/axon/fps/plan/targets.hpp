// Target sets: which pose or which focal-plane point each robot should reach, read from YAML or
// CSV, and their validation against a collision model.
//
// A target is either an explicit pose (alpha, beta in degrees) or a focal-plane point (x, y in
// mm) for a named fibre (default "boss"), optionally with the elbow to use (default: ccw when it
// is within the limits, else cw). The formats are described in docs/fps-plan.md.
//
// Validation resolves every target to a pose and checks the whole configuration: robots without
// a target stand at the park pose (folded), every robot pair and robot-obstacle pair must keep
// its clearance. Problems come back as typed errors per robot. Policy `reject` marks each bad
// robot rejected; policy `park` folds bad robots to the park pose instead (recording why) and
// re-checks until the configuration is clear; robots that collide even when parked stay rejected.
// Targets for unknown robots and duplicate targets are errors under either policy.
#pragma once

#include "axon/fps/plan/collision.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace axon::fps::plan {

struct Target {
  std::int32_t robot = 0;
  std::optional<Pose> pose;       // explicit angles, or
  std::optional<Vec2> position;   // a focal-plane point for `fibre`
  std::string fibre = "boss";
  std::optional<Elbow> elbow;
  int line = 0;                   // where it came from (0: built in code)
};

// Parse a target file; the format follows the extension (.yaml/.yml or .csv).
Result<std::vector<Target>> load_targets(const std::string& path);
// `name` is used in error messages (file:line).
Result<std::vector<Target>> parse_targets_yaml(std::string_view text, const std::string& name = "<targets>");
Result<std::vector<Target>> parse_targets_csv(std::string_view text, const std::string& name = "<targets>");

enum class TargetPolicy { reject, park };

struct ValidationOptions {
  TargetPolicy policy = TargetPolicy::reject;
  Pose park{10.0, 170.0};  // the folded pose of the in-service planner's lattice
  bool check_collisions = true;
};

struct RobotOutcome {
  enum class Status { ok, untargeted, parked, rejected };
  std::int32_t robot = 0;
  Status status = Status::untargeted;
  Pose pose;                   // the pose the robot should take (park pose unless status ok)
  std::optional<Error> issue;  // why it was parked or rejected
};
std::string_view to_string(RobotOutcome::Status s) noexcept;

struct TargetValidation {
  std::vector<RobotOutcome> robots;  // one per robot, in model order
  std::vector<Error> errors;         // unknown robots, duplicate targets
  [[nodiscard]] bool ok() const noexcept;
  // All problems, one line each ("robot 12: rejected: ...").
  [[nodiscard]] std::string summary() const;
  // The poses in model order, ready for CollisionModel::segments() or a planner.
  [[nodiscard]] std::vector<Pose> poses() const;
};

TargetValidation validate_targets(const CollisionModel& model, std::span<const Target> targets,
                                  const ValidationOptions& options = {});

// The validation under `policy` when its result can be planned: errors (PlanErrc::bad_target_file,
// the validation summary as detail) for unknown robots or duplicates, and under
// TargetPolicy::reject for any bad target.
Result<TargetValidation> usable_targets(const CollisionModel& model, std::span<const Target> targets, TargetPolicy policy);

// The poses of validated targets (usable_targets), in model order: what a planner takes. Errors
// (PlanErrc::bad_target_file, the validation summary as detail): unknown robots or duplicates, and
// under TargetPolicy::reject any bad target. `notes`, when given, receives what parking resolved
// (empty when nothing).
Result<std::vector<Pose>> target_poses(const CollisionModel& model, std::span<const Target> targets, TargetPolicy policy,
                                       std::string* notes = nullptr);

}  // namespace axon::fps::plan

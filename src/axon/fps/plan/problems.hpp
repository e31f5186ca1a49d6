// Configurations for planner problems: the folded lattice and random clear configurations (the
// benchmark's and `axon fps plan --from folded --to random`'s inputs).
#pragma once

#include "axon/fps/plan/collision.hpp"
#include "axon/fps/plan/targets.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace axon::fps::plan {

// The folded pose of the in-service planner's lattice.
inline constexpr Pose kFoldedPose{10.0, 170.0};

// Every robot at `fold`.
std::vector<Pose> folded_poses(const CollisionModel& model, Pose fold = kFoldedPose);

struct RandomPoseOptions {
  double alpha_min_deg = 0;
  double alpha_max_deg = 360;
  double beta_min_deg = 0;    // the in-service planner draws the ccw elbow only: beta 0..180
  double beta_max_deg = 180;
  double min_clearance_mm = 0;  // to the neighbours and obstacles already placed
  int attempts = 200;           // draws per robot before it stays at `fallback`
  Pose fallback = kFoldedPose;
};

// Robots in a random order each draw a pose until it keeps its clearance to every neighbour's
// pose so far (which starts at `fallback`) and to the obstacles: a clear configuration,
// reproducible from the seed.
std::vector<Pose> random_poses(const CollisionModel& model, std::uint64_t seed, const RandomPoseOptions& options = {});

// A configuration read for a planner problem.
struct ProblemPoses {
  std::vector<Pose> poses;  // model order
  // Per robot, the fibre whose focal-plane point its target is (safe_zone.hpp's point_fibres; all
  // nullopt for folded and random poses).
  std::vector<std::optional<std::size_t>> point_fibre;
  std::string notes;  // what TargetPolicy::park resolved (robots parked and why), empty if nothing
  std::vector<RobotOutcome> parked;  // those robots: their targets are replaced by the park pose
};

// A target file (targets.hpp) resolved against the model under `policy` (validate_targets). Errors:
// the file's (PlanErrc::bad_target_file, located), or the validation's (unknown robots,
// duplicates; under reject any bad target) with the file named in the detail.
Result<ProblemPoses> poses_from_file(const CollisionModel& model, const std::string& path, TargetPolicy policy);
// "folded", "random" (drawn from `seed`) or a target file: how `axon fps plan --from/--to` and
// bench/fps_plan name a configuration.
Result<ProblemPoses> poses_by_name(const CollisionModel& model, const std::string& name, std::uint64_t seed,
                                   TargetPolicy policy);

}  // namespace axon::fps::plan

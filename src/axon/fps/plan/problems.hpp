// Configurations for planner problems: the folded lattice and random clear configurations (the
// benchmark's and `axon fps plan --from folded --to random`'s inputs).
#pragma once

#include "axon/fps/plan/collision.hpp"

#include <cstdint>
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

}  // namespace axon::fps::plan

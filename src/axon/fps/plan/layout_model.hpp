// The focal-plane layout (src/axon/fps/layout) as the planner sees it: robots, fiducials, and which
// robots must not move.
#pragma once

#include "axon/fps/layout/focal_plane.hpp"
#include "axon/fps/plan/collision.hpp"

#include <vector>

namespace axon::fps::plan {

struct LayoutModelOptions {
  ArmDesign design{};
  double buffer_mm = 2.0;           // every robot's collision buffer
  double fiducial_buffer_mm = 3.0;
  AngleLimits limits{};
};

// Robots in layout order (per-robot arm offsets become calibration offsets).
Result<CollisionModel> model_from_layout(const FocalPlane& plane, const LayoutModelOptions& options = {});
// Disabled and offline robots, in layout order: they stay where they are.
std::vector<bool> frozen_robots(const FocalPlane& plane);

}  // namespace axon::fps::plan

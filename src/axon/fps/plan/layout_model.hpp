// The focal-plane layout (src/axon/fps/layout) as the planner sees it: robots with their own
// geometry, the plane's arms, fiducials, guide cameras, and which robots must not move.
//
// One geometry model: the CollisionModel built here is what the planner, the checker, target
// validation, the host's plan-and-move and position corrections, and the simulator of a layout
// (fps/sim/focal_plane_sim.hpp) use, so a layout's per-robot orientation, arm lengths, zero
// offsets, measured fibres and its guide cameras reach every one of them.
#pragma once

#include "axon/fps/layout/focal_plane.hpp"
#include "axon/fps/plan/collision.hpp"

#include <vector>

namespace axon::fps::plan {

struct LayoutModelOptions {
  // The fibres of the arm design (the arm lengths come from the layout's `arms`).
  std::vector<Fibre> fibres = ArmDesign::default_fibres();
  double buffer_mm = 2.0;           // every robot's collision buffer
  double fiducial_buffer_mm = 3.0;
  AngleLimits limits{};
};

// The arm design of the layout: its ArmLengths with the options' fibres.
ArmDesign design_of(const FocalPlane& plane, const LayoutModelOptions& options = {});
// One robot's calibration: orientation, arm offsets, length corrections against the layout's arms
// (alpha_length_mm - arms.alpha_length_mm, beta_length_mm - arms.beta_tip_mm), measured fibres.
RobotCalibration calibration_of(const RobotSite& robot, const ArmLengths& arms);

// Robots in layout order; fiducials become point obstacles (fiducial_buffer_mm), guide cameras
// segment obstacles named "guide camera <id>" with their own buffers.
ModelSpec model_spec_from_layout(const FocalPlane& plane, const LayoutModelOptions& options = {});
// CollisionModel::build(model_spec_from_layout(plane, options)).
Result<CollisionModel> model_from_layout(const FocalPlane& plane, const LayoutModelOptions& options = {});
// Disabled and offline robots, in layout order: they stay where they are.
std::vector<bool> frozen_robots(const FocalPlane& plane);

}  // namespace axon::fps::plan

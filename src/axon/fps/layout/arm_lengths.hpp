// The arm lengths of a fibre positioner: the one place the nominal design's figures live.
//
// The layout (focal_plane.hpp) carries them per plane and per robot; the planner's kinematics
// (fps/plan/kinematics.hpp), the simulator's robots (fps/sim/positioner_config.hpp) and every
// collision check start from these defaults.
#pragma once

namespace axon::fps {

// Millimetres. The collision body is the segment from the beta axis to beta_collision_mm along the
// beta arm (shorter than the arm: the fibre head's end is rounded).
struct ArmLengths {
  double alpha_length_mm = 7.4;     // alpha axis to beta axis
  double beta_tip_mm = 16.2;        // beta axis to the end of the beta arm
  double beta_collision_mm = 14.7;  // beta axis to the end of the collision segment
  bool operator==(const ArmLengths&) const = default;
};

}  // namespace axon::fps

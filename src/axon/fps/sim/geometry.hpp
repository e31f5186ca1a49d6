// Focal-plane geometry of positioners for collision checks (millimetres, degrees).
//
// A robot's alpha axis sits at its base; the beta axis at the end of the alpha arm. Alpha is
// measured counter-clockwise from the robot's orientation on the plane, beta from the direction of
// the alpha arm (beta = 180 folds the beta arm back over the alpha arm). Only the beta arm is a
// collision body: a capsule around the segment from the beta axis to beta_arm_mm along the arm,
// with the robot's collision buffer as radius. Two robots touch when their segments come closer
// than the sum of their buffers; a robot touches an obstacle (a point or a segment with its own
// radius, e.g. a fiducial with 3 mm) when the distance is below buffer + radius.
//
// The plane's vectors, segments and the exact segment distance are the planner's (fps/plan): the
// simulator's collision check and the planner's dense checker measure with the same primitive.
#pragma once

#include "axon/fps/plan/distance.hpp"
#include "axon/fps/plan/vec2.hpp"

#include <string>

namespace axon::fps::sim {

using plan::Segment;
using plan::segment_distance;
using plan::Vec2;

// A quick test: true when the segments are certainly at least `limit` apart (false: maybe closer).
bool surely_apart(const Segment& s, const Segment& t, double limit) noexcept;

struct RobotGeometry {
  Vec2 base;
  double orientation_deg = 0;
  double alpha_arm_mm = 7.4;
  double beta_arm_mm = 14.7;
  double buffer_mm = 2.0;

  // How far from the base the capsule can reach.
  [[nodiscard]] double reach_mm() const noexcept { return alpha_arm_mm + beta_arm_mm + buffer_mm; }
};

// The beta arm's collision segment for the given arm angles.
Segment beta_segment(const RobotGeometry& g, double alpha_deg, double beta_deg) noexcept;

struct Obstacle {
  Segment shape;             // a == b for a point
  double radius_mm = 3.0;
  std::string name;
};

}  // namespace axon::fps::sim

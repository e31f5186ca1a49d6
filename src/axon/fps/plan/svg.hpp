// SVG drawing of a focal plane: robots with their arms at given poses, collision buffers,
// fiducials and obstacles, contacts, and optionally the paths fibres take over a move.
//
// Plain SVG 1.1 text, no dependency. Focal-plane y points up; the drawing flips it so the picture
// looks like the plane seen from the front (the direction the angles are measured in).
#pragma once

#include "axon/fps/plan/collision.hpp"
#include "axon/fps/plan/trajectory.hpp"

#include <span>
#include <string>
#include <vector>

namespace axon::fps::plan {

struct SvgOptions {
  double px_per_mm = 4.0;
  double margin_mm = 25.0;
  bool buffers = true;      // draw the beta arms' capsules
  bool patrol = false;      // draw each robot's reachable annulus for the first fibre
  bool labels = true;       // robot ids
  std::string title;
};

struct SvgPath {
  std::size_t robot = 0;    // index in the model
  std::vector<Vec2> points;
};

// The fibre `fibre`'s path for each moving robot, sampled every `step_s` seconds.
std::vector<SvgPath> fibre_paths(const CollisionModel& model, std::span<const RobotTrajectory> trajectories,
                                 std::size_t fibre, double step_s);

// poses: one per robot in model order. Contacts (from find_contacts) are drawn in red.
std::string render_svg(const CollisionModel& model, std::span<const Pose> poses, const SvgOptions& options = {},
                       std::span<const SvgPath> paths = {}, std::span<const Contact> contacts = {});

}  // namespace axon::fps::plan

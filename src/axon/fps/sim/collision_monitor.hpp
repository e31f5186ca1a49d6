// The neighbour collision check of a simulated focal plane (pure, no I/O).
//
// The geometry is the planner's collision model (plan::CollisionModel, fps/plan/collision.hpp):
// the beta arms' capsules, fixed obstacles and the pairs that can touch, measured with the same
// segment distance against the same limits. A plane simulated from a layout gets the model
// plan::model_spec_from_layout builds, so its robots collide with the layout's per-robot arm
// lengths, orientations and zero offsets, its fiducials and its guide cameras, exactly where the
// planner says they touch. Poses are the arms' physical angles (what a calibrated robot reports).
//
// Given every robot's arm angles at successive instants, it reports the robots that ran into a
// neighbour or an obstacle: the two bodies are closer than their buffers allow (negative
// clearance, as the planner counts it), they were not at the previous instant or have come closer
// since, and the robot moved in between. A robot standing still is never reported (it cannot feel
// being hit), and bodies already in contact that move apart are left alone, so a robot can back
// away after a collision. Which arm feels the contact is decided by the caller from the `moved`
// flags.
#pragma once

#include "axon/fps/plan/collision.hpp"

#include <cstddef>
#include <optional>
#include <span>
#include <vector>

namespace axon::fps::sim {

using plan::Segment;
using plan::Vec2;
// A fixed obstacle: a point (shape.a == shape.b) or a segment, with its own buffer.
using Obstacle = plan::ObstacleSpec;

class CollisionMonitor {
 public:
  using Pose = plan::Pose;
  struct Contact {
    std::size_t robot = 0;             // index into the model's robots
    std::optional<std::size_t> other;  // the neighbour, or nullopt for an obstacle
    std::size_t obstacle = 0;          // index into the model's obstacles when other is nullopt
    double clearance_mm = 0;           // negative: how far the bodies overlap
    bool alpha_moved = false;
    bool beta_moved = false;
  };

  CollisionMonitor() = default;
  // With neighbours = false only obstacles are checked.
  explicit CollisionMonitor(plan::CollisionModel model, bool neighbours = true);

  [[nodiscard]] const plan::CollisionModel& model() const noexcept { return model_; }
  [[nodiscard]] std::size_t size() const noexcept { return model_.size(); }
  // Pairs close enough to touch at all (0 with neighbours off).
  [[nodiscard]] std::size_t neighbour_pairs() const noexcept {
    return neighbours_ ? model_.robot_pairs().size() : 0;
  }

  // The poses now, one per robot in the model's order. The first call only records.
  std::vector<Contact> update(std::span<const Pose> poses);

 private:
  plan::CollisionModel model_;
  bool neighbours_ = true;
  std::vector<Pose> previous_;
  std::vector<Segment> previous_segments_;  // beta segments at the previous poses
  std::vector<Segment> segments_;           // scratch: at the current poses
};

}  // namespace axon::fps::sim

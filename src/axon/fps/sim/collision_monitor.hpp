// The neighbour collision check of a simulated focal plane (pure, no I/O).
//
// Given every robot's arm angles at successive instants, it reports the robots that ran into a
// neighbour or an obstacle: the two bodies are closer than their buffers allow, they were not at
// the previous instant or have come closer since, and the robot moved in between. A robot standing
// still is never reported (it cannot feel being hit), and bodies already in contact that move
// apart are left alone, so a robot can back away after a collision. Which arm feels the contact is
// decided by the caller from the `moved` flags.
#pragma once

#include "axon/fps/sim/geometry.hpp"

#include <cstddef>
#include <optional>
#include <span>
#include <vector>

namespace axon::fps::sim {

class CollisionMonitor {
 public:
  struct Pose {
    double alpha_deg = 0;
    double beta_deg = 0;
    friend bool operator==(const Pose&, const Pose&) = default;
  };
  struct Contact {
    std::size_t robot = 0;             // index into the geometries
    std::optional<std::size_t> other;  // the neighbour, or nullopt for an obstacle
    std::size_t obstacle = 0;          // index into the obstacles when other is nullopt
    double distance_mm = 0;            // between the segments
    bool alpha_moved = false;
    bool beta_moved = false;
  };

  CollisionMonitor() = default;
  // With neighbours = false only obstacles are checked.
  explicit CollisionMonitor(std::vector<RobotGeometry> robots, bool neighbours = true);

  void set_obstacles(std::vector<Obstacle> obstacles);
  [[nodiscard]] const std::vector<Obstacle>& obstacles() const noexcept { return obstacles_; }
  [[nodiscard]] std::size_t size() const noexcept { return robots_.size(); }
  // Pairs close enough to touch at all (bases within the sum of their reaches).
  [[nodiscard]] std::size_t neighbour_pairs() const noexcept { return pairs_.size(); }

  // The poses now, one per robot in the order given at construction. The first call only records.
  std::vector<Contact> update(std::span<const Pose> poses);

 private:
  struct Pair {
    std::size_t a = 0;
    std::size_t b = 0;
    double limit = 0;
  };

  std::vector<RobotGeometry> robots_;
  std::vector<Pair> pairs_;
  std::vector<Obstacle> obstacles_;
  std::vector<Pose> previous_;
  std::vector<Segment> previous_segments_;  // beta segments at the previous poses
  std::vector<Segment> segments_;           // scratch: at the current poses
};

}  // namespace axon::fps::sim

// The collision model of a focal plane: robots' beta arms as capsules, fiducials and other fixed
// obstacles as buffered points or segments, and the neighbour pairs that can touch at all.
//
// Only the beta arm is a collision body: a capsule around the segment from the beta axis to
// ArmLengths::beta_collision_mm (the robot's own, Positioner::arms()) along the arm, radius = the robot's buffer. Two robots collide when
// their segments come closer than the sum of their buffers; a robot and an obstacle when the
// distance is below the robot's buffer plus the obstacle's. "Clearance" is that distance minus
// the limit: negative means collision.
//
// Pairs are fixed when the model is built: two robots are neighbours when their centres lie closer
// than reach_a + reach_b + buffer_a + buffer_b (48.2 mm for nominal robots), a robot and an
// obstacle when the obstacle's shape comes within reach + both buffers of the centre. Every query
// below takes caller-owned storage, so a planner can call them in its inner loop without
// allocating.
#pragma once

#include "axon/fps/plan/kinematics.hpp"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace axon::fps::plan {

// A fiducial: a fixed point the robots must keep clear of.
struct FiducialSpec {
  std::int32_t id = 0;
  Vec2 position;
  double buffer_mm = 3.0;
};

// Any other fixed obstacle (a guide camera edge, a plate feature): a circle when a == b.
struct ObstacleSpec {
  std::string name;
  Segment shape;
  double buffer_mm = 3.0;
};

struct Obstacle {
  enum class Kind : std::uint8_t { fiducial, other };
  Kind kind = Kind::other;
  std::int32_t id = 0;  // fiducial id (0 for other obstacles)
  std::string name;     // "fiducial <id>" or the obstacle's name
  Segment shape;
  double buffer_mm = 3.0;
};

struct RobotPair {
  std::uint32_t a = 0;  // robot indices, a < b
  std::uint32_t b = 0;
  double limit_mm = 0;  // buffer_a + buffer_b
};

struct ObstaclePair {
  std::uint32_t robot = 0;
  std::uint32_t obstacle = 0;
  double limit_mm = 0;  // robot buffer + obstacle buffer
};

struct Contact {
  enum class Kind : std::uint8_t { robot, obstacle };
  Kind kind = Kind::robot;
  std::uint32_t a = 0;  // robot index
  std::uint32_t b = 0;  // the other robot's index, or the obstacle's index
  double clearance_mm = 0;
};

// Everything a CollisionModel is built from: what model_from_layout (layout_model.hpp) derives from
// a layout, and what the simulator builds its collision check from (fps/sim/collision_monitor.hpp).
struct ModelSpec {
  std::vector<RobotSpec> robots;
  ArmDesign design;
  std::vector<FiducialSpec> fiducials;
  std::vector<ObstacleSpec> obstacles;
};

class CollisionModel {
 public:
  // Fails with PlanErrc::unknown_robot detail "duplicate robot id" when two robots share an id.
  static Result<CollisionModel> build(std::span<const RobotSpec> robots, const ArmDesign& design = {},
                                      std::span<const FiducialSpec> fiducials = {},
                                      std::span<const ObstacleSpec> obstacles = {});
  static Result<CollisionModel> build(const ModelSpec& spec) {
    return build(spec.robots, spec.design, spec.fiducials, spec.obstacles);
  }

  [[nodiscard]] std::size_t size() const noexcept { return robots_.size(); }
  [[nodiscard]] const Positioner& robot(std::size_t i) const noexcept { return robots_[i]; }
  [[nodiscard]] std::span<const Positioner> robots() const noexcept { return robots_; }
  [[nodiscard]] const ArmDesign& design() const noexcept { return design_; }
  [[nodiscard]] std::optional<std::size_t> index_of(std::int32_t id) const noexcept;
  [[nodiscard]] std::span<const Obstacle> obstacles() const noexcept { return obstacles_; }
  [[nodiscard]] std::span<const RobotPair> robot_pairs() const noexcept { return robot_pairs_; }
  [[nodiscard]] std::span<const ObstaclePair> obstacle_pairs() const noexcept { return obstacle_pairs_; }
  // Indices of robot i's neighbours, and indices into robot_pairs() of the pairs it belongs to.
  [[nodiscard]] std::span<const std::uint32_t> neighbours(std::size_t i) const noexcept;
  [[nodiscard]] std::span<const std::uint32_t> pairs_of(std::size_t i) const noexcept;
  // Indices into obstacle_pairs() of robot i's obstacle pairs.
  [[nodiscard]] std::span<const std::uint32_t> obstacle_pairs_of(std::size_t i) const noexcept;

  // Collision segments for one pose per robot (poses.size() == out.size() == size()).
  void segments(std::span<const Pose> poses, std::span<Segment> out) const noexcept;

  [[nodiscard]] double clearance(const RobotPair& p, std::span<const Segment> segs) const noexcept;
  [[nodiscard]] double clearance(const ObstaclePair& p, std::span<const Segment> segs) const noexcept;
  // The smallest clearance robot i has to its neighbours and obstacles with its segment replaced
  // by `seg` (the others from segs): what a planner asks before taking a step.
  [[nodiscard]] double robot_clearance(std::size_t i, const Segment& seg, std::span<const Segment> segs) const noexcept;

  // Every pair with negative clearance, appended to `out` after clearing it. Returns the smallest
  // clearance over all pairs (+infinity when there are none).
  double find_contacts(std::span<const Segment> segs, std::vector<Contact>& out) const;

 private:
  std::vector<Positioner> robots_;
  ArmDesign design_;
  std::vector<Obstacle> obstacles_;
  std::vector<RobotPair> robot_pairs_;
  std::vector<ObstaclePair> obstacle_pairs_;
  // Compressed rows: robot i's entries are [offset[i], offset[i+1]).
  std::vector<std::uint32_t> nb_offset_, nb_index_, nb_pair_;
  std::vector<std::uint32_t> ob_offset_, ob_pair_;
};

}  // namespace axon::fps::plan

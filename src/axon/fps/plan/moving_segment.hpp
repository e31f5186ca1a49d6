// One robot's collision segment along its trajectory, read at increasing times: where it is, how
// fast any of its points can move until the next trajectory point of either arm, and when that is.
// The bound under both conservative advancements: the checker's (checker.hpp) and the shortcuts'
// certificate (smooth.hpp). A point at distance r from an axis turning at w rad/s moves at w * r,
// so no point of the segment moves faster than alpha speed x reach + beta speed x collision length.
#pragma once

#include "axon/fps/plan/distance.hpp"
#include "axon/fps/plan/kinematics.hpp"
#include "axon/fps/plan/trajectory.hpp"

#include <algorithm>
#include <span>

namespace axon::fps::plan {

class MovingSegment {
 public:
  MovingSegment(const Positioner& robot, std::span<const TimedAngle> alpha, std::span<const TimedAngle> beta) noexcept
      : robot_(&robot), alpha_(alpha), beta_(beta) {}
  // The segment at t; then rate() and next() hold from t on. Times going back restart the cursors.
  Segment at(double t) noexcept { return robot_->collision_segment({alpha_.at(t), beta_.at(t)}); }
  // How fast any point of the segment can move until next(), mm/s.
  [[nodiscard]] double rate() const noexcept {
    return (alpha_.speed() * robot_->reach_mm() + beta_.speed() * robot_->collision_length_mm()) * kRad;
  }
  // The next trajectory point of either arm after the last at() (infinity after both ends).
  [[nodiscard]] double next() const noexcept { return std::min(alpha_.next_point(), beta_.next_point()); }

 private:
  const Positioner* robot_;
  AngleCursor alpha_, beta_;
};

// The two bodies a conservative advancement walks: two moving robots, or a moving robot and a
// fixed segment (an obstacle). clearance(t) reads both at t (distance minus `limit`, both buffers);
// rate() and next() then hold for the pair from t on.
struct MovingRobotPair {
  MovingSegment a, b;
  double limit;
  double clearance(double t) noexcept { return segment_distance(a.at(t), b.at(t)) - limit; }
  [[nodiscard]] double rate() const noexcept { return a.rate() + b.rate(); }
  [[nodiscard]] double next() const noexcept { return std::min(a.next(), b.next()); }
};

struct MovingObstaclePair {
  MovingSegment a;
  Segment obstacle;
  double limit;
  double clearance(double t) noexcept { return segment_distance(a.at(t), obstacle) - limit; }
  [[nodiscard]] double rate() const noexcept { return a.rate(); }
  [[nodiscard]] double next() const noexcept { return a.next(); }
};

}  // namespace axon::fps::plan

// The motion of one arm as a piecewise-linear function of simulated time.
//
// Every motion a positioner makes (go-to moves with their approach, trajectories, datum searches,
// calibration sweeps) is known in full when it starts, so it is stored as a list of (time,
// position) corners and evaluated by interpolation. Before the first corner the path sits at its
// first position, after the last at its last. Positions are in degrees at the arm.
#pragma once

#include "axon/fps/sim/sim_time.hpp"

#include <optional>
#include <vector>

namespace axon::fps::sim {

class ArmPath {
 public:
  struct Corner {
    SimTime t{};
    double deg = 0;
  };

  ArmPath() = default;  // empty: no motion
  ArmPath(SimTime start, double deg) { corners_.push_back({start, deg}); }

  // Appends a straight move to `deg` at `deg_per_s` (> 0) from the end of the path.
  ArmPath& line_to(double deg, double deg_per_s);
  // Stays at the last position for `d`.
  ArmPath& hold(SimDuration d);
  // Appends a corner; t earlier than the end is moved to the end.
  ArmPath& point(SimTime t, double deg);

  [[nodiscard]] bool empty() const noexcept { return corners_.empty(); }
  [[nodiscard]] const std::vector<Corner>& corners() const noexcept { return corners_; }
  [[nodiscard]] SimTime start() const noexcept { return corners_.empty() ? SimTime{} : corners_.front().t; }
  [[nodiscard]] SimTime end() const noexcept { return corners_.empty() ? SimTime{} : corners_.back().t; }
  [[nodiscard]] double final_position() const noexcept { return corners_.empty() ? 0.0 : corners_.back().deg; }
  // Position at t (clamped to the path's time span). Requires a non-empty path.
  [[nodiscard]] double at(SimTime t) const noexcept;
  // Signed speed (deg/s) at t: the slope of the segment that contains t (0 outside the path).
  [[nodiscard]] double speed_at(SimTime t) const noexcept;

  // The same path moved by `delta` degrees.
  [[nodiscard]] ArmPath shifted(double delta) const;
  // The first time the path goes strictly below `lo` or above `hi`, if it does.
  [[nodiscard]] std::optional<SimTime> first_outside(double lo, double hi) const noexcept;

  // What an arm that cannot pass [lo, hi] does when driven along this path. With `slip` (open-loop
  // drive) the motor keeps turning against the stop and loses the steps: once the command turns
  // back the arm follows at once, offset by the steps lost. Without (closed loop) the arm waits at
  // the stop until the command comes back inside the range.
  [[nodiscard]] ArmPath clamped(double lo, double hi, bool slip) const;

 private:
  std::vector<Corner> corners_;
};

}  // namespace axon::fps::sim

// Arm trajectories as the positioners execute them: (time, angle) points, linear in between.
//
// Before the first point an arm holds the first angle, after the last point the last angle (the
// positioner starts from where it is and stays where it ends). Times in seconds, angles in degrees.
#pragma once

#include "axon/fps/plan/kinematics.hpp"

#include <cstddef>
#include <span>
#include <vector>

namespace axon::fps::plan {

struct TimedAngle {
  double t_s = 0;
  double deg = 0;
};

struct RobotTrajectory {
  std::vector<TimedAngle> alpha;
  std::vector<TimedAngle> beta;

  // A robot that holds `p` for the whole move.
  static RobotTrajectory hold(Pose p) { return {{{0.0, p.alpha_deg}}, {{0.0, p.beta_deg}}}; }
  // A straight move from `from` (at t0) to `to` (at t1), both arms together.
  static RobotTrajectory linear(Pose from, Pose to, double t0_s, double t1_s) {
    return {{{t0_s, from.alpha_deg}, {t1_s, to.alpha_deg}}, {{t0_s, from.beta_deg}, {t1_s, to.beta_deg}}};
  }
};

// Non-empty, finite, strictly increasing times (PlanErrc::bad_trajectory otherwise).
Result<void> validate(std::span<const TimedAngle> points, std::string_view what);
Result<void> validate(const RobotTrajectory& t);

// The angle at time t (clamped to the ends).
double angle_at(std::span<const TimedAngle> points, double t_s) noexcept;
// When the trajectory's last point comes (the later arm's): the robot stands at its end from then.
double end_time(const RobotTrajectory& t) noexcept;
// The part of `t` between t0_s and t1_s (t0_s < t1_s), times from 0: each arm's angles at both
// ends (interpolated) and its points in between.
RobotTrajectory window(const RobotTrajectory& t, double t0_s, double t1_s);
// The largest |d angle / dt| of any segment, deg/s (0 for a single point).
double max_speed(std::span<const TimedAngle> points) noexcept;

// Reads a trajectory at increasing times in amortised O(1): the cursor remembers the segment.
class AngleCursor {
 public:
  AngleCursor() = default;
  explicit AngleCursor(std::span<const TimedAngle> points) noexcept : points_(points) {}
  // The angle at t_s; t_s must not decrease between calls (else it restarts from the beginning).
  double at(double t_s) noexcept;
  // After at(t): the arm's |deg/s| from t until next_point() (0 before the first point and after
  // the last), and the time of that next point (infinity after the last).
  [[nodiscard]] double speed() const noexcept;
  [[nodiscard]] double next_point() const noexcept;

 private:
  std::span<const TimedAngle> points_;
  std::size_t i_ = 0;
  double last_t_ = -1e300;
};

}  // namespace axon::fps::plan

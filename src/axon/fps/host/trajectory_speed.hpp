// How fast a trajectory drives each arm, against the arms' speed limits. A robot refuses every
// trajectory point that would drive an arm faster than its actuator allows (VALUE_OUT_OF_RANGE,
// point by point), so the host checks before the upload and says what duration would do instead
// of collecting hundreds of refusals.
//
// The firmware starts each arm from where it stands at time 0, so the first segment runs from the
// robot's position to the first point. The limit is the arm speed (deg/s) that the motor speed
// allows through the gearbox: plan::SpeedLimits::from_motor(rpm, gear ratio). The interface
// document asks the actuators for 5000 rpm at the motor and advises 2000-3000 rpm below 0 degC
// (the cold policy); hosts in service use a gear ratio of about 1000:1.
#pragma once

#include "axon/fps/host/positioner.hpp"
#include "axon/fps/plan/planner.hpp"
#include "axon/fps/protocol/trajectory.hpp"

#include <cstdint>
#include <map>
#include <optional>
#include <string>

namespace axon::fps::host {

// The spec's actuator limit and the usual gear ratio: 5000 rpm at 1000:1 is 30 deg/s at the arm.
inline constexpr double kMaxMotorRpm = 5000.0;
inline constexpr double kGearRatio = 1000.0;

struct SpeedCheck {
  double duration_s = 0;  // the trajectory's duration (last point of either arm)
  // The highest segment speed of either arm over its limit (<= 1: the robot accepts it).
  double worst_ratio = 0;
  [[nodiscard]] bool feasible() const noexcept { return worst_ratio <= 1.0; }
  // The shortest duration of the same path with every time stretched by one factor.
  [[nodiscard]] double shortest_duration_s() const noexcept { return duration_s * worst_ratio; }
};

// Checks one trajectory that starts at `start`.
[[nodiscard]] SpeedCheck check_speed(const protocol::Trajectory& trajectory, ArmAngles start,
                                     const plan::SpeedLimits& limits);

// The robot that needs the longest duration, and that duration rounded up to 0.1 s with a margin
// for the firmware's quantisation of positions and times (what to pass as --duration).
struct SlowestRobot {
  std::uint16_t id = 0;
  double needed_s = 0;
  std::size_t too_fast = 0;  // robots whose trajectory the limits refuse
};
// `starts` must hold every robot of `trajectories` (robots without a start are skipped).
[[nodiscard]] std::optional<SlowestRobot> slowest_robot(const std::map<std::uint16_t, protocol::Trajectory>& trajectories,
                                                        const std::map<std::uint16_t, ArmAngles>& starts,
                                                        const plan::SpeedLimits& limits);
// Seconds rounded up to the next 0.1 s after a 0.5 % margin.
[[nodiscard]] double feasible_duration_s(double shortest_s) noexcept;

}  // namespace axon::fps::host

// The controller's side of soft control switching for one axis (manual, chapter 12): a pure object
// driven by the simulated clock that the controller starts when an axis enters mode 1/2 (drive ->
// PC) or 1'/2' (PC -> drive), and asks, each period, how to build the drive's command:
//   - the drive's regulator output bounded by the variable-threshold limiter drive_gain (Imax - Imin)
//     (rho entering, eta leaving; Imin = 0);
//   - the drive's dynamic-model current scaled by drive_gain (its channel carries the PC's current
//     in modes 1/2);
//   - the PC's current (D5, saturated to Imax) scaled by pc_gain (eta entering, rho leaving) when
//     the controller applies the reducer itself (SoftSwitchConfig::reduce_pc_current), else passed
//     as sent (the PC's regulators carry the reducer, RID_2 in the manual's block diagram).
// It also watches the robot: through T1, T2 and T3 the axis must stay within `still_tolerance`
// motor turns of where it stood when the switch started; moved() says when it did not (the
// controller then raises SCS_ROBOT_MOVED and switches the drives off).
#pragma once

#include "axon/c4g/protocol/soft_switch.hpp"
#include "axon/c4g/sim/axis_model.hpp"

namespace axon::c4g::sim {

// SoftSwitchConfig (T1..T3, tolerance, where the reducer sits) is part of RobotConfig: robots.hpp.

class SoftSwitch {
 public:
  // Starts a switch; the first sample() fixes its time origin. `position` is where the axis stands.
  void start(protocol::SwitchDirection direction, double position) noexcept;
  // No switch under way (mode 0, drives off, ...).
  void clear() noexcept { state_ = State::idle; }
  [[nodiscard]] bool active() const noexcept { return state_ != State::idle; }
  [[nodiscard]] protocol::SwitchDirection direction() const noexcept { return direction_; }
  [[nodiscard]] double anchor() const noexcept { return anchor_; }

  // The model at simulated time t [s]. Idle: interval none.
  protocol::SwitchSample sample(const SoftSwitchConfig& config, double t) noexcept;
  [[nodiscard]] const protocol::SwitchSample& last() const noexcept { return last_; }

  // Fills the drive's share of a command for an axis whose current channel belongs to the PC
  // (modes 1, 2 and their standbys): loops, limiter, dynamic-model gain and the PC's current.
  // Samples the model at t first. `pc_current` is the PC's D5, `i_max` the axis's current limit.
  void command(const SoftSwitchConfig& config, double t, double pc_current, double i_max, AxisCommand& cmd) noexcept;

  // True when the last sample required the robot still and `position` is further than the tolerance
  // from where the switch started.
  [[nodiscard]] bool moved(const SoftSwitchConfig& config, double position) const noexcept;

 private:
  enum class State : std::uint8_t { idle, starting, running };
  State state_ = State::idle;
  protocol::SwitchDirection direction_ = protocol::SwitchDirection::to_pc;
  double t0_ = 0;
  double anchor_ = 0;
  protocol::SwitchSample last_{};
};

}  // namespace axon::c4g::sim

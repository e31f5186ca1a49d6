// One simulated motor-side axis: the DSA position loop (P), velocity loop (PI with anti-windup), an
// ideal current loop with saturation, and the motor with its reflected load (inertia, viscous
// friction). Pure and clock-stepped: step() advances by one DSA period, integrating the mechanics at
// the DSP current-loop rate inside it.
//
// Units: positions in motor turns, velocities in turns/s, accelerations in turns/s^2, currents in A.
#pragma once

#include "axon/c4g/sim/robots.hpp"

namespace axon::c4g::sim {

inline constexpr double kDsaPeriod = 500e-6;   // position/velocity loops (manual, timing chapter)
inline constexpr double kDspPeriod = 62.5e-6;  // current loop: the mechanics' integration step

// What the controller hands the DSA for one DSA period.
struct AxisCommand {
  double position = 0;        // position reference [turns] (corrections already included)
  double velocity = 0;        // velocity feed-forward [turns/s]
  double acceleration = 0;    // reference acceleration [turns/s^2], for the dynamic model
  bool loops = true;          // DSA position and velocity loops run (false: the PC closes them)
  double loop_limit = 1.0;    // soft control switching: DSA loop current bounded by loop_limit * Imax
                              // (the variable-threshold limiter, Imin = 0)
  double velocity_add = 0;    // [turns/s] extra input of the velocity loop (mode 8)
  double current_add = 0;     // [A] current contribution from the PC (modes 1, 2, 9)
  bool dynamic_model = true;  // add the dynamic-model current (its channel is the PC's in 1, 2, 9)
  double dynamic_gain = 1.0;  // soft control switching: the dynamic-model current's share (rho / eta)
};

class AxisModel {
 public:
  AxisModel() = default;
  AxisModel(const AxisParams& params, double ratio);

  // Puts the axis at rest at a position, loops cleared.
  void reset(double position) noexcept;
  // One DSA period. powered = false: drives off, the brake holds the axis, no current.
  void step(const AxisCommand& cmd, bool powered) noexcept;

  [[nodiscard]] double position() const noexcept { return pos_; }
  [[nodiscard]] double velocity() const noexcept { return vel_; }
  [[nodiscard]] double current() const noexcept { return current_; }          // reference current
  [[nodiscard]] double dynamic_current() const noexcept { return dyn_current_; }
  [[nodiscard]] double inertia() const noexcept { return inertia_; }           // at the motor [kg m^2]
  [[nodiscard]] bool saturated() const noexcept { return saturated_; }
  [[nodiscard]] const AxisParams& params() const noexcept { return p_; }
  // The velocity-loop gain in A per turn/s (kv = J * bandwidth / kt, per radian turned into turns).
  [[nodiscard]] double kv() const noexcept { return kv_; }

 private:
  AxisParams p_{};
  double inertia_ = 1e-3;
  double kv_ = 0, ki_ = 0;
  double pos_ = 0, vel_ = 0;
  double integral_ = 0;  // velocity-loop integrator [A]
  double current_ = 0, dyn_current_ = 0;
  bool saturated_ = false;
};

}  // namespace axon::c4g::sim

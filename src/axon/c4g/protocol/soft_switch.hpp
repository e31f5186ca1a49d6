// Soft control switching (manual, chapter 12): the clock that hands an axis's control from the
// drive's regulators (DSA) to the PC's and back without a jolt. Pure: no state, no I/O; both the
// controller simulator and the PC side evaluate the same model.
//
// A switch lasts three intervals, measured from the first packet that shows the new mode:
//   T1 pre-switching   chi = 0        the previous owner keeps full control, transients settle;
//   T2 switching       chi 0 -> 1     linear model: chi = (t - T1) / T2, eta = chi, rho = 1 - chi;
//   T3 post-switching  chi = 1        the new owner has full control, its transients settle.
// The robot must stand still (drives on) through all three.
//
// Entering modes 1/2 (drive -> PC): the PC's current is scaled by eta (variable-gain reducer), the
// drive's regulator output is bounded by rho (Imax - Imin) (variable-threshold limiter) and the
// drive's dynamic-model current by rho. Leaving them (1' / 2', PC -> drive) the roles swap: the PC's
// current by rho, the drive's limiter at eta (Imax - Imin), its dynamic model back by eta.
//
// The manual gives no values for T1..T3 (they depend on the robot's reaction times); the defaults
// below (50 + 100 + 50 ms) suit the simulated six-axis robot and are documented in
// docs/c4g-simulator.md. Both sides must be configured alike: the PC only infers the intervals from
// the modes it sees and the time since they appeared.
#pragma once

#include "axon/core/error.hpp"

#include <cstdint>
#include <string_view>

namespace axon::c4g::protocol {

struct SwitchTimes {
  double t1_s = 0.05;  // pre-switching
  double t2_s = 0.10;  // switching (the linear ramp)
  double t3_s = 0.05;  // post-switching
  [[nodiscard]] double total_s() const noexcept { return t1_s + t2_s + t3_s; }
};
// invalid_argument for a negative or non-finite interval.
Result<void> validate(const SwitchTimes& t);

enum class SwitchDirection : std::uint8_t { to_pc, to_drive };
enum class SwitchInterval : std::uint8_t {
  none,       // no switch under way (the axis is not in mode 1, 2, 1' or 2')
  pre,        // T1
  switching,  // T2
  post,       // T3
  done,       // after T3: the new owner has the axis alone
};
std::string_view to_string(SwitchInterval i) noexcept;
std::string_view to_string(SwitchDirection d) noexcept;

struct SwitchSample {
  SwitchDirection direction = SwitchDirection::to_pc;
  SwitchInterval interval = SwitchInterval::none;
  double elapsed_s = 0;  // since the switch started
  double chi = 0;        // 0 before T2, linear through T2, 1 after
  double eta = 0;        // = chi
  double rho = 1;        // = 1 - chi

  // The factor for the PC's current: eta entering, rho leaving; 0 with no switch under way.
  [[nodiscard]] double pc_gain() const noexcept {
    if (interval == SwitchInterval::none) return 0.0;
    return direction == SwitchDirection::to_pc ? eta : rho;
  }
  // The factor for the drive's limiter and dynamic model: rho entering, eta leaving; 1 with none.
  [[nodiscard]] double drive_gain() const noexcept {
    if (interval == SwitchInterval::none) return 1.0;
    return direction == SwitchDirection::to_pc ? rho : eta;
  }
  // T1, T2 or T3: the robot must not move.
  [[nodiscard]] bool robot_must_be_still() const noexcept {
    return interval == SwitchInterval::pre || interval == SwitchInterval::switching || interval == SwitchInterval::post;
  }
};

// The linear switching model at `elapsed_s` after the switch started (negative counts as 0).
SwitchSample linear_switch(const SwitchTimes& times, SwitchDirection direction, double elapsed_s) noexcept;

// The variable-threshold limiter: current bounded to +-factor (Imax - Imin), sign kept.
double limit_current(double current, double factor, double i_max, double i_min = 0.0) noexcept;

}  // namespace axon::c4g::protocol

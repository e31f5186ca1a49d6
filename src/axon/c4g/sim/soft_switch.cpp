#include "axon/c4g/sim/soft_switch.hpp"

#include <algorithm>
#include <cmath>

namespace axon::c4g::sim {

namespace P = protocol;

void SoftSwitch::start(P::SwitchDirection direction, double position) noexcept {
  state_ = State::starting;
  direction_ = direction;
  anchor_ = position;
  t0_ = 0;  // last_ keeps the previous period's sample until the next sample()
}

P::SwitchSample SoftSwitch::sample(const SoftSwitchConfig& config, double t) noexcept {
  if (state_ == State::idle) {
    last_ = P::SwitchSample{};
    return last_;
  }
  if (state_ == State::starting) {
    t0_ = t;
    state_ = State::running;
  }
  last_ = P::linear_switch(config.times, direction_, t - t0_);
  return last_;
}

void SoftSwitch::command(const SoftSwitchConfig& config, double t, double pc_current, double i_max, AxisCommand& cmd) noexcept {
  P::SwitchSample s = sample(config, t);
  // An axis in mode 1/2 without a switch under way (cannot happen through set_mode; be safe): the PC
  // has it.
  if (s.interval == P::SwitchInterval::none) s = P::linear_switch(P::SwitchTimes{0, 0, 0}, P::SwitchDirection::to_pc, 0);
  const double drive = s.drive_gain();
  const double pc = std::clamp(pc_current, -std::fabs(i_max), std::fabs(i_max));
  cmd.loops = drive > 0.0;
  cmd.loop_limit = drive;  // the variable-threshold limiter (Imin = 0), applied inside the drive's loop
  cmd.dynamic_model = drive > 0.0;
  cmd.dynamic_gain = drive;
  cmd.current_add = config.reduce_pc_current ? s.pc_gain() * pc : pc;
}

bool SoftSwitch::moved(const SoftSwitchConfig& config, double position) const noexcept {
  return state_ == State::running && last_.robot_must_be_still() && std::fabs(position - anchor_) > config.still_tolerance;
}

}  // namespace axon::c4g::sim

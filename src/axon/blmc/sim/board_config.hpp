// Configuration of one simulated motor driver board: its two motors, the two ADC inputs and the
// firmware's own constants.
//
// YAML (every key optional; unknown keys are errors):
//   motor: { ...MotorConfig keys... }        both motors (see motor_config.hpp)
//   motors: [ {...}, {...} ]                 per motor, over `motor` (one or two entries)
//   adc: [ {kind: constant, offset: 0.2}, {kind: sine, offset: 0.5, amplitude: 0.4, frequency_hz: 1} ]
//   alignment_s: 2.0                         alignment time on the first enable after power-up
//   vspring_gain_a_per_rev: 1.0              virtual spring mode (ENABLE_VSPRINGx)
//   over_current_trip_a: 0                   trip (error 7) above this commanded current; 0 = off
//   data_while_disabled: false               send the 1 kHz data with the system disabled too
//   system_enabled_at_power_up: false        true: ENABLE_SYS=1 after power-up, the spec's default
//   receive_queue: 64                        frames the firmware buffers between cycles
#pragma once

#include "axon/blmc/sim/adc_signal.hpp"
#include "axon/blmc/sim/motor_config.hpp"
#include "axon/core/clock.hpp"

#include <array>
#include <chrono>
#include <cstddef>

namespace axon::blmc::sim {

struct BoardConfig {
  std::array<MotorConfig, 2> motors{};
  std::array<AdcSignal, 2> adc{};  // A6 (sent in the motor 1 half), B6 (motor 2 half)
  core::Duration alignment_time = std::chrono::seconds(2);
  double vspring_gain_a_per_rev = 1.0;
  double over_current_trip_a = 0.0;
  bool data_while_disabled = false;
  // The spec's command table gives ENABLE_SYS a default of 1. The simulated firmware powers up with
  // the system off unless this is set: the stricter board for a host, which must send ENABLE_SYS=1
  // itself (axon's does; docs/blmc-host.md, "ENABLE_SYS at power-up").
  bool system_enabled_at_power_up = false;
  std::size_t receive_queue = 64;

  [[nodiscard]] Result<void> validate() const;
  static Result<BoardConfig> from_config(const core::ConfigNode& node);
};

}  // namespace axon::blmc::sim

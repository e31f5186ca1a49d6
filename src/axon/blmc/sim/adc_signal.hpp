// A scripted signal for one of the board's additional ADC inputs (A6, B6): constant or a sine,
// read as a fraction of the ADC's full scale and clamped to 0..1 as a real converter saturates.
//
// YAML: { kind: constant, offset: 0.5 }  or  { kind: sine, offset: 0.5, amplitude: 0.25,
//        frequency_hz: 1.0, phase_rad: 0 }
#pragma once

#include "axon/core/config.hpp"
#include "axon/core/error.hpp"

#include <cstdint>

namespace axon::blmc::sim {

struct AdcSignal {
  enum class Kind : std::uint8_t { constant, sine };
  Kind kind = Kind::constant;
  double offset = 0.5;        // full-scale fraction
  double amplitude = 0.0;     // sine only
  double frequency_hz = 0.0;  // sine only
  double phase_rad = 0.0;     // sine only

  // The reading at `t_s` seconds after power-up, within 0..1.
  [[nodiscard]] double value(double t_s) const noexcept;
  [[nodiscard]] Result<void> validate() const;
  static Result<AdcSignal> from_config(const core::ConfigNode& node);
};

}  // namespace axon::blmc::sim

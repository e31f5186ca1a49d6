#include "axon/blmc/sim/adc_signal.hpp"

#include "axon/blmc/protocol/units.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace axon::blmc::sim {

double AdcSignal::value(double t_s) const noexcept {
  double v = offset;
  if (kind == Kind::sine) v += amplitude * std::sin(protocol::kTwoPi * frequency_hz * t_s + phase_rad);
  if (!std::isfinite(v)) return 0.0;
  return std::clamp(v, 0.0, 1.0);
}

Result<void> AdcSignal::validate() const {
  const auto bad = [](std::string what) { return make_error(CoreErrc::invalid_argument, "adc signal: " + what); };
  if (!std::isfinite(offset) || !std::isfinite(amplitude) || !std::isfinite(phase_rad)) return bad("values must be finite");
  if (!std::isfinite(frequency_hz) || frequency_hz < 0 || frequency_hz > 500)
    return bad("frequency_hz must be within 0..500 (the board samples at 1 kHz)");
  return ok();
}

Result<AdcSignal> AdcSignal::from_config(const core::ConfigNode& node) {
  AXON_TRY(node.reject_unknown({"kind", "offset", "amplitude", "frequency_hz", "phase_rad"}));
  AdcSignal s;
  AXON_TRY(kind, node.get_or<std::string>("kind", "constant"));
  if (kind == "sine") {
    s.kind = Kind::sine;
  } else if (kind != "constant") {
    AXON_TRY(k, node.child("kind"));
    return k.error(CoreErrc::config_bad_value, "expected constant or sine, got '" + kind + "'");
  }
  AXON_TRY(offset, node.get_or<double>("offset", s.offset));
  AXON_TRY(amplitude, node.get_or<double>("amplitude", s.amplitude));
  AXON_TRY(freq, node.get_or<double>("frequency_hz", s.frequency_hz));
  AXON_TRY(phase, node.get_or<double>("phase_rad", s.phase_rad));
  s.offset = offset;
  s.amplitude = amplitude;
  s.frequency_hz = freq;
  s.phase_rad = phase;
  if (s.kind == Kind::constant && (node.has("amplitude") || node.has("frequency_hz") || node.has("phase_rad")))
    return node.error(CoreErrc::config_bad_value, "amplitude, frequency_hz and phase_rad need kind: sine");
  auto v = s.validate();
  if (!v) return node.error(CoreErrc::config_bad_value, v.error().detail);
  return s;
}

}  // namespace axon::blmc::sim

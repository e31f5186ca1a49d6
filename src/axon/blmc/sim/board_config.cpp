#include "axon/blmc/sim/board_config.hpp"

#include <fmt/format.h>

#include <cmath>

namespace axon::blmc::sim {

Result<void> BoardConfig::validate() const {
  for (std::size_t i = 0; i < motors.size(); ++i) {
    auto v = motors[i].validate();
    if (!v) return make_error(CoreErrc::invalid_argument, fmt::format("motor {}: {}", i + 1, v.error().detail));
  }
  for (const auto& a : adc) {
    AXON_TRY(a.validate());
  }
  const auto bad = [](std::string_view what) { return make_error(CoreErrc::invalid_argument, fmt::format("board config: {}", what)); };
  if (alignment_time < core::Duration::zero() || alignment_time > std::chrono::minutes(1))
    return bad("alignment time must be within 0..60 s");
  if (!std::isfinite(vspring_gain_a_per_rev) || vspring_gain_a_per_rev < 0) return bad("vspring_gain_a_per_rev must be >= 0");
  if (!std::isfinite(over_current_trip_a) || over_current_trip_a < 0) return bad("over_current_trip_a must be >= 0");
  if (receive_queue < 1 || receive_queue > 65536) return bad("receive_queue must be within 1..65536");
  return ok();
}

Result<BoardConfig> BoardConfig::from_config(const core::ConfigNode& node) {
  AXON_TRY(node.reject_unknown({"motor", "motors", "adc", "alignment_s", "vspring_gain_a_per_rev", "over_current_trip_a",
                                "data_while_disabled", "system_enabled_at_power_up", "receive_queue"}));
  BoardConfig c;
  if (node.has("motor")) {
    AXON_TRY(m, node.child("motor"));
    AXON_TRY(both, MotorConfig::from_config(m));
    c.motors = {both, both};
  }
  if (node.has("motors")) {
    AXON_TRY(ms, node.child("motors"));
    AXON_TRY(items, ms.items());
    if (items.empty() || items.size() > 2) return ms.error(CoreErrc::config_bad_value, "expected one or two motors");
    for (std::size_t i = 0; i < items.size(); ++i) {
      AXON_TRY(m, MotorConfig::from_config(items[i], c.motors[i]));
      c.motors[i] = m;
    }
  }
  if (node.has("adc")) {
    AXON_TRY(as, node.child("adc"));
    AXON_TRY(items, as.items());
    if (items.empty() || items.size() > 2) return as.error(CoreErrc::config_bad_value, "expected one or two ADC signals");
    for (std::size_t i = 0; i < items.size(); ++i) {
      AXON_TRY(s, AdcSignal::from_config(items[i]));
      c.adc[i] = s;
    }
  }
  if (node.has("alignment_s")) {
    AXON_TRY(a, node.get_in<double>("alignment_s", 0.0, 60.0));
    c.alignment_time = std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(a));
  }
  if (node.has("vspring_gain_a_per_rev")) {
    AXON_TRY(g, node.get_in<double>("vspring_gain_a_per_rev", 0.0, 100.0));
    c.vspring_gain_a_per_rev = g;
  }
  if (node.has("over_current_trip_a")) {
    AXON_TRY(t, node.get_in<double>("over_current_trip_a", 0.0, 100.0));
    c.over_current_trip_a = t;
  }
  AXON_TRY(dwd, node.get_or<bool>("data_while_disabled", c.data_while_disabled));
  c.data_while_disabled = dwd;
  AXON_TRY(sys, node.get_or<bool>("system_enabled_at_power_up", c.system_enabled_at_power_up));
  c.system_enabled_at_power_up = sys;
  if (node.has("receive_queue")) {
    AXON_TRY(q, node.get_in<std::size_t>("receive_queue", 1, 65536));
    c.receive_queue = q;
  }
  auto v = c.validate();
  if (!v) return node.error(CoreErrc::config_bad_value, v.error().detail);
  return c;
}

}  // namespace axon::blmc::sim

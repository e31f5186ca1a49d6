// Operation at cold temperatures (interface document, section 10), as a pure function.
//
// From the focal plane's temperatures the policy picks the settings to apply to every robot:
//   - below `limit_speed_below_c` (0 degC): motor speed limited to `cold_motor_rpm` (3000 rpm;
//     5000 rpm otherwise), because friction and the hall sensors cause false collisions;
//   - below `heat_below_c` (-10 degC): alpha holding current raised to `cold_alpha_holding_pct`
//     (45 %, 0 % otherwise) to heat the motors; beta keeps `beta_holding_pct` (30 %).
// "Below" is strict: exactly 0 degC is normal operation. The coldest valid reading of the
// configured sensors decides (all sensors when none are configured). When no valid reading exists
// (every sensor faulty) the policy assumes the worst: limited speed and heating, and says so in
// the report, since too slow and too warm is safe and the opposite is not.
//
// Applying the settings (SET_SPEED, SET_HOLDING_CURRENT) is the host's job; this only decides.
#pragma once

#include "axon/core/config.hpp"
#include "axon/core/error.hpp"
#include "axon/fps/plc/register_map.hpp"

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace axon::fps::plc {

struct ColdPolicyConfig {
  double limit_speed_below_c = 0.0;
  std::uint32_t cold_motor_rpm = 3000;
  std::uint32_t normal_motor_rpm = 5000;
  double heat_below_c = -10.0;
  double cold_alpha_holding_pct = 45.0;
  double normal_alpha_holding_pct = 0.0;
  double beta_holding_pct = 30.0;
  std::vector<std::string> sensors;  // which temperatures count; empty: all

  // Keys as the field names; absent keys keep the defaults.
  static Result<ColdPolicyConfig> from_config(const core::ConfigNode& node);
};

struct ColdSettings {
  std::uint32_t motor_rpm = 5000;
  double alpha_holding_pct = 0;
  double beta_holding_pct = 30;
  bool speed_limited = false;
  bool heating = false;
  bool operator==(const ColdSettings&) const = default;
};

struct ColdDecision {
  ColdSettings settings;
  std::optional<double> coldest_c;  // nullopt: no valid reading
  std::string coldest_sensor;
  std::vector<std::string> notes;   // why, in words

  [[nodiscard]] std::string report() const;
};

[[nodiscard]] ColdDecision cold_policy(std::span<const SensorReading> temperatures, const ColdPolicyConfig& config = {});

}  // namespace axon::fps::plc

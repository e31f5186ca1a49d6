#include "axon/fps/plc/cold_policy.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace axon::fps::plc {

Result<ColdPolicyConfig> ColdPolicyConfig::from_config(const core::ConfigNode& node) {
  ColdPolicyConfig c;
  AXON_TRY(node.reject_unknown({"limit_speed_below_c", "cold_motor_rpm", "normal_motor_rpm", "heat_below_c",
                                "cold_alpha_holding_pct", "normal_alpha_holding_pct", "beta_holding_pct", "sensors"}));
  AXON_TRY(a, node.get_or<double>("limit_speed_below_c", c.limit_speed_below_c));
  AXON_TRY(b, node.get_or<std::uint32_t>("cold_motor_rpm", c.cold_motor_rpm));
  AXON_TRY(d, node.get_or<std::uint32_t>("normal_motor_rpm", c.normal_motor_rpm));
  AXON_TRY(e, node.get_or<double>("heat_below_c", c.heat_below_c));
  c.limit_speed_below_c = a;
  c.cold_motor_rpm = b;
  c.normal_motor_rpm = d;
  c.heat_below_c = e;
  for (auto [key, field] : {std::pair<const char*, double*>{"cold_alpha_holding_pct", &c.cold_alpha_holding_pct},
                            {"normal_alpha_holding_pct", &c.normal_alpha_holding_pct},
                            {"beta_holding_pct", &c.beta_holding_pct}}) {
    if (!node.has(key)) continue;
    AXON_TRY(v, node.get_in<double>(key, 0.0, 100.0));
    *field = v;
  }
  if (node.has("sensors")) {
    AXON_TRY(list, node.child("sensors"));
    AXON_TRY(items, list.items());
    for (const auto& item : items) {
      AXON_TRY(name, item.as<std::string>());
      c.sensors.push_back(name);
    }
  }
  if (c.cold_motor_rpm > c.normal_motor_rpm)
    return node.error(CoreErrc::config_bad_value, "cold_motor_rpm must not exceed normal_motor_rpm");
  return c;
}

ColdDecision cold_policy(std::span<const SensorReading> temperatures, const ColdPolicyConfig& config) {
  ColdDecision d;
  for (const auto& t : temperatures) {
    if (!config.sensors.empty() &&
        std::find(config.sensors.begin(), config.sensors.end(), t.name) == config.sensors.end())
      continue;
    if (!t.value) {
      d.notes.push_back(fmt::format("sensor {} has no valid reading; ignored", t.name));
      continue;
    }
    if (!d.coldest_c || *t.value < *d.coldest_c) {
      d.coldest_c = *t.value;
      d.coldest_sensor = t.name;
    }
  }
  auto& s = d.settings;
  s.beta_holding_pct = config.beta_holding_pct;
  if (!d.coldest_c) {
    s.speed_limited = true;
    s.heating = true;
    d.notes.push_back("no valid temperature: assuming the coldest case");
  } else {
    s.speed_limited = *d.coldest_c < config.limit_speed_below_c;
    s.heating = *d.coldest_c < config.heat_below_c;
  }
  s.motor_rpm = s.speed_limited ? config.cold_motor_rpm : config.normal_motor_rpm;
  s.alpha_holding_pct = s.heating ? config.cold_alpha_holding_pct : config.normal_alpha_holding_pct;
  if (d.coldest_c) {
    d.notes.push_back(fmt::format("coldest reading {:.1f} degC ({})", *d.coldest_c, d.coldest_sensor));
    d.notes.push_back(s.speed_limited ? fmt::format("below {:.1f} degC: motor speed limited to {} rpm",
                                                    config.limit_speed_below_c, s.motor_rpm)
                                      : fmt::format("motor speed {} rpm", s.motor_rpm));
    d.notes.push_back(s.heating ? fmt::format("below {:.1f} degC: alpha holding current {:.0f} % to heat the motors",
                                              config.heat_below_c, s.alpha_holding_pct)
                                : fmt::format("alpha holding current {:.0f} %", s.alpha_holding_pct));
  }
  return d;
}

std::string ColdDecision::report() const {
  std::string s = fmt::format("cold policy: speed {} rpm{}, holding current alpha {:.0f} % beta {:.0f} %{}\n",
                              settings.motor_rpm, settings.speed_limited ? " (limited)" : "", settings.alpha_holding_pct,
                              settings.beta_holding_pct, settings.heating ? " (heating)" : "");
  for (const auto& n : notes) s += "  " + n + "\n";
  return s;
}

}  // namespace axon::fps::plc

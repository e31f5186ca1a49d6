#include "axon/blmc/sim/motor_config.hpp"

#include <fmt/format.h>

#include <cmath>
#include <string>

namespace axon::blmc::sim {
namespace {

Error bad(std::string_view field, std::string_view what) {
  return make_error(CoreErrc::invalid_argument, fmt::format("motor config: {} {}", field, what));
}

bool finite_at_least(double v, double lo) { return std::isfinite(v) && v >= lo; }

Result<void> read(const core::ConfigNode& node, std::string_view key, double& out) {
  if (!node.has(key)) return ok();
  AXON_TRY(v, node.get<double>(key));
  out = v;
  return ok();
}

}  // namespace

Result<void> MotorConfig::validate() const {
  if (!finite_at_least(torque_constant_nm_per_a, 0) || torque_constant_nm_per_a == 0)
    return bad("torque_constant_nm_per_a", "must be positive");
  if (!finite_at_least(rotor_inertia_kgm2, 0) || rotor_inertia_kgm2 == 0) return bad("rotor_inertia_kgm2", "must be positive");
  if (!finite_at_least(viscous_friction_nms, 0)) return bad("viscous_friction_nms", "must be >= 0");
  if (!finite_at_least(coulomb_friction_nm, 0)) return bad("coulomb_friction_nm", "must be >= 0");
  if (!finite_at_least(current_limit_a, 0) || current_limit_a == 0 || current_limit_a > 100)
    return bad("current_limit_a", "must be within (0, 100]");
  if (!finite_at_least(supply_voltage_v, 0)) return bad("supply_voltage_v", "must be >= 0");
  if (supply_voltage_v > 0 && (!std::isfinite(winding_resistance_ohm) || winding_resistance_ohm <= 0))
    return bad("winding_resistance_ohm", "must be positive when supply_voltage_v is set");
  if (!std::isfinite(index_offset_rev) || index_offset_rev < 0 || index_offset_rev >= 1)
    return bad("index_offset_rev", "must be within [0, 1)");
  if (!std::isfinite(initial_position_rev) || std::abs(initial_position_rev) >= 100)
    return bad("initial_position_rev", "must be within (-100, 100)");
  if (!finite_at_least(load.inertia_kgm2, 0)) return bad("load.inertia_kgm2", "must be >= 0");
  if (!finite_at_least(load.spring_nm_per_rad, 0)) return bad("load.spring_nm_per_rad", "must be >= 0");
  if (!std::isfinite(load.spring_center_rev)) return bad("load.spring_center_rev", "must be finite");
  return ok();
}

Result<MotorConfig> MotorConfig::from_config(const core::ConfigNode& node) { return from_config(node, MotorConfig{}); }

Result<MotorConfig> MotorConfig::from_config(const core::ConfigNode& node, MotorConfig c) {
  AXON_TRY(node.reject_unknown({"torque_constant_nm_per_a", "rotor_inertia_kgm2", "viscous_friction_nms",
                                "coulomb_friction_nm", "current_limit_a", "supply_voltage_v", "winding_resistance_ohm",
                                "encoder_counts_per_rev", "index_offset_rev", "initial_position_rev", "load"}));
  AXON_TRY(read(node, "torque_constant_nm_per_a", c.torque_constant_nm_per_a));
  AXON_TRY(read(node, "rotor_inertia_kgm2", c.rotor_inertia_kgm2));
  AXON_TRY(read(node, "viscous_friction_nms", c.viscous_friction_nms));
  AXON_TRY(read(node, "coulomb_friction_nm", c.coulomb_friction_nm));
  AXON_TRY(read(node, "current_limit_a", c.current_limit_a));
  AXON_TRY(read(node, "supply_voltage_v", c.supply_voltage_v));
  AXON_TRY(read(node, "winding_resistance_ohm", c.winding_resistance_ohm));
  AXON_TRY(cpr, node.get_or<std::uint32_t>("encoder_counts_per_rev", c.encoder_counts_per_rev));
  c.encoder_counts_per_rev = cpr;
  AXON_TRY(read(node, "index_offset_rev", c.index_offset_rev));
  AXON_TRY(read(node, "initial_position_rev", c.initial_position_rev));
  if (node.has("load")) {
    AXON_TRY(l, node.child("load"));
    AXON_TRY(l.reject_unknown({"inertia_kgm2", "spring_nm_per_rad", "spring_center_rev"}));
    AXON_TRY(read(l, "inertia_kgm2", c.load.inertia_kgm2));
    AXON_TRY(read(l, "spring_nm_per_rad", c.load.spring_nm_per_rad));
    AXON_TRY(read(l, "spring_center_rev", c.load.spring_center_rev));
  }
  auto v = c.validate();
  if (!v) return node.error(CoreErrc::config_bad_value, v.error().detail);
  return c;
}

}  // namespace axon::blmc::sim

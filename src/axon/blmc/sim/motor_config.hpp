// Physical parameters of one simulated motor (and what it drives), in SI units unless the name
// says otherwise. The defaults describe the small outrunner motors of the open dynamic robot
// boards (torque constant 0.025 N m/A, a 5000-line encoder read in quadrature) with nothing
// attached to the shaft.
//
// YAML (every key optional; unknown keys are errors):
//   torque_constant_nm_per_a: 0.025     rotor_inertia_kgm2: 6.0e-6
//   viscous_friction_nms: 2.0e-6        coulomb_friction_nm: 2.0e-3
//   current_limit_a: 12                 supply_voltage_v: 24      winding_resistance_ohm: 0.3
//   encoder_counts_per_rev: 20000       index_offset_rev: 0.0     initial_position_rev: 0.0
//   load: { inertia_kgm2: 0, spring_nm_per_rad: 0, spring_center_rev: 0 }
#pragma once

#include "axon/core/config.hpp"
#include "axon/core/error.hpp"

#include <cstdint>

namespace axon::blmc::sim {

// Something attached to the shaft: extra inertia and a linear spring towards a rest position.
struct LoadConfig {
  double inertia_kgm2 = 0.0;       // added to the rotor inertia
  double spring_nm_per_rad = 0.0;  // restoring torque per radian away from spring_center_rev
  double spring_center_rev = 0.0;  // rest position of the spring, in encoder revolutions
};

struct MotorConfig {
  double torque_constant_nm_per_a = 0.025;  // kt: shaft torque per ampere of Iq (also the back-EMF constant, V s/rad)
  double rotor_inertia_kgm2 = 6.0e-6;       // J of the rotor alone
  double viscous_friction_nms = 2.0e-6;     // torque per rad/s, opposing motion
  double coulomb_friction_nm = 2.0e-3;      // constant torque opposing motion; also the breakaway torque
  double current_limit_a = 12.0;            // the driver never applies more than this (either sign)
  // Back-EMF limit: the driver cannot push more current than (V - kt w) / R into a spinning motor.
  // supply_voltage_v = 0 switches this off.
  double supply_voltage_v = 24.0;
  double winding_resistance_ohm = 0.3;
  // Encoder: counts per revolution after quadrature (0 = ideal, unquantised), where the index mark
  // sits within each revolution (0 <= offset < 1), and the encoder reading at power-up.
  std::uint32_t encoder_counts_per_rev = 20000;
  double index_offset_rev = 0.0;
  double initial_position_rev = 0.0;
  LoadConfig load;

  // invalid_argument naming the field for non-finite, negative or inconsistent values.
  [[nodiscard]] Result<void> validate() const;
  // Reads the keys above from a map node over the defaults (or over `base`); then validates.
  static Result<MotorConfig> from_config(const core::ConfigNode& node);
  static Result<MotorConfig> from_config(const core::ConfigNode& node, MotorConfig base);
};

}  // namespace axon::blmc::sim

#include "axon/blmc/protocol/units.hpp"

#include "axon/blmc/protocol/error.hpp"

#include <fmt/format.h>

#include <cmath>

namespace axon::blmc::protocol {

Result<JointScaling> JointScaling::make(double gear_ratio, double torque_constant) {
  if (!std::isfinite(gear_ratio) || gear_ratio <= 0.0) {
    return Error(ProtocolErrc::value_out_of_range,
                 fmt::format("gear ratio {} must be finite and positive", gear_ratio));
  }
  if (!std::isfinite(torque_constant) || torque_constant <= 0.0) {
    return Error(ProtocolErrc::value_out_of_range,
                 fmt::format("torque constant {} N m/A must be finite and positive", torque_constant));
  }
  return JointScaling(gear_ratio, torque_constant);
}

double JointScaling::joint_rad(double motor_rev) const noexcept {
  return revolutions_to_rad(motor_rev) / gear_ratio_;
}
double JointScaling::motor_rev(double joint_rad) const noexcept {
  return rad_to_revolutions(joint_rad) * gear_ratio_;
}
double JointScaling::joint_rad_per_s(double motor_krpm) const noexcept {
  return krpm_to_rad_per_s(motor_krpm) / gear_ratio_;
}
double JointScaling::motor_krpm(double joint_rad_per_s) const noexcept {
  return rad_per_s_to_krpm(joint_rad_per_s) * gear_ratio_;
}
double JointScaling::joint_torque_nm(double motor_current_a) const noexcept {
  return motor_current_a * torque_constant_ * gear_ratio_;
}
double JointScaling::motor_current_a(double joint_torque_nm) const noexcept {
  return joint_torque_nm / (torque_constant_ * gear_ratio_);
}

}  // namespace axon::blmc::protocol

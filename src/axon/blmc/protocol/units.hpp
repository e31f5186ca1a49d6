// Physical units of the blmc wire and conversions to joint units through a gearbox.
//
// On the wire (all Q24, see q24.hpp):
//   current      amperes (A), the q-axis current Iq
//   position     motor revolutions (0.5 = half a turn of the motor shaft; the firmware rolls over
//                at +-100 revolutions)
//   velocity     thousands of motor revolutions per minute (krpm)
//   ADC input    a fraction of the ADC's full scale, 0..1
//
// Joint units sit behind a gearbox: joint angle = motor angle / gear ratio, joint torque =
// torque constant (N m per A, at the motor) * current * gear ratio. JointScaling holds the two
// constants of one joint and checks them once, so the conversions themselves cannot fail (the
// result still has to pass to_q24's range check before it goes on the wire).
#pragma once

#include "axon/core/error.hpp"

#include <numbers>

namespace axon::blmc::protocol {

inline constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Motor-side conversions, no gearbox involved.
constexpr double revolutions_to_rad(double rev) noexcept { return rev * kTwoPi; }
constexpr double rad_to_revolutions(double rad) noexcept { return rad / kTwoPi; }
// 1 krpm = 1000 rev / 60 s.
constexpr double krpm_to_rad_per_s(double krpm) noexcept { return krpm * 1000.0 * kTwoPi / 60.0; }
constexpr double rad_per_s_to_krpm(double rad_s) noexcept { return rad_s * 60.0 / (1000.0 * kTwoPi); }

class JointScaling {
 public:
  // gear_ratio: motor turns per joint turn (e.g. 9 for a 9:1 reduction); torque_constant: N m per A
  // at the motor shaft. Both must be finite and positive, else ProtocolErrc::value_out_of_range.
  static Result<JointScaling> make(double gear_ratio, double torque_constant);

  [[nodiscard]] double gear_ratio() const noexcept { return gear_ratio_; }
  [[nodiscard]] double torque_constant() const noexcept { return torque_constant_; }

  [[nodiscard]] double joint_rad(double motor_rev) const noexcept;
  [[nodiscard]] double motor_rev(double joint_rad) const noexcept;
  [[nodiscard]] double joint_rad_per_s(double motor_krpm) const noexcept;
  [[nodiscard]] double motor_krpm(double joint_rad_per_s) const noexcept;
  [[nodiscard]] double joint_torque_nm(double motor_current_a) const noexcept;
  [[nodiscard]] double motor_current_a(double joint_torque_nm) const noexcept;

 private:
  JointScaling(double g, double kt) noexcept : gear_ratio_(g), torque_constant_(kt) {}
  double gear_ratio_;
  double torque_constant_;
};

}  // namespace axon::blmc::protocol

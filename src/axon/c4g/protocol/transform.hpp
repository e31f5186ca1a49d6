// Kinematic influence: converting between link-side joint values (radians) and motor-side values
// (motor turns) for one arm.
//
//   K_r2  diagonal of the signed transmission ratios kr_i (armNTxRate)
//   K_1   identity plus the wrist's influence coefficients: K_1(4,5) = k54, K_1(4,6) = k64,
//         K_1(5,6) = k65 (1-based rows/columns), with k54, k64, k65 = armNAxInfo[4], [5], [6]
//         counted from 1, i.e. the C elements [3], [4], [5]
//   K_r = K_r2 K_1^-T  (motor turns per link turn, lower triangular)
//
//   motor position [turns] = K_r q / 2 pi + q0    (q0: calibration constants, armNCalData)
//   link position [rad]    = 2 pi K_r^-1 (motor - q0)
//   velocities: the same without q0, in whatever time unit the caller uses on both sides (the packet's
//   "delta motor turns" is turns per cycle: multiply turns/s by the period in seconds).
//
// The arm's axes are its logical axes 1..n, n = the last axis with a non-zero transmission ratio.
// Vectors have a fixed capacity of 10: no allocation after construction.
#pragma once

#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/core/error.hpp"

#include <Eigen/Dense>

#include <cstddef>
#include <span>

namespace axon::c4g::protocol {

class ArmTransform {
 public:
  using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 10, 1>;
  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 10, 10>;

  // arm is 1..4. singular_transform when the arm has no axis or a zero ratio below its last axis.
  static Result<ArmTransform> from_init(const InitPacket& init, std::size_t arm);
  // ratios, calibration: one per axis (1..10 of them); influence: the arm's coefficient array as in
  // the initialization packet (only its elements [3], [4], [5] are used; may be shorter).
  static Result<ArmTransform> make(std::span<const double> ratios, std::span<const double> influence,
                                   std::span<const double> calibration);

  std::size_t axes() const noexcept { return static_cast<std::size_t>(kr_.rows()); }
  const Matrix& kr() const noexcept { return kr_; }          // K_r
  const Matrix& kr_inverse() const noexcept { return kr_inv_; }
  const Matrix& k1() const noexcept { return k1_; }          // K_1
  const Vector& calibration() const noexcept { return q0_; }

  // Vectors must have axes() elements (checked with an assertion in debug builds).
  Vector motor_position(const Vector& link_rad) const;        // -> motor turns
  Vector link_position(const Vector& motor_turns) const;      // -> rad
  Vector motor_velocity(const Vector& link_rad_per_t) const;  // -> motor turns per t
  Vector link_velocity(const Vector& motor_turns_per_t) const;  // -> rad per t

 private:
  Matrix kr_, kr_inv_, k1_;
  Vector q0_;
};

}  // namespace axon::c4g::protocol

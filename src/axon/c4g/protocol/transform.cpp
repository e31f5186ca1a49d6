#include "axon/c4g/protocol/transform.hpp"

#include "axon/c4g/protocol/error.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <numbers>

namespace axon::c4g::protocol {

Result<ArmTransform> ArmTransform::from_init(const InitPacket& init, std::size_t arm) {
  if (arm < 1 || arm > kMaxArms)
    return Error(ProtocolErrc::value_out_of_range, fmt::format("c4g transform: arm {} (arms are 1..4)", arm));
  const auto& tx = init.transmission_ratio[arm - 1];
  std::size_t n = 0;
  for (std::size_t i = 0; i < kAxesPerArm; ++i)
    if (tx[i] != 0.0f) n = i + 1;
  if (n == 0) return Error(ProtocolErrc::singular_transform, fmt::format("c4g transform: arm {} has no axis", arm));
  std::array<double, kAxesPerArm> ratios{}, influence{}, calibration{};
  for (std::size_t i = 0; i < kAxesPerArm; ++i) {
    ratios[i] = tx[i];
    influence[i] = init.influence[arm - 1][i];
    calibration[i] = init.calibration[arm - 1][i];
  }
  auto t = make(std::span(ratios).first(n), influence, std::span(calibration).first(n));
  if (!t) return Error(t.error().code, fmt::format("arm {}: {}", arm, t.error().detail));
  return t;
}

Result<ArmTransform> ArmTransform::make(std::span<const double> ratios, std::span<const double> influence,
                                        std::span<const double> calibration) {
  const std::size_t n = ratios.size();
  if (n < 1 || n > kAxesPerArm || calibration.size() != n)
    return Error(ProtocolErrc::value_out_of_range,
                 fmt::format("c4g transform: {} ratios and {} calibration constants (1..10, equal)", n, calibration.size()));
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(ratios[i]) || !std::isfinite(calibration[i]))
      return Error(ProtocolErrc::not_finite, fmt::format("c4g transform: axis {}", i + 1));
    if (ratios[i] == 0.0)
      return Error(ProtocolErrc::singular_transform, fmt::format("c4g transform: axis {} has ratio 0", i + 1));
  }
  for (double k : influence)
    if (!std::isfinite(k)) return Error(ProtocolErrc::not_finite, "c4g transform: influence coefficient");
  auto coeff = [&](std::size_t i) { return i < influence.size() ? influence[i] : 0.0; };

  ArmTransform t;
  const auto m = static_cast<Eigen::Index>(n);
  t.k1_ = Matrix::Identity(m, m);
  // Influence of the wrist axes, placed only where the arm has those axes.
  if (n >= 5) t.k1_(3, 4) = coeff(3);  // k54
  if (n >= 6) {
    t.k1_(3, 5) = coeff(4);  // k64
    t.k1_(4, 5) = coeff(5);  // k65
  }
  Matrix kr2 = Matrix::Zero(m, m);
  t.q0_.resize(m);
  for (std::size_t i = 0; i < n; ++i) {
    kr2(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i)) = ratios[i];
    t.q0_(static_cast<Eigen::Index>(i)) = calibration[i];
  }
  // K_1 is unit upper triangular, so K_1^T is unit lower triangular and always invertible.
  const Matrix k1_inv_t = t.k1_.transpose().triangularView<Eigen::UnitLower>().solve(Matrix::Identity(m, m));
  t.kr_ = kr2 * k1_inv_t;
  // K_r is lower triangular with the non-zero ratios on its diagonal.
  t.kr_inv_ = t.kr_.triangularView<Eigen::Lower>().solve(Matrix::Identity(m, m));
  return t;
}

ArmTransform::Vector ArmTransform::motor_position(const Vector& q) const {
  return kr_ * q / (2.0 * std::numbers::pi) + q0_;
}
ArmTransform::Vector ArmTransform::link_position(const Vector& motor) const {
  return 2.0 * std::numbers::pi * (kr_inv_ * (motor - q0_));
}
ArmTransform::Vector ArmTransform::motor_velocity(const Vector& dq) const { return kr_ * dq / (2.0 * std::numbers::pi); }
ArmTransform::Vector ArmTransform::link_velocity(const Vector& dm) const { return 2.0 * std::numbers::pi * (kr_inv_ * dm); }

}  // namespace axon::c4g::protocol

// Units on the fps wire and their checked conversions to physical values.
//
//   Angle           int32, 2^30 steps per full turn of the arm: 90 deg = 268435456 (range about +-720 deg)
//   Time            uint32, 0.5 ms steps: 10 s = 20000 (up to about 24.8 days)
//   MotorSpeed      uint32 rpm at the motor, before the gearbox (arm speed = motor speed / gear ratio)
//   CurrentPercent  uint32 percent of the motor's rated current, 0..100 (set current, holding current)
//   CollisionMargin int32, -30..30 (defaults: alpha -5, beta 20)
//
// Conversions from physical values round to the nearest step (halves away from zero). A value that
// is not finite, or falls outside the field's range after rounding, is ProtocolErrc::value_out_of_range:
// nothing is ever wrapped or clamped. Conversions to physical values are exact up to double rounding.
#pragma once

#include "axon/core/error.hpp"

#include <compare>
#include <cstdint>

namespace axon::fps::protocol {

inline constexpr std::int64_t kStepsPerTurn = std::int64_t{1} << 30;
inline constexpr double kDegreesPerTurn = 360.0;
inline constexpr std::int64_t kTicksPerSecond = 2000;  // 0.5 ms per tick

class Angle {
 public:
  constexpr Angle() = default;
  static constexpr Angle from_steps(std::int32_t steps) noexcept { return Angle(steps); }
  static Result<Angle> from_degrees(double degrees);

  [[nodiscard]] constexpr std::int32_t steps() const noexcept { return steps_; }
  [[nodiscard]] double degrees() const noexcept;

  friend constexpr auto operator<=>(const Angle&, const Angle&) noexcept = default;

 private:
  constexpr explicit Angle(std::int32_t s) noexcept : steps_(s) {}
  std::int32_t steps_ = 0;
};

class Time {
 public:
  constexpr Time() = default;
  static constexpr Time from_ticks(std::uint32_t ticks) noexcept { return Time(ticks); }
  static Result<Time> from_seconds(double seconds);

  [[nodiscard]] constexpr std::uint32_t ticks() const noexcept { return ticks_; }
  [[nodiscard]] double seconds() const noexcept;

  friend constexpr auto operator<=>(const Time&, const Time&) noexcept = default;

 private:
  constexpr explicit Time(std::uint32_t t) noexcept : ticks_(t) {}
  std::uint32_t ticks_ = 0;
};

class MotorSpeed {
 public:
  constexpr MotorSpeed() = default;
  static constexpr MotorSpeed from_wire(std::uint32_t rpm) noexcept { return MotorSpeed(rpm); }
  // Whole rpm at the motor; negative or above 2^32-1 is an error.
  static Result<MotorSpeed> from_rpm(std::int64_t rpm);
  // From the arm's angular speed in degrees per second and the motor-to-arm gear ratio (about 1000
  // in service: 12 deg/s at the arm is 2000 rpm at the motor). The ratio must be positive.
  static Result<MotorSpeed> from_arm_speed(double degrees_per_second, double gear_ratio);

  [[nodiscard]] constexpr std::uint32_t rpm() const noexcept { return rpm_; }
  // Degrees per second at the arm for the given gear ratio.
  [[nodiscard]] double arm_speed(double gear_ratio) const noexcept;

  friend constexpr auto operator<=>(const MotorSpeed&, const MotorSpeed&) noexcept = default;

 private:
  constexpr explicit MotorSpeed(std::uint32_t r) noexcept : rpm_(r) {}
  std::uint32_t rpm_ = 0;
};

class CurrentPercent {
 public:
  static constexpr std::int64_t kMax = 100;
  constexpr CurrentPercent() = default;
  // 0..100; anything else is an error.
  static Result<CurrentPercent> from_percent(std::int64_t percent);

  [[nodiscard]] constexpr std::uint32_t percent() const noexcept { return percent_; }

  friend constexpr auto operator<=>(const CurrentPercent&, const CurrentPercent&) noexcept = default;

 private:
  constexpr explicit CurrentPercent(std::uint32_t p) noexcept : percent_(p) {}
  std::uint32_t percent_ = 0;
};

// Default idle holding currents after power-up, percent.
inline constexpr std::uint32_t kDefaultHoldingCurrentAlpha = 0;
inline constexpr std::uint32_t kDefaultHoldingCurrentBeta = 30;

class CollisionMargin {
 public:
  static constexpr std::int64_t kMin = -30;
  static constexpr std::int64_t kMax = 30;
  constexpr CollisionMargin() = default;
  // -30..30; anything else is an error.
  static Result<CollisionMargin> from_value(std::int64_t value);

  [[nodiscard]] constexpr std::int32_t value() const noexcept { return value_; }

  friend constexpr auto operator<=>(const CollisionMargin&, const CollisionMargin&) noexcept = default;

 private:
  constexpr explicit CollisionMargin(std::int32_t v) noexcept : value_(v) {}
  std::int32_t value_ = 0;
};

// Collision margins after power-up (they are not stored in flash).
inline constexpr std::int32_t kDefaultCollisionMarginAlpha = -5;
inline constexpr std::int32_t kDefaultCollisionMarginBeta = 20;

}  // namespace axon::fps::protocol

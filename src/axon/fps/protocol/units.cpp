#include "axon/fps/protocol/units.hpp"

#include "axon/fps/protocol/error.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>

namespace axon::fps::protocol {
namespace {

// Rounds to the nearest integer (halves away from zero) and checks [lo, hi]; NaN and infinities fail.
Result<std::int64_t> round_checked(double v, double lo, double hi, std::string_view what, double input,
                                   std::string_view unit) {
  if (!std::isfinite(v)) {
    return Error(ProtocolErrc::value_out_of_range, fmt::format("{}: {} {} is not a finite number", what, input, unit));
  }
  const double r = std::round(v);
  if (r < lo || r > hi) {
    return Error(ProtocolErrc::value_out_of_range,
                 fmt::format("{}: {} {} is outside {}..{} on the wire", what, input, unit, lo, hi));
  }
  return static_cast<std::int64_t>(r);
}

constexpr double kI32Min = std::numeric_limits<std::int32_t>::min();
constexpr double kI32Max = std::numeric_limits<std::int32_t>::max();
constexpr double kU32Max = std::numeric_limits<std::uint32_t>::max();

}  // namespace

Result<Angle> Angle::from_degrees(double degrees) {
  AXON_TRY(steps, round_checked(degrees / kDegreesPerTurn * static_cast<double>(kStepsPerTurn), kI32Min, kI32Max,
                                "angle", degrees, "deg"));
  return Angle(static_cast<std::int32_t>(steps));
}

double Angle::degrees() const noexcept {
  return static_cast<double>(steps_) * kDegreesPerTurn / static_cast<double>(kStepsPerTurn);
}

Result<Time> Time::from_seconds(double seconds) {
  AXON_TRY(ticks, round_checked(seconds * static_cast<double>(kTicksPerSecond), 0, kU32Max, "time", seconds, "s"));
  return Time(static_cast<std::uint32_t>(ticks));
}

double Time::seconds() const noexcept { return static_cast<double>(ticks_) / static_cast<double>(kTicksPerSecond); }

Result<MotorSpeed> MotorSpeed::from_rpm(std::int64_t rpm) {
  if (rpm < 0 || rpm > static_cast<std::int64_t>(std::numeric_limits<std::uint32_t>::max())) {
    return Error(ProtocolErrc::value_out_of_range, fmt::format("motor speed {} rpm", rpm));
  }
  return MotorSpeed(static_cast<std::uint32_t>(rpm));
}

Result<MotorSpeed> MotorSpeed::from_arm_speed(double degrees_per_second, double gear_ratio) {
  if (!std::isfinite(gear_ratio) || gear_ratio <= 0) {
    return Error(ProtocolErrc::value_out_of_range, fmt::format("gear ratio {} must be positive", gear_ratio));
  }
  // deg/s at the arm -> turns per minute at the arm -> turns per minute at the motor.
  const double rpm = degrees_per_second / kDegreesPerTurn * 60.0 * gear_ratio;
  AXON_TRY(r, round_checked(rpm, 0, kU32Max, "arm speed", degrees_per_second, "deg/s"));
  return MotorSpeed(static_cast<std::uint32_t>(r));
}

double MotorSpeed::arm_speed(double gear_ratio) const noexcept {
  return static_cast<double>(rpm_) / gear_ratio / 60.0 * kDegreesPerTurn;
}

Result<CurrentPercent> CurrentPercent::from_percent(std::int64_t percent) {
  if (percent < 0 || percent > kMax) {
    return Error(ProtocolErrc::value_out_of_range, fmt::format("current {} % is outside 0..100", percent));
  }
  return CurrentPercent(static_cast<std::uint32_t>(percent));
}

Result<CollisionMargin> CollisionMargin::from_value(std::int64_t value) {
  if (value < kMin || value > kMax) {
    return Error(ProtocolErrc::value_out_of_range, fmt::format("collision margin {} is outside -30..30", value));
  }
  return CollisionMargin(static_cast<std::int32_t>(value));
}

}  // namespace axon::fps::protocol

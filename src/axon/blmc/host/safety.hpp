// Host-side safety checks of one board, as a pure function of the latest measurements, the
// currents a controller asks for and the time: no I/O, no allocation, no locks, so the real-time
// cycle can run it and tests can drive it frame by frame.
//
// Every cycle, in this order:
//   1. faults (latched until reset): the board reports an error code, or one the spec does not
//      define (6: the board says something is wrong; the host cannot tell what, so it stops at
//      once rather than wait for the data to go stale); the board reports itself or
//      a used motor disabled; a used quantity (current, position, velocity, optionally ADC, and the
//      status) arrived longer ago than its stale limit, or never since arm(); a position outside
//      its limits; a non-finite current from the controller. A fault makes every later output
//      zero; the caller disables the motors and reports fault() (describe() names the board's
//      error code, the quantity or the limit).
//   2. velocity limit: a motor turning faster than the limit gets zero current this cycle (not a
//      fault: the motor coasts and control resumes once it slows down).
//   3. current clamp: each current is limited to +-max_current.
// Motors not in use always get zero current and are not checked.
#pragma once

#include "axon/blmc/host/measurements.hpp"
#include "axon/blmc/protocol/status.hpp"
#include "axon/core/clock.hpp"
#include "axon/core/error.hpp"

#include <array>
#include <chrono>
#include <cstdint>
#include <string>

namespace axon::blmc::host {

using namespace std::chrono_literals;

struct PositionLimit {
  bool enabled = false;
  double min_rev = 0.0;
  double max_rev = 0.0;
};

struct SafetyLimits {
  std::array<bool, 2> motors{true, true};  // which motors are in use
  double max_current_a = 2.0;              // |Iq| sent to the board
  double max_velocity_krpm = 2.0;          // above it the motor gets zero current
  std::array<PositionLimit, 2> position{};
  core::Duration stale_after = 10ms;       // current, position, velocity (and ADC if checked)
  core::Duration status_stale_after = 2500ms;  // the board sends status once per second
  bool check_adc = false;                  // ADC frames are optional for control

  // HostErrc::invalid_argument, in words, for a current or velocity limit that is not a finite
  // number > 0, a stale limit that is not > 0, or an enabled position limit with min >= max.
  [[nodiscard]] Result<void> validate() const;
};

enum class FaultKind : std::uint8_t {
  none,
  board_error,     // status error code != 0 (board_error holds it)
  undocumented_error,  // status error code 6, which the spec does not define (undocumented_code)
  board_disabled,  // status shows the system or a used motor disabled
  stale_data,      // quantity holds which message is missing
  position_limit,  // motor, value, limit
  bad_command,     // the controller asked for a non-finite current (motor)
};
const char* to_string(FaultKind k) noexcept;

struct Fault {
  FaultKind kind = FaultKind::none;
  int motor = -1;  // 0 or 1 when the fault concerns one motor
  protocol::ErrorCode board_error = protocol::ErrorCode::none;
  // The raw code of an undocumented board error (6), for that fault or, like board_error, one
  // learnt from the board's next status after a host-side fault; 0 = none.
  std::uint8_t undocumented_code = 0;
  Quantity quantity = Quantity::status;
  double value = 0.0;  // the position or the age (seconds) that tripped
  double limit = 0.0;
  core::TimePoint at{};

  // For logs and users (allocates: call outside the real-time cycle), e.g.
  // "board error ENCODER", "board sent undocumented error code 6",
  // "stale data: no velocity frame for 0.012 s (limit 0.010 s)".
  // A stale-data or other host-side fault also names the board's error code when the board's
  // next status told it (ControlLoop waits for it briefly).
  [[nodiscard]] std::string describe() const;
  [[nodiscard]] Fault without_board_error() const noexcept {
    Fault f = *this;
    f.board_error = protocol::ErrorCode::none;
    f.undocumented_code = 0;
    return f;
  }
};

struct SafetyCounters {
  std::uint64_t cycles = 0;
  std::uint64_t clamped = 0;          // motor-cycles whose current was clamped
  std::uint64_t velocity_limited = 0; // motor-cycles zeroed by the velocity limit
};

class Safety {
 public:
  explicit Safety(SafetyLimits limits = {}) noexcept : limits_(limits) {}

  // Starts supervision: quantities never received count as stale from this time on.
  void arm(core::TimePoint now) noexcept;
  // Clears a latched fault and re-arms at `now`.
  void reset(core::TimePoint now) noexcept;

  // The currents to send this cycle. Zero for both motors once a fault is latched; the cycle
  // that latches it returns true from newly_tripped().
  MotorPair apply(const Measurements& m, MotorPair requested, core::TimePoint now) noexcept;

  [[nodiscard]] bool tripped() const noexcept { return fault_.kind != FaultKind::none; }
  [[nodiscard]] bool newly_tripped() const noexcept { return newly_; }
  [[nodiscard]] const Fault& fault() const noexcept { return fault_; }
  [[nodiscard]] const SafetyLimits& limits() const noexcept { return limits_; }
  [[nodiscard]] const SafetyCounters& counters() const noexcept { return counters_; }

  // The fault check alone (no latching), for callers that only supervise.
  [[nodiscard]] Fault check(const Measurements& m, core::TimePoint now) const noexcept;

 private:
  SafetyLimits limits_;
  core::TimePoint armed_{};
  Fault fault_{};
  bool newly_ = false;
  SafetyCounters counters_{};
};

}  // namespace axon::blmc::host

// The 64-bit status word of the main application (GET_STATUS reply, firmware 04.01.00 and later).
//
// Only the bits listed in StatusBit are documented; other set bits are kept in raw() and printed as
// "BIT_<n>". Two quirks of the interface document, resolved here:
//   - It names bit 0 SYSTEM_INITIALIZATION; host software in service calls it SYSTEM_INITIALIZED.
//     Both names are accepted by status_bit_from_name(); the printed name is the document's.
//   - Its masks for bits 17..19 are written with one hex digit too many (0x00000000000020000 ...);
//     read as numbers they are 1<<17, 1<<18, 1<<19, which is what the neighbouring bits imply.
#pragma once

#include "axon/core/error.hpp"
#include "axon/fps/protocol/payload.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace axon::fps::protocol {

enum class StatusBit : std::uint8_t {
  system_initialized = 0,
  receiving_trajectory = 4,
  trajectory_alpha_received = 5,
  trajectory_beta_received = 6,
  low_power_after_move = 7,
  displacement_completed = 8,
  displacement_completed_alpha = 9,
  displacement_completed_beta = 10,
  collision_alpha = 11,
  collision_beta = 12,
  closed_loop_alpha = 13,
  closed_loop_beta = 14,
  collision_detect_alpha_disable = 17,
  collision_detect_beta_disable = 18,
  motor_calibration = 19,
  motor_alpha_calibrated = 20,
  motor_beta_calibrated = 21,
  datum_calibration = 22,
  datum_alpha_calibrated = 23,
  datum_beta_calibrated = 24,
  datum_initialization = 25,
  datum_alpha_initialized = 26,
  datum_beta_initialized = 27,
  hall_alpha_disable = 28,
  hall_beta_disable = 29,
  cogging_calibration = 30,
  cogging_alpha_calibrated = 31,
  cogging_beta_calibrated = 32,
  estimated_position = 33,
  position_restored = 34,
  switch_off_after_move = 35,
  precise_move_alpha = 37,
  precise_move_beta = 38,
  switch_off_hall_after_move = 39,
};

struct StatusBitInfo {
  StatusBit bit;
  std::string_view name;     // as printed, e.g. "DATUM_ALPHA_INITIALIZED"
  std::string_view meaning;  // one line in our words
};

constexpr std::uint64_t mask(StatusBit b) noexcept { return std::uint64_t{1} << static_cast<unsigned>(b); }

// Every documented bit, by position.
inline constexpr std::array<StatusBitInfo, 34> kStatusBits{{
    {StatusBit::system_initialized, "SYSTEM_INITIALIZATION", "firmware has finished starting up"},
    {StatusBit::receiving_trajectory, "RECEIVING_TRAJECTORY", "a trajectory upload is in progress"},
    {StatusBit::trajectory_alpha_received, "TRAJECTORY_ALPHA_RECEIVED", "every announced alpha point has arrived"},
    {StatusBit::trajectory_beta_received, "TRAJECTORY_BETA_RECEIVED", "every announced beta point has arrived"},
    {StatusBit::low_power_after_move, "LOW_POWER_AFTER_MOVE", "after a move, drop to the holding currents"},
    {StatusBit::displacement_completed, "DISPLACEMENT_COMPLETED", "no move is running"},
    {StatusBit::displacement_completed_alpha, "DISPLACEMENT_COMPLETED_ALPHA", "the alpha arm is not moving"},
    {StatusBit::displacement_completed_beta, "DISPLACEMENT_COMPLETED_BETA", "the beta arm is not moving"},
    {StatusBit::collision_alpha, "COLLISION_ALPHA", "the alpha arm detected a collision"},
    {StatusBit::collision_beta, "COLLISION_BETA", "the beta arm detected a collision"},
    {StatusBit::closed_loop_alpha, "CLOSED_LOOP_ALPHA", "the alpha motor runs in closed loop"},
    {StatusBit::closed_loop_beta, "CLOSED_LOOP_BETA", "the beta motor runs in closed loop"},
    {StatusBit::collision_detect_alpha_disable, "COLLISION_DETECT_ALPHA_DISABLE", "alpha collision detection is off"},
    {StatusBit::collision_detect_beta_disable, "COLLISION_DETECT_BETA_DISABLE", "beta collision detection is off"},
    {StatusBit::motor_calibration, "MOTOR_CALIBRATION", "a motor calibration is running"},
    {StatusBit::motor_alpha_calibrated, "MOTOR_ALPHA_CALIBRATED", "the alpha motor is calibrated"},
    {StatusBit::motor_beta_calibrated, "MOTOR_BETA_CALIBRATED", "the beta motor is calibrated"},
    {StatusBit::datum_calibration, "DATUM_CALIBRATION", "a datum calibration is running"},
    {StatusBit::datum_alpha_calibrated, "DATUM_ALPHA_CALIBRATED", "the alpha datum is calibrated"},
    {StatusBit::datum_beta_calibrated, "DATUM_BETA_CALIBRATED", "the beta datum is calibrated"},
    {StatusBit::datum_initialization, "DATUM_INITIALIZATION", "a datum search (go to datums) is running"},
    {StatusBit::datum_alpha_initialized, "DATUM_ALPHA_INITIALIZED", "the alpha zero reference is known"},
    {StatusBit::datum_beta_initialized, "DATUM_BETA_INITIALIZED", "the beta zero reference is known"},
    {StatusBit::hall_alpha_disable, "HALL_ALPHA_DISABLE", "the alpha hall sensor is off or unused"},
    {StatusBit::hall_beta_disable, "HALL_BETA_DISABLE", "the beta hall sensor is off or unused"},
    {StatusBit::cogging_calibration, "COGGING_CALIBRATION", "a cogging torque calibration is running"},
    {StatusBit::cogging_alpha_calibrated, "COGGING_ALPHA_CALIBRATED", "alpha cogging torque is calibrated"},
    {StatusBit::cogging_beta_calibrated, "COGGING_BETA_CALIBRATED", "beta cogging torque is calibrated"},
    {StatusBit::estimated_position, "ESTIMATED_POSITION",
     "the stored position is an estimate (power was lost during a move)"},
    {StatusBit::position_restored, "POSITION_RESTORED", "the position was restored from flash at start-up"},
    {StatusBit::switch_off_after_move, "SWITCH_OFF_AFTER_MOVE",
     "after a move, switch the H-bridges off (overrides LOW_POWER_AFTER_MOVE)"},
    {StatusBit::precise_move_alpha, "PRECISE_MOVE_ALPHA", "alpha go-to moves end with the open-loop approach"},
    {StatusBit::precise_move_beta, "PRECISE_MOVE_BETA", "beta go-to moves end with the open-loop approach"},
    {StatusBit::switch_off_hall_after_move, "SWITCH_OFF_HALL_AFTER_MOVE", "hall sensors sleep while idle"},
}};

constexpr std::uint64_t known_status_mask() noexcept {
  std::uint64_t m = 0;
  for (const auto& b : kStatusBits) m |= mask(b.bit);
  return m;
}

std::string_view status_bit_name(StatusBit b) noexcept;
// Case-insensitive; accepts SYSTEM_INITIALIZED as well as SYSTEM_INITIALIZATION.
std::optional<StatusBit> status_bit_from_name(std::string_view name) noexcept;

class PositionerStatus {
 public:
  static constexpr std::size_t kWireSize = 8;
  // Every bit the document defines.
  static constexpr std::uint64_t kKnownMask = known_status_mask();

  constexpr PositionerStatus() = default;
  constexpr explicit PositionerStatus(std::uint64_t raw) noexcept : raw_(raw) {}

  [[nodiscard]] constexpr std::uint64_t raw() const noexcept { return raw_; }
  [[nodiscard]] constexpr bool has(StatusBit b) const noexcept { return (raw_ & mask(b)) != 0; }
  constexpr PositionerStatus& set(StatusBit b, bool on = true) noexcept {
    raw_ = on ? (raw_ | mask(b)) : (raw_ & ~mask(b));
    return *this;
  }
  constexpr PositionerStatus& clear(StatusBit b) noexcept { return set(b, false); }

  // Set bits outside the documented ones.
  [[nodiscard]] std::uint64_t unknown_bits() const noexcept { return raw_ & ~kKnownMask; }

  // Names of the set bits, lowest first; undocumented bits as "BIT_<n>".
  [[nodiscard]] std::vector<std::string> names() const;
  // The names joined with '|' ("" when no bit is set).
  [[nodiscard]] std::string to_string() const;

  // Both datums are known and nothing moves: the state in which hosts in service start a move.
  [[nodiscard]] constexpr bool ready_to_move() const noexcept {
    return has(StatusBit::datum_alpha_initialized) && has(StatusBit::datum_beta_initialized) &&
           has(StatusBit::displacement_completed);
  }
  // Initialised and both datums known (the host in service calls such a robot healthy).
  [[nodiscard]] constexpr bool initialized() const noexcept {
    return has(StatusBit::system_initialized) && has(StatusBit::datum_alpha_initialized) &&
           has(StatusBit::datum_beta_initialized);
  }
  // Not moving (DISPLACEMENT_COMPLETED).
  [[nodiscard]] constexpr bool idle() const noexcept { return has(StatusBit::displacement_completed); }
  [[nodiscard]] constexpr bool collided() const noexcept {
    return has(StatusBit::collision_alpha) || has(StatusBit::collision_beta);
  }
  // A motor, datum or cogging calibration, or a datum search, is running.
  [[nodiscard]] constexpr bool calibrating() const noexcept {
    return has(StatusBit::motor_calibration) || has(StatusBit::datum_calibration) ||
           has(StatusBit::cogging_calibration) || has(StatusBit::datum_initialization);
  }
  // Both arms' trajectories have arrived completely.
  [[nodiscard]] constexpr bool trajectory_received() const noexcept {
    return has(StatusBit::trajectory_alpha_received) && has(StatusBit::trajectory_beta_received);
  }
  [[nodiscard]] constexpr bool motors_calibrated() const noexcept {
    return has(StatusBit::motor_alpha_calibrated) && has(StatusBit::motor_beta_calibrated);
  }
  [[nodiscard]] constexpr bool datums_calibrated() const noexcept {
    return has(StatusBit::datum_alpha_calibrated) && has(StatusBit::datum_beta_calibrated);
  }
  [[nodiscard]] constexpr bool hall_disabled() const noexcept {
    return has(StatusBit::hall_alpha_disable) || has(StatusBit::hall_beta_disable);
  }

  // The 8-byte GET_STATUS reply (little-endian uint64). All 64 bits count.
  [[nodiscard]] Payload encode() const;
  static Result<PositionerStatus> decode(std::span<const std::uint8_t> bytes);

  friend constexpr bool operator==(const PositionerStatus&, const PositionerStatus&) noexcept = default;

 private:
  std::uint64_t raw_ = 0;
};

}  // namespace axon::fps::protocol

// Typed codecs for the data of every fps request and reply.
//
// Each payload type has encode() -> Payload and a static decode(bytes) -> Result<T>. decode checks
// the size first (ProtocolErrc::wrong_length, which a positioner answers with code 5) and then the
// documented value ranges (ProtocolErrc::value_out_of_range, answered with code 1). Types hold wire
// values in the unit types of units.hpp, so a decoded value re-encodes to the same bytes.
//
// CommandTypes<CommandId> says which type each command's request and accepted reply use; the
// command table and these types are checked against each other at compile time (payloads.cpp).
// Error replies (non-zero response code) carry no data the host uses.
#pragma once

#include "axon/core/error.hpp"
#include "axon/fps/protocol/bootloader_status.hpp"
#include "axon/fps/protocol/commands.hpp"
#include "axon/fps/protocol/firmware_version.hpp"
#include "axon/fps/protocol/payload.hpp"
#include "axon/fps/protocol/status.hpp"
#include "axon/fps/protocol/units.hpp"

#include <cstdint>
#include <span>
#include <string>
#include <utility>

namespace axon::fps::protocol {

// No data (most commands, and the replies of every set/move command).
struct Empty {
  static constexpr std::size_t kMinSize = 0, kMaxSize = 0;
  [[nodiscard]] Payload encode() const { return {}; }
  static Result<Empty> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const { return {}; }
  friend constexpr bool operator==(const Empty&, const Empty&) noexcept = default;
};

// GET_ID reply: the positioner's id as uint32 (must fit the identifier's 11 bits).
struct PositionerIdReply {
  static constexpr std::size_t kMinSize = 4, kMaxSize = 4;
  std::uint16_t id = 0;
  [[nodiscard]] Payload encode() const { return Payload().put_u32(id); }
  static Result<PositionerIdReply> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const;
  friend constexpr bool operator==(const PositionerIdReply&, const PositionerIdReply&) noexcept = default;
};

// SEND_NEW_TRAJECTORY: how many points follow for each arm (each 0..1023, see trajectory.hpp).
struct TrajectorySize {
  static constexpr std::size_t kMinSize = 8, kMaxSize = 8;
  static constexpr std::uint32_t kMaxPoints = 1023;
  std::uint32_t alpha_points = 0;
  std::uint32_t beta_points = 0;
  [[nodiscard]] Payload encode() const { return Payload().put_u32(alpha_points).put_u32(beta_points); }
  static Result<TrajectorySize> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const;
  friend constexpr bool operator==(const TrajectorySize&, const TrajectorySize&) noexcept = default;
};

// SEND_TRAJECTORY_DATA: one point, the position to be reached at the given time after the start.
struct TrajectoryPoint {
  static constexpr std::size_t kMinSize = 8, kMaxSize = 8;
  Angle position;
  Time time;
  [[nodiscard]] Payload encode() const { return Payload().put_i32(position.steps()).put_u32(time.ticks()); }
  static Result<TrajectoryPoint> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const;
  friend constexpr bool operator==(const TrajectoryPoint&, const TrajectoryPoint&) noexcept = default;
};

// Alpha and beta positions: go-to targets and offsets, set/get position, offsets, hall positions.
struct ArmPositions {
  static constexpr std::size_t kMinSize = 8, kMaxSize = 8;
  Angle alpha;
  Angle beta;
  [[nodiscard]] Payload encode() const { return Payload().put_i32(alpha.steps()).put_i32(beta.steps()); }
  static Result<ArmPositions> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const;
  friend constexpr bool operator==(const ArmPositions&, const ArmPositions&) noexcept = default;
};

// Reply to the go-to commands: how long each arm's move takes.
struct ArmTimes {
  static constexpr std::size_t kMinSize = 8, kMaxSize = 8;
  Time alpha;
  Time beta;
  [[nodiscard]] Payload encode() const { return Payload().put_u32(alpha.ticks()).put_u32(beta.ticks()); }
  static Result<ArmTimes> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const;
  friend constexpr bool operator==(const ArmTimes&, const ArmTimes&) noexcept = default;
};

// SET_SPEED: motor speeds for go-to moves.
struct ArmSpeeds {
  static constexpr std::size_t kMinSize = 8, kMaxSize = 8;
  MotorSpeed alpha;
  MotorSpeed beta;
  [[nodiscard]] Payload encode() const { return Payload().put_u32(alpha.rpm()).put_u32(beta.rpm()); }
  static Result<ArmSpeeds> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const;
  friend constexpr bool operator==(const ArmSpeeds&, const ArmSpeeds&) noexcept = default;
};

// SET_CURRENT, SET_HOLDING_CURRENT and the GET_HOLDING_CURRENT reply: percent, 0..100 each.
struct ArmCurrents {
  static constexpr std::size_t kMinSize = 8, kMaxSize = 8;
  CurrentPercent alpha;
  CurrentPercent beta;
  [[nodiscard]] Payload encode() const { return Payload().put_u32(alpha.percent()).put_u32(beta.percent()); }
  static Result<ArmCurrents> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const;
  friend constexpr bool operator==(const ArmCurrents&, const ArmCurrents&) noexcept = default;
};

// SET_COLLISION_MARGIN: -30..30 each.
struct ArmMargins {
  static constexpr std::size_t kMinSize = 8, kMaxSize = 8;
  CollisionMargin alpha;
  CollisionMargin beta;
  [[nodiscard]] Payload encode() const { return Payload().put_i32(alpha.value()).put_i32(beta.value()); }
  static Result<ArmMargins> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const;
  friend constexpr bool operator==(const ArmMargins&, const ArmMargins&) noexcept = default;
};

// Requests of the cogging table reads: one table index per arm.
struct ArmIndices {
  static constexpr std::size_t kMinSize = 8, kMaxSize = 8;
  std::uint32_t alpha = 0;
  std::uint32_t beta = 0;
  [[nodiscard]] Payload encode() const { return Payload().put_u32(alpha).put_u32(beta); }
  static Result<ArmIndices> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const;
  friend constexpr bool operator==(const ArmIndices&, const ArmIndices&) noexcept = default;
};

// Two signed readings, one per arm; the unit depends on the command: whole degrees (calibration
// errors, cogging angles per motor turn), percent (measured currents, commanded torques) or raw
// cogging values.
struct ArmValues {
  static constexpr std::size_t kMinSize = 8, kMaxSize = 8;
  std::int32_t alpha = 0;
  std::int32_t beta = 0;
  [[nodiscard]] Payload encode() const { return Payload().put_i32(alpha).put_i32(beta); }
  static Result<ArmValues> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const;
  friend constexpr bool operator==(const ArmValues&, const ArmValues&) noexcept = default;
};

// One arm's position with a signed reading in percent (measured current or commanded torque).
struct PositionAndValue {
  static constexpr std::size_t kMinSize = 8, kMaxSize = 8;
  Angle position;
  std::int32_t value = 0;
  [[nodiscard]] Payload encode() const { return Payload().put_i32(position.steps()).put_i32(value); }
  static Result<PositionAndValue> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const;
  friend constexpr bool operator==(const PositionAndValue&, const PositionAndValue&) noexcept = default;
};

// One unsigned number: cogging table length, raw temperature reading.
struct U32Value {
  static constexpr std::size_t kMinSize = 4, kMaxSize = 4;
  std::uint32_t value = 0;
  [[nodiscard]] Payload encode() const { return Payload().put_u32(value); }
  static Result<U32Value> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const;
  friend constexpr bool operator==(const U32Value&, const U32Value&) noexcept = default;
};

// GET_FIRMWARE_VERSION reply (field byte order; FirmwareVersion::decode takes the other order too).
struct FirmwareVersionReply {
  static constexpr std::size_t kMinSize = 4, kMaxSize = 4;
  FirmwareVersion version;
  [[nodiscard]] Payload encode() const { return version.encode(); }
  static Result<FirmwareVersionReply> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const { return version.to_string(); }
  friend constexpr bool operator==(const FirmwareVersionReply&, const FirmwareVersionReply&) noexcept = default;
};

// GET_STATUS reply of the main application (8 bytes) and of the bootloader (4 bytes).
struct StatusReply {
  static constexpr std::size_t kMinSize = 8, kMaxSize = 8;
  PositionerStatus status;
  [[nodiscard]] Payload encode() const { return status.encode(); }
  static Result<StatusReply> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const { return status.to_string(); }
  friend constexpr bool operator==(const StatusReply&, const StatusReply&) noexcept = default;
};
struct BootloaderStatusReply {
  static constexpr std::size_t kMinSize = 4, kMaxSize = 4;
  BootloaderStatus status;
  [[nodiscard]] Payload encode() const { return status.encode(); }
  static Result<BootloaderStatusReply> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const { return status.to_string(); }
  friend constexpr bool operator==(const BootloaderStatusReply&, const BootloaderStatusReply&) noexcept = default;
};

// START_FIRMWARE_UPGRADE: image size in bytes and its zlib CRC-32 (firmware_image.hpp makes one).
struct FirmwareUpgradeHeader {
  static constexpr std::size_t kMinSize = 8, kMaxSize = 8;
  std::uint32_t size = 0;
  std::uint32_t crc32 = 0;
  [[nodiscard]] Payload encode() const { return Payload().put_u32(size).put_u32(crc32); }
  static Result<FirmwareUpgradeHeader> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const;
  friend constexpr bool operator==(const FirmwareUpgradeHeader&, const FirmwareUpgradeHeader&) noexcept = default;
};

// FIRMWARE_DATA: the next slice of the image, 8 bytes (1..8 for the last one), in image order.
struct FirmwareChunk {
  static constexpr std::size_t kMinSize = 1, kMaxSize = 8;
  Payload data;
  [[nodiscard]] Payload encode() const { return data; }
  static Result<FirmwareChunk> decode(std::span<const std::uint8_t> bytes);
  [[nodiscard]] std::string to_string() const { return data.to_hex(); }
  friend constexpr bool operator==(const FirmwareChunk&, const FirmwareChunk&) noexcept = default;
};

// Which payload types a command uses. Commands not specialised here carry no data either way.
template <CommandId C>
struct CommandTypes {
  using request = Empty;
  using reply = Empty;
  using bootloader_reply = reply;
};

#define AXON_FPS_COMMAND_TYPES(cmd, req, rep) \
  template <>                                 \
  struct CommandTypes<CommandId::cmd> {       \
    using request = req;                      \
    using reply = rep;                        \
    using bootloader_reply = rep;             \
  }

AXON_FPS_COMMAND_TYPES(get_id, Empty, PositionerIdReply);
AXON_FPS_COMMAND_TYPES(get_firmware_version, Empty, FirmwareVersionReply);
AXON_FPS_COMMAND_TYPES(send_new_trajectory, TrajectorySize, Empty);
AXON_FPS_COMMAND_TYPES(send_trajectory_data, TrajectoryPoint, Empty);
AXON_FPS_COMMAND_TYPES(get_datum_calibration_error, Empty, ArmValues);
AXON_FPS_COMMAND_TYPES(go_to_absolute_position, ArmPositions, ArmTimes);
AXON_FPS_COMMAND_TYPES(go_to_relative_position, ArmPositions, ArmTimes);
AXON_FPS_COMMAND_TYPES(get_current_position, Empty, ArmPositions);
AXON_FPS_COMMAND_TYPES(set_current_position, ArmPositions, Empty);
AXON_FPS_COMMAND_TYPES(get_offsets, Empty, ArmPositions);
AXON_FPS_COMMAND_TYPES(set_offsets, ArmPositions, Empty);
AXON_FPS_COMMAND_TYPES(set_speed, ArmSpeeds, Empty);
AXON_FPS_COMMAND_TYPES(set_current, ArmCurrents, Empty);
AXON_FPS_COMMAND_TYPES(get_hall_position, Empty, ArmPositions);
AXON_FPS_COMMAND_TYPES(get_motor_calibration_error, Empty, ArmValues);
AXON_FPS_COMMAND_TYPES(get_position_and_current_alpha, Empty, PositionAndValue);
AXON_FPS_COMMAND_TYPES(get_position_and_current_beta, Empty, PositionAndValue);
AXON_FPS_COMMAND_TYPES(get_currents, Empty, ArmValues);
AXON_FPS_COMMAND_TYPES(get_position_and_torque_alpha, Empty, PositionAndValue);
AXON_FPS_COMMAND_TYPES(get_position_and_torque_beta, Empty, PositionAndValue);
AXON_FPS_COMMAND_TYPES(get_torques, Empty, ArmValues);
AXON_FPS_COMMAND_TYPES(get_cogging_vector_length, Empty, U32Value);
AXON_FPS_COMMAND_TYPES(get_cogging_positive, ArmIndices, ArmValues);
AXON_FPS_COMMAND_TYPES(get_cogging_negative, ArmIndices, ArmValues);
AXON_FPS_COMMAND_TYPES(get_cogging_angles, ArmIndices, ArmValues);
AXON_FPS_COMMAND_TYPES(set_collision_margin, ArmMargins, Empty);
AXON_FPS_COMMAND_TYPES(set_holding_current, ArmCurrents, Empty);
AXON_FPS_COMMAND_TYPES(get_holding_current, Empty, ArmCurrents);
AXON_FPS_COMMAND_TYPES(get_raw_temperature, Empty, U32Value);
AXON_FPS_COMMAND_TYPES(start_firmware_upgrade, FirmwareUpgradeHeader, Empty);
AXON_FPS_COMMAND_TYPES(firmware_data, FirmwareChunk, Empty);
#undef AXON_FPS_COMMAND_TYPES

template <>
struct CommandTypes<CommandId::get_status> {
  using request = Empty;
  using reply = StatusReply;
  using bootloader_reply = BootloaderStatusReply;
};

template <CommandId C>
using RequestOf = typename CommandTypes<C>::request;
template <CommandId C>
using ReplyOf = typename CommandTypes<C>::reply;

// Calls f.template operator()<C>() with the compile-time CommandId equal to `id` (every id is in
// the table, so exactly one call happens).
template <class F>
constexpr void visit_command(CommandId id, F&& f) {
  [&]<std::size_t... I>(std::index_sequence<I...>) {
    (void)((kCommands[I].id == id ? (f.template operator()<kCommands[I].id>(), true) : false) || ...);
  }(std::make_index_sequence<kCommands.size()>{});
}

// Decodes `bytes` as the given command's request (or accepted reply in `mode`) with its typed codec:
// the full check a positioner (or host) applies, sizes first, then value ranges.
Result<void> check_payload(CommandId id, Direction dir, Mode mode, std::span<const std::uint8_t> bytes);

// Human-readable decoded payload, e.g. "alpha=90.0000 deg beta=45.0000 deg" ("" for no data).
Result<std::string> describe_payload(CommandId id, Direction dir, Mode mode, std::span<const std::uint8_t> bytes);

}  // namespace axon::fps::protocol

// The fps command table: every command of the bootloader (spec 5.2) and of the main application
// (spec 5.3) with its number, names, where it is valid, whether it may be broadcast and the shapes
// of its request and of its accepted reply. Hosts use it to build and check requests, simulators to
// answer malformed ones with the right response code (wrong size -> code 5, and so on).
//
// Command 112 and 113. The chapter headings of the interface document give "Set holding current"
// and "Get holding current" both the number 112, while its command summary (table 6) lists set as
// 112 and get as 113. The two can only be told apart by number or by size: set carries 8 bytes, get
// none. We follow the summary table, which is also what the host software in service sends: 112 is
// SET_HOLDING_CURRENT (8-byte request), 113 is GET_HOLDING_CURRENT (empty request, 8-byte reply).
// For firmware that follows the headings instead, DeviceOptions::get_holding_current_on_112 makes a
// device-side check read an *empty* 112 as a get (an 8-byte 112 stays a set); it is off by default.
//
// Motion and the collision lock. Each command has a safety class, given by two flags: `moves` and
// `read_only` (never both). A host refuses every `moves` command while its array is locked after a
// collision or a stop, at one point (host/motion_lock.hpp, applied by host/command_client.hpp);
// `read_only` commands change nothing and may be repeated after a timeout; a command with neither
// flag changes a setting or stops motion, and goes out while locked. Sections of the interface
// document in brackets.
//   moves: GO_TO_ABSOLUTE_POSITION 30 and GO_TO_RELATIVE_POSITION 31 [5.3.21, 5.3.22];
//     START_TRAJECTORY 14 [5.3.8] (a sync-line edge starts a loaded trajectory the same way [6]);
//     the datum searches 20-22 [5.3.11-5.3.13] and datum calibrations 23-25 [5.3.14-5.3.16], which
//     drive the arms into their hard stops; the motor calibrations 26-28, which turn both motors a
//     few turns [5.3.17-5.3.19]; the cogging calibrations 47-49, which drive to the hard stop
//     first [5.3.31-5.3.33]; and the trajectory upload SEND_NEW_TRAJECTORY 10,
//     SEND_TRAJECTORY_DATA 11, TRAJECTORY_DATA_END 12 [5.3.4-5.3.6]. The upload moves nothing by
//     itself, but a loaded trajectory runs on the next sync-line edge, which a CAN host neither
//     sends nor sees [6, 7.2]: refusing the load is the host's last chance to keep a locked plane
//     still, and the document has trajectories sent only after the collision flags are cleared
//     [9.4.1].
//   read_only: the GET_* commands 1-3 (both firmwares), 29, 32, 34, 44, 45, 54-59, 106-108, 110,
//     113, 132.
//   neither, stops: TRAJECTORY_ABORT 13 and STOP_TRAJECTORY 15 stop every motion [5.3.7, 5.3.9];
//     they always go out, and STOP_TRAJECTORY is what clears the collision flags, so it is also
//     how an array unlocks [5.3.9, 9.4.1].
//   neither, settings: SET_CURRENT_POSITION 33 and SET_OFFSETS 35 (redefine positions, no motion)
//     [5.3.24, 5.3.26]; SET_SPEED 40 (the speed of later go-to moves) [5.3.27]; SET_CURRENT 41
//     [5.3.28]; SAVE_CALIBRATION 53 [5.3.34]; SET_COLLISION_MARGIN 111 and the loop and
//     collision-detection modes 118-125, which the document's collision troubleshooting changes
//     while a flag is set [9.4.2, 9.4.3]; SET_HOLDING_CURRENT 112 [5.3.46]; the hall sensors
//     116/117 [5.3.48, 5.3.49]; the LED 126/127; the precise-move switches 128-131; and the
//     bootloader's START_FIRMWARE_UPGRADE 200 and FIRMWARE_DATA 201 (the bootloader does not drive
//     the motors) [5.2.4, 5.2.5].
//   COLLISION_DETECTED 18 is only ever sent by a robot (no flag).
#pragma once

#include "axon/core/error.hpp"
#include "axon/fps/protocol/layout.hpp"
#include "axon/fps/protocol/response.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace axon::fps::protocol {

// Which firmware answers: the bootloader (version YY == 80) or the main application.
enum class Mode : std::uint8_t { bootloader, application };
// Host to positioner, or positioner to host.
enum class Direction : std::uint8_t { request, reply };

enum class CommandId : std::uint8_t {
  get_id = 1,
  get_firmware_version = 2,
  get_status = 3,
  send_new_trajectory = 10,
  send_trajectory_data = 11,
  trajectory_data_end = 12,
  trajectory_abort = 13,
  start_trajectory = 14,
  stop_trajectory = 15,
  collision_detected = 18,
  go_to_datums = 20,
  go_to_datum_alpha = 21,
  go_to_datum_beta = 22,
  calibrate_datum = 23,
  calibrate_datum_alpha = 24,
  calibrate_datum_beta = 25,
  calibrate_motors = 26,
  calibrate_motor_alpha = 27,
  calibrate_motor_beta = 28,
  get_datum_calibration_error = 29,
  go_to_absolute_position = 30,
  go_to_relative_position = 31,
  get_current_position = 32,
  set_current_position = 33,
  get_offsets = 34,
  set_offsets = 35,
  set_speed = 40,
  set_current = 41,
  get_hall_position = 44,
  get_motor_calibration_error = 45,
  calibrate_cogging = 47,
  calibrate_cogging_alpha = 48,
  calibrate_cogging_beta = 49,
  save_calibration = 53,
  get_position_and_current_alpha = 54,
  get_position_and_current_beta = 55,
  get_currents = 56,
  get_position_and_torque_alpha = 57,
  get_position_and_torque_beta = 58,
  get_torques = 59,
  get_cogging_vector_length = 106,
  get_cogging_positive = 107,
  get_cogging_negative = 108,
  get_cogging_angles = 110,
  set_collision_margin = 111,
  set_holding_current = 112,
  get_holding_current = 113,
  switch_on_hall = 116,
  switch_off_hall = 117,
  alpha_closed_loop_with_collision_detection = 118,
  alpha_closed_loop_without_collision_detection = 119,
  alpha_open_loop_with_collision_detection = 120,
  alpha_open_loop_without_collision_detection = 121,
  beta_closed_loop_with_collision_detection = 122,
  beta_closed_loop_without_collision_detection = 123,
  beta_open_loop_with_collision_detection = 124,
  beta_open_loop_without_collision_detection = 125,
  switch_on_led = 126,
  switch_off_led = 127,
  switch_on_precise_move_alpha = 128,
  switch_off_precise_move_alpha = 129,
  switch_on_precise_move_beta = 130,
  switch_off_precise_move_beta = 131,
  get_raw_temperature = 132,
  start_firmware_upgrade = 200,
  firmware_data = 201,
};

constexpr std::uint8_t number(CommandId c) noexcept { return static_cast<std::uint8_t>(c); }

struct CommandInfo {
  CommandId id{};
  std::string_view name;     // upper-case, e.g. "GO_TO_ABSOLUTE_POSITION"
  std::string_view summary;  // one line in our words
  bool broadcast = false;    // may be addressed to positioner 0
  bool bootloader = false;   // taken by the bootloader
  bool application = false;  // taken by the main application
  bool host_sends = true;    // false: only a positioner sends it (collision report)
  bool moves = false;        // sets a robot moving or arms a motion: refused while locked (see top)
  bool read_only = false;    // changes nothing: safe to repeat (see top)
  Layout request;            // what the host sends
  Layout reply;              // the accepted reply of the main application
  Layout bootloader_reply;   // the accepted reply of the bootloader (differs for GET_STATUS only)

  [[nodiscard]] constexpr std::uint8_t number() const noexcept { return protocol::number(id); }
  [[nodiscard]] constexpr bool valid_in(Mode m) const noexcept {
    return m == Mode::bootloader ? bootloader : application;
  }
  [[nodiscard]] constexpr const Layout& reply_in(Mode m) const noexcept {
    return m == Mode::bootloader ? bootloader_reply : reply;
  }
  [[nodiscard]] constexpr const Layout& layout(Direction d, Mode m) const noexcept {
    return d == Direction::request ? request : reply_in(m);
  }
};

namespace detail {
inline constexpr Field kAlphaPos{"alpha", FieldType::i32, Unit::position};
inline constexpr Field kBetaPos{"beta", FieldType::i32, Unit::position};
inline constexpr Layout kPositions = layout::two(kAlphaPos, kBetaPos);
inline constexpr Layout kAlphaBetaDegrees =
    layout::two({"alpha", FieldType::i32, Unit::degrees}, {"beta", FieldType::i32, Unit::degrees});
inline constexpr Layout kAlphaBetaPercent =
    layout::two({"alpha", FieldType::i32, Unit::percent}, {"beta", FieldType::i32, Unit::percent});
inline constexpr Layout kAlphaBetaHolding =
    layout::two({"alpha", FieldType::u32, Unit::percent}, {"beta", FieldType::u32, Unit::percent});
inline constexpr Layout kCoggingIndices =
    layout::two({"alpha_index", FieldType::u32, Unit::none}, {"beta_index", FieldType::u32, Unit::none});
inline constexpr Layout kCoggingValues =
    layout::two({"alpha", FieldType::i32, Unit::none}, {"beta", FieldType::i32, Unit::none});
inline constexpr Layout kPositionAndCurrent =
    layout::two({"position", FieldType::i32, Unit::position}, {"current", FieldType::i32, Unit::percent});
inline constexpr Layout kPositionAndTorque =
    layout::two({"position", FieldType::i32, Unit::position}, {"torque", FieldType::i32, Unit::percent});

enum Flags : unsigned { kBroadcast = 1, kBoot = 2, kApp = 4, kFromDevice = 8, kMoves = 16, kRead = 32 };

constexpr CommandInfo cmd(CommandId id, std::string_view name, std::string_view summary, unsigned flags,
                          Layout request = layout::none, Layout reply = layout::none) noexcept {
  return CommandInfo{id,
                     name,
                     summary,
                     (flags & kBroadcast) != 0,
                     (flags & kBoot) != 0,
                     (flags & kApp) != 0,
                     (flags & kFromDevice) == 0,
                     (flags & kMoves) != 0,
                     (flags & kRead) != 0,
                     request,
                     reply,
                     reply};
}
constexpr CommandInfo with_bootloader_reply(CommandInfo c, Layout reply) noexcept {
  c.bootloader_reply = reply;
  return c;
}
}  // namespace detail

// Sorted by number.
inline constexpr std::array kCommands{
    // Taken by both firmwares.
    detail::cmd(CommandId::get_id, "GET_ID", "read the positioner id",
                detail::kBroadcast | detail::kBoot | detail::kApp | detail::kRead, layout::none,
                layout::one({"id", FieldType::u32, Unit::none})),
    detail::cmd(CommandId::get_firmware_version, "GET_FIRMWARE_VERSION", "read the running firmware's version",
                detail::kBroadcast | detail::kBoot | detail::kApp | detail::kRead, layout::none,
                layout::one({"version", FieldType::u32, Unit::firmware_version})),
    detail::with_bootloader_reply(
        detail::cmd(CommandId::get_status, "GET_STATUS", "read the status word (64 bits; 32 in the bootloader)",
                    detail::kBroadcast | detail::kBoot | detail::kApp | detail::kRead, layout::none,
                    layout::one({"status", FieldType::u64, Unit::status})),
        layout::one({"status", FieldType::u32, Unit::bootloader_status})),
    // Main application.
    detail::cmd(CommandId::send_new_trajectory, "SEND_NEW_TRAJECTORY",
                "announce a trajectory: point counts per arm (restarts any half-sent one)",
                detail::kApp | detail::kMoves,
                layout::two({"alpha_points", FieldType::u32, Unit::none}, {"beta_points", FieldType::u32, Unit::none})),
    detail::cmd(CommandId::send_trajectory_data, "SEND_TRAJECTORY_DATA",
                "one trajectory point: alpha points first, then beta points", detail::kApp | detail::kMoves,
                layout::two({"position", FieldType::i32, Unit::position}, {"time", FieldType::u32, Unit::time})),
    detail::cmd(CommandId::trajectory_data_end, "TRAJECTORY_DATA_END", "close the trajectory and have it checked",
                detail::kApp | detail::kMoves),
    detail::cmd(CommandId::trajectory_abort, "TRAJECTORY_ABORT",
                "stop motion, drop trajectories, end calibrations; keeps collision flags",
                detail::kBroadcast | detail::kApp),
    detail::cmd(CommandId::start_trajectory, "START_TRAJECTORY", "start the loaded trajectory",
                detail::kBroadcast | detail::kApp | detail::kMoves),
    detail::cmd(CommandId::stop_trajectory, "STOP_TRAJECTORY",
                "stop motion, drop trajectories, end calibrations and clear collision flags",
                detail::kBroadcast | detail::kApp),
    detail::cmd(CommandId::collision_detected, "COLLISION_DETECTED",
                "sent by a positioner on its own (uid 0) when an arm collides; code 8 alpha, 9 beta",
                detail::kApp | detail::kFromDevice),
    detail::cmd(CommandId::go_to_datums, "GO_TO_DATUMS", "drive both arms to their hard stops to find zero",
                detail::kApp | detail::kMoves),
    detail::cmd(CommandId::go_to_datum_alpha, "GO_TO_DATUM_ALPHA", "find zero on the alpha arm",
                detail::kApp | detail::kMoves),
    detail::cmd(CommandId::go_to_datum_beta, "GO_TO_DATUM_BETA", "find zero on the beta arm",
                detail::kApp | detail::kMoves),
    detail::cmd(CommandId::calibrate_datum, "CALIBRATE_DATUM", "calibrate both datums (three hard-stop hits)",
                detail::kApp | detail::kMoves),
    detail::cmd(CommandId::calibrate_datum_alpha, "CALIBRATE_DATUM_ALPHA", "calibrate the alpha datum",
                detail::kApp | detail::kMoves),
    detail::cmd(CommandId::calibrate_datum_beta, "CALIBRATE_DATUM_BETA", "calibrate the beta datum",
                detail::kApp | detail::kMoves),
    detail::cmd(CommandId::calibrate_motors, "CALIBRATE_MOTORS", "calibrate hall amplitudes and offsets, both motors",
                detail::kApp | detail::kMoves),
    detail::cmd(CommandId::calibrate_motor_alpha, "CALIBRATE_MOTOR_ALPHA", "calibrate the alpha motor",
                detail::kApp | detail::kMoves),
    detail::cmd(CommandId::calibrate_motor_beta, "CALIBRATE_MOTOR_BETA", "calibrate the beta motor",
                detail::kApp | detail::kMoves),
    detail::cmd(CommandId::get_datum_calibration_error, "GET_DATUM_CALIBRATION_ERROR",
                "spread of the hard-stop hits of the last datum calibration, degrees", detail::kApp | detail::kRead,
                layout::none, detail::kAlphaBetaDegrees),
    detail::cmd(CommandId::go_to_absolute_position, "GO_TO_ABSOLUTE_POSITION",
                "move both arms to absolute positions; replies with the time each needs", detail::kApp | detail::kMoves,
                detail::kPositions,
                layout::two({"alpha_eta", FieldType::u32, Unit::time}, {"beta_eta", FieldType::u32, Unit::time})),
    detail::cmd(CommandId::go_to_relative_position, "GO_TO_RELATIVE_POSITION",
                "move both arms by offsets; replies with the time each needs", detail::kApp | detail::kMoves,
                detail::kPositions,
                layout::two({"alpha_eta", FieldType::u32, Unit::time}, {"beta_eta", FieldType::u32, Unit::time})),
    detail::cmd(CommandId::get_current_position, "GET_CURRENT_POSITION", "read both arm positions",
                detail::kApp | detail::kRead, layout::none, detail::kPositions),
    detail::cmd(CommandId::set_current_position, "SET_CURRENT_POSITION",
                "declare the current position (risky: re-datum afterwards)", detail::kApp, detail::kPositions),
    detail::cmd(CommandId::get_offsets, "GET_OFFSETS", "read the zero offsets", detail::kApp | detail::kRead,
                layout::none, detail::kPositions),
    detail::cmd(CommandId::set_offsets, "SET_OFFSETS", "set the zero offsets", detail::kApp, detail::kPositions),
    detail::cmd(
        CommandId::set_speed, "SET_SPEED", "motor speeds for go-to moves, rpm at the motor", detail::kApp,
        layout::two({"alpha_rpm", FieldType::u32, Unit::motor_rpm}, {"beta_rpm", FieldType::u32, Unit::motor_rpm})),
    detail::cmd(CommandId::set_current, "SET_CURRENT", "motor currents in percent (factory testing)", detail::kApp,
                detail::kAlphaBetaHolding),
    detail::cmd(CommandId::get_hall_position, "GET_HALL_POSITION", "raw hall sensor positions of both arms",
                detail::kApp | detail::kRead, layout::none, detail::kPositions),
    detail::cmd(CommandId::get_motor_calibration_error, "GET_MOTOR_CALIBRATION_ERROR",
                "motor calibration error of both arms, degrees", detail::kApp | detail::kRead, layout::none,
                detail::kAlphaBetaDegrees),
    detail::cmd(CommandId::calibrate_cogging, "CALIBRATE_COGGING",
                "calibrate cogging torque, both motors (up to 40 min)", detail::kApp | detail::kMoves),
    detail::cmd(CommandId::calibrate_cogging_alpha, "CALIBRATE_COGGING_ALPHA", "calibrate alpha cogging torque",
                detail::kApp | detail::kMoves),
    detail::cmd(CommandId::calibrate_cogging_beta, "CALIBRATE_COGGING_BETA", "calibrate beta cogging torque",
                detail::kApp | detail::kMoves),
    detail::cmd(CommandId::save_calibration, "SAVE_CALIBRATION", "store calibration data in flash", detail::kApp),
    detail::cmd(CommandId::get_position_and_current_alpha, "GET_POSITION_AND_CURRENT_ALPHA",
                "alpha position and measured current", detail::kApp | detail::kRead, layout::none,
                detail::kPositionAndCurrent),
    detail::cmd(CommandId::get_position_and_current_beta, "GET_POSITION_AND_CURRENT_BETA",
                "beta position and measured current", detail::kApp | detail::kRead, layout::none,
                detail::kPositionAndCurrent),
    detail::cmd(CommandId::get_currents, "GET_CURRENTS", "measured currents of both arms, percent",
                detail::kApp | detail::kRead, layout::none, detail::kAlphaBetaPercent),
    detail::cmd(CommandId::get_position_and_torque_alpha, "GET_POSITION_AND_TORQUE_ALPHA",
                "alpha position and commanded torque", detail::kApp | detail::kRead, layout::none,
                detail::kPositionAndTorque),
    detail::cmd(CommandId::get_position_and_torque_beta, "GET_POSITION_AND_TORQUE_BETA",
                "beta position and commanded torque", detail::kApp | detail::kRead, layout::none,
                detail::kPositionAndTorque),
    detail::cmd(CommandId::get_torques, "GET_TORQUES", "commanded torques of both arms, percent",
                detail::kApp | detail::kRead, layout::none, detail::kAlphaBetaPercent),
    detail::cmd(CommandId::get_cogging_vector_length, "GET_COGGING_VECTOR_LENGTH", "entries in the cogging table",
                detail::kApp | detail::kRead, layout::none, layout::one({"length", FieldType::u32, Unit::none})),
    detail::cmd(CommandId::get_cogging_positive, "GET_COGGING_POSITIVE", "positive-direction cogging values at indices",
                detail::kApp | detail::kRead, detail::kCoggingIndices, detail::kCoggingValues),
    detail::cmd(CommandId::get_cogging_negative, "GET_COGGING_NEGATIVE", "negative-direction cogging values at indices",
                detail::kApp | detail::kRead, detail::kCoggingIndices, detail::kCoggingValues),
    detail::cmd(CommandId::get_cogging_angles, "GET_COGGING_ANGLES", "motor angles (degrees per motor turn) at indices",
                detail::kApp | detail::kRead, detail::kCoggingIndices, detail::kAlphaBetaDegrees),
    detail::cmd(CommandId::set_collision_margin, "SET_COLLISION_MARGIN", "collision detection margins, -30..30",
                detail::kApp,
                layout::two({"alpha", FieldType::i32, Unit::collision_margin},
                            {"beta", FieldType::i32, Unit::collision_margin})),
    detail::cmd(CommandId::set_holding_current, "SET_HOLDING_CURRENT", "idle holding currents in percent", detail::kApp,
                detail::kAlphaBetaHolding),
    detail::cmd(CommandId::get_holding_current, "GET_HOLDING_CURRENT", "read the idle holding currents",
                detail::kApp | detail::kRead, layout::none, detail::kAlphaBetaHolding),
    detail::cmd(CommandId::switch_on_hall, "SWITCH_ON_HALL", "wake the hall sensors before moving (about 5 s)",
                detail::kBroadcast | detail::kApp),
    detail::cmd(CommandId::switch_off_hall, "SWITCH_OFF_HALL", "put the hall sensors to sleep while idle",
                detail::kBroadcast | detail::kApp),
    detail::cmd(CommandId::alpha_closed_loop_with_collision_detection, "ALPHA_CLOSED_LOOP_WITH_COLLISION_DETECTION",
                "alpha: closed loop, collision detection on (power-up default)", detail::kApp),
    detail::cmd(CommandId::alpha_closed_loop_without_collision_detection,
                "ALPHA_CLOSED_LOOP_WITHOUT_COLLISION_DETECTION", "alpha: closed loop, collision detection off",
                detail::kApp),
    detail::cmd(CommandId::alpha_open_loop_with_collision_detection, "ALPHA_OPEN_LOOP_WITH_COLLISION_DETECTION",
                "alpha: open loop, collision detection on", detail::kApp),
    detail::cmd(CommandId::alpha_open_loop_without_collision_detection, "ALPHA_OPEN_LOOP_WITHOUT_COLLISION_DETECTION",
                "alpha: open loop, collision detection off (hall sensors unused)", detail::kApp),
    detail::cmd(CommandId::beta_closed_loop_with_collision_detection, "BETA_CLOSED_LOOP_WITH_COLLISION_DETECTION",
                "beta: closed loop, collision detection on (power-up default)", detail::kApp),
    detail::cmd(CommandId::beta_closed_loop_without_collision_detection, "BETA_CLOSED_LOOP_WITHOUT_COLLISION_DETECTION",
                "beta: closed loop, collision detection off", detail::kApp),
    detail::cmd(CommandId::beta_open_loop_with_collision_detection, "BETA_OPEN_LOOP_WITH_COLLISION_DETECTION",
                "beta: open loop, collision detection on", detail::kApp),
    detail::cmd(CommandId::beta_open_loop_without_collision_detection, "BETA_OPEN_LOOP_WITHOUT_COLLISION_DETECTION",
                "beta: open loop, collision detection off (hall sensors unused)", detail::kApp),
    detail::cmd(CommandId::switch_on_led, "SWITCH_ON_LED", "switch the LED on", detail::kApp),
    detail::cmd(CommandId::switch_off_led, "SWITCH_OFF_LED", "switch the LED off", detail::kBroadcast | detail::kApp),
    detail::cmd(CommandId::switch_on_precise_move_alpha, "SWITCH_ON_PRECISE_MOVE_ALPHA",
                "alpha: finish go-to moves with the open-loop approach (default)", detail::kApp),
    detail::cmd(CommandId::switch_off_precise_move_alpha, "SWITCH_OFF_PRECISE_MOVE_ALPHA",
                "alpha: no open-loop approach at the end of go-to moves", detail::kApp),
    detail::cmd(CommandId::switch_on_precise_move_beta, "SWITCH_ON_PRECISE_MOVE_BETA",
                "beta: finish go-to moves with the open-loop approach (default)", detail::kApp),
    detail::cmd(CommandId::switch_off_precise_move_beta, "SWITCH_OFF_PRECISE_MOVE_BETA",
                "beta: no open-loop approach at the end of go-to moves", detail::kApp),
    detail::cmd(CommandId::get_raw_temperature, "GET_RAW_TEMPERATURE", "raw reading of the microcontroller's sensor",
                detail::kApp | detail::kRead, layout::none, layout::one({"temperature", FieldType::u32, Unit::none})),
    // Bootloader only.
    detail::cmd(CommandId::start_firmware_upgrade, "START_FIRMWARE_UPGRADE",
                "announce a firmware image: size and zlib CRC-32", detail::kBoot,
                layout::two({"size", FieldType::u32, Unit::none}, {"crc32", FieldType::u32, Unit::crc32})),
    detail::cmd(CommandId::firmware_data, "FIRMWARE_DATA", "the next 8 bytes of the image (1..8 for the last)",
                detail::kBoot, layout::bytes("data", 1, 8)),
};

// nullptr when no firmware knows the number.
constexpr const CommandInfo* find_command(std::uint8_t number) noexcept {
  for (const auto& c : kCommands) {
    if (c.number() == number) return &c;
  }
  return nullptr;
}
// Every CommandId is in the table (checked at compile time in commands.cpp).
constexpr const CommandInfo& command_info(CommandId id) noexcept { return *find_command(number(id)); }
constexpr std::string_view command_name(CommandId id) noexcept { return command_info(id).name; }

// The command, or ProtocolErrc::unknown_command.
Result<const CommandInfo*> lookup_command(std::uint8_t number);
// By printable name, case-insensitive ("go_to_absolute_position" works); nullptr when unknown.
const CommandInfo* find_command(std::string_view name) noexcept;
// Printable name of any number ("UNKNOWN_COMMAND_250" when unknown).
std::string command_name(std::uint8_t number);

// Host side: may this request go out? Checks that the host sends this command, that the addressed
// firmware takes it (when the caller knows which one runs), that a broadcast (positioner 0) is
// allowed, and the payload size. Errors: not_sendable, wrong_mode, broadcast_not_allowed,
// wrong_length.
Result<void> check_request(const CommandInfo& c, bool broadcast, std::size_t size,
                           std::optional<Mode> mode = std::nullopt);

// Host side: does an accepted reply have the size its command declares (in the given firmware)?
// A reply with a non-zero response code may be empty or have the accepted size; anything else is
// ProtocolErrc::wrong_length.
Result<void> check_reply(const CommandInfo& c, Mode mode, ResponseCode code, std::size_t size);

// Device side: what a positioner running `mode` answers to a request, before it looks at values.
struct DeviceOptions {
  bool get_holding_current_on_112 = false;  // see the note on 112/113 at the top of this file
};
struct RequestVerdict {
  ResponseCode code = ResponseCode::accepted;
  const CommandInfo* command = nullptr;  // how the request was understood (nullptr: unknown number)
};
// Checks in this order: unknown number (13), not taken by this firmware or never sent by hosts
// (11 in the bootloader, 12 in the application), broadcast not allowed (10), wrong size (5).
RequestVerdict check_device_request(std::uint8_t number, Mode mode, bool broadcast, std::size_t size,
                                    const DeviceOptions& options = {}) noexcept;

}  // namespace axon::fps::protocol

// Axis modes (the SM field) and the mode-change rules of the open interface's state machine.
//
// A mode code travels in every axis of every packet. Codes: 0 (controller in full control), 0' = 10
// (echo test, reserved to the maker), 1..9 (PC takes part in control or trajectory), 1xx (an external
// sensor's measure; 101 accelerometer, 102 camera, 103 force sensor), 201/202 (Cartesian target or
// correction), the standby codes the controller passes through when leaving a mode (11, 12, 14, 15,
// 17, 170) and the special codes 500..508 (freezing, driving on, exit, drive-off, restart, following
// error). 0xFF appears only in the initialization packet: "open, start-up mode not given".
//
// Everything here is a pure function of its arguments.
#pragma once

#include "axon/c4g/protocol/packet.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace axon::c4g::protocol {

enum class Mode : std::int32_t {
  mode0 = 0,
  mode1 = 1,
  mode2 = 2,
  mode3 = 3,
  mode4 = 4,
  mode5 = 5,
  mode6 = 6,
  mode7 = 7,
  mode8 = 8,
  mode9 = 9,
  mode0_prime = 10,
  mode1_standby = 11,
  mode2_standby = 12,
  mode4_standby = 14,
  mode5_standby = 15,
  mode7_standby = 17,
  sensor = 100,  // generic 1xx: any code 100..199 without a name of its own
  sensor_accelerometer = 101,
  sensor_camera = 102,
  sensor_force = 103,
  mode7_standby_exit = 170,
  cartesian_target = 201,
  cartesian_delta = 202,
  freezing_active = 500,
  driving_on = 501,
  freezing_passive_in = 502,
  freezing_passive_out = 503,
  exit_open = 504,
  drive_off = 505,
  server_restart = 506,
  following_error = 508,
};
constexpr std::int32_t code(Mode m) noexcept { return static_cast<std::int32_t>(m); }

// Fields of an axis, as bits, to say which ones a mode gives meaning to.
using FieldMask = std::uint16_t;
inline constexpr FieldMask kFieldD1 = 1u << 1, kFieldD2 = 1u << 2, kFieldD3 = 1u << 3, kFieldD4 = 1u << 4,
                           kFieldD5 = 1u << 5, kFieldExt1 = 1u << 6, kFieldExt2 = 1u << 7, kFieldExt3 = 1u << 8;

enum class ModeKind { standard, standby, sensor, cartesian, special };
enum class Origin { controller, pc };  // who puts the code in the SM field first

struct ModeInfo {
  Mode mode;
  std::string_view name;         // identifier, e.g. "mode1_standby", "drive_off"
  std::string_view label;        // the manual's notation, e.g. "1'", "0'", "505"
  std::string_view description;  // what the PC and the controller do in it
  ModeKind kind;
  Origin origin;
  bool available;                // false: announced by the manual as "not currently available"
  FieldMask pc_fields;           // fields of the PC's reply that carry this mode's data every cycle
};

// The table entry for a code (1xx codes without their own entry map to the generic sensor entry);
// nullptr for codes the interface does not define (including 507 and 0xFF).
const ModeInfo* find_mode(std::int32_t code) noexcept;
inline bool is_known_mode(std::int32_t code) noexcept { return find_mode(code) != nullptr; }
// The special codes 500..508 (freezing, driving on, exit, drive off, restart, following error).
constexpr bool is_special_mode(std::int32_t code) noexcept { return code >= 500 && code <= 508; }
std::string_view mode_name(std::int32_t code) noexcept;  // "unknown" when not defined
std::span<const ModeInfo> all_modes() noexcept;           // every named mode, in code order
// Accepts a name ("mode4", "drive_off"), a label ("0'", "1'") or a number ("505").
std::optional<std::int32_t> parse_mode(std::string_view text) noexcept;

// The first open axis of pkt whose SM is not a defined mode (Fault unknown_mode, field 0).
Fault check_modes(const Packet& pkt) noexcept;

// The data fields of an axis that are not zero (kFieldD1 .. kFieldExt3; NaN counts as not zero).
FieldMask nonzero_fields(const Axis& a) noexcept;
// The per-mode table against a PC reply: every field is on the wire, and those the axis's mode does
// not use must be null (chapter 8 and the mode tables of chapter 14). The first offending open
// axis: Fault field_not_null, field = the field's bit (1 = D1 .. 8 = EXT3), got = the mode. Axes
// whose mode is not defined are left to check_modes.
Fault check_reply_fields(const Packet& reply) noexcept;

// ---- Mode changes -------------------------------------------------------------------------------
// Whether the controller accepts a change of an axis from `current` to `requested` asked by the PC.
// Rules (manual chapters 11, 13, 15 and the field libraries): unchanged is always fine; drive-off
// (505) and following-error (508) requests are always accepted; while driving on (501) nothing else
// is (15.2); codes only the controller issues (the standby codes, 501..504) are refused, except 2'
// from mode 2 (the PC starts the end of mode 2, state machine 24.2.4); the other special codes need
// mode 0; any other mode may be entered from mode 0 (the PC may set a mode once the drives are on,
// chapter 11 second phase and 15.2) or once the PC has sent exit-from-open; codes the interface does
// not define are refused. What this function cannot see (drives on, the controller's trajectory
// still moving) is checked by its callers: see docs/c4g-server.md, "Who sets the mode".
enum class ModeChange { allowed, unchanged, unknown_mode, driving_on, not_from_mode0, controller_only };
ModeChange check_mode_change(std::int32_t current, std::int32_t requested, bool exit_from_open_sent) noexcept;
inline bool may_set_mode(std::int32_t current, std::int32_t requested, bool exit_from_open_sent) noexcept {
  const auto c = check_mode_change(current, requested, exit_from_open_sent);
  return c == ModeChange::allowed || c == ModeChange::unchanged;
}
std::string_view to_string(ModeChange c) noexcept;

// Standby code used while leaving a mode (1->11, 2->12, 4->14, 5->15, 7->17), and back.
std::optional<std::int32_t> standby_of(std::int32_t mode) noexcept;
std::optional<std::int32_t> base_of_standby(std::int32_t standby) noexcept;  // 170 -> 7

// The codes an axis passes through after the PC's exit-from-open, ending in mode 0. For mode 7 it
// depends on whether the controller's own motion has finished (7 -> 170 -> 0) or not (7 -> 17 ->
// 170 -> 0). Modes 0 and 0' are left by the controller program setting another mode: empty.
struct ModeSequence {
  std::array<std::int32_t, 3> codes{};
  std::size_t count = 0;
  std::span<const std::int32_t> view() const noexcept { return {codes.data(), count}; }
};
ModeSequence exit_sequence(std::int32_t mode, bool controller_motion_finished) noexcept;

// START / CRUISE / END of a mode (state-machine chapter).
enum class EndTrigger { controller_sets_mode, pc_exit_from_open, none };
struct ModePhases {
  bool has_cruise = false;          // only modes 1 and 2 have a ramp (START) before CRUISE
  EndTrigger end_by = EndTrigger::none;
  std::string_view start, cruise, end;  // what starts each phase, in words
};
ModePhases phases(std::int32_t mode) noexcept;

// The conceptual state machine: S00 stop (drives on, still), S10 closed (controller moves),
// S01 open type A (PC moves), S11 open type B (both move). Transitions the manual marks "not
// allowed" return nullopt: a mode change always goes through the still state.
enum class MotionState { stop, closed, open_a, open_b };
enum class MotionEvent { move, motion_end, go_open_a, go_open_b, exit_from_open };
std::optional<MotionState> next_state(MotionState s, MotionEvent e) noexcept;
std::string_view to_string(MotionState s) noexcept;
std::string_view to_string(MotionEvent e) noexcept;

}  // namespace axon::c4g::protocol

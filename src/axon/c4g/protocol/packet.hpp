// The cyclic packet of the c4g open interface, and the map of the whole codec. Pure: no I/O.
//
// ---- API summary (namespace axon::c4g::protocol) ------------------------------------------------
// packet.hpp     Packet {num, infpar, cmd, count, axes: std::array<Axis,20>} and Axis {mode, d1..d5,
//                ext1..ext3}; encode_packet(pkt, span<std::byte>) / decode_packet(span, pkt[, n])
//                return a Fault (no allocation, noexcept: for the 1 kHz loop); to_result(fault) /
//                to_error(fault) turn a Fault into axon::Result / axon::Error outside the loop.
//                packet_size(n) = 12 + 36 n; classify(datagram) tells init / cyclic / neither.
//                Reply numbering: reply_number(num, ReplyNumbering::same|next), next_protocol_number.
//                Per-arm bytes of INFPAR/CMD: arm_byte, with_arm_byte, drives_on, exit_from_open,
//                request_exit_from_open.
// init_packet.hpp InitPacket (the 300 four-byte fields of the initialization packet, struct order),
//                encode_init / decode_init (exactly 1200 bytes), init_field_name(i), to_string(init).
// mode.hpp       Mode codes (0, 0'=10, 1..9, 1xx, 101..103, 201, 202, standbys 11 12 14 15 17 170,
//                specials 500..508), mode_info(code) {name, description, pc_fields, origin...},
//                mode-change rules: may_set_mode, standby_of, exit_sequence, phases, the FSM
//                (MotionState x MotionEvent -> next state).
// axis_map.hpp   AxisMap::from_init(init): open index (0-based packet position) <-> (arm 1..4,
//                logical axis 1..10), per-arm counts, modes at start-up.
// transform.hpp  ArmTransform::from_init(init, arm): K_r = K_r2 K_1^-T with Eigen; link rad <->
//                motor turns (with calibration constants) for positions, and velocities.
// safety.hpp     PC-side checks of the manual: following error over threshold, current saturation.
// error.hpp      ProtocolErrc and the "axon.c4g.protocol" error category.
// -------------------------------------------------------------------------------------------------
//
// Wire layout (little-endian, int32 and float32): a 12-byte header NUM, INFPAR, CMD (int32), then per
// open axis 36 bytes: SM (int32 mode) and eight floats D1..D5, EXT1..EXT3. The same layout travels in
// both directions; only the meaning of the fields differs (see field_name and docs/c4g-protocol.md).
//
// Checks on decode: size must be 12 + 36 n with 1 <= n <= 20 (and n must equal the initialization
// packet's axis count when given), NUM must be in 0..0x7FFF, every float must be finite. Encode makes
// the same checks on what it is asked to send, so neither side ever puts a NaN on the wire.
#pragma once

#include "axon/c4g/protocol/error.hpp"
#include "axon/core/error.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace axon::c4g::protocol {

inline constexpr std::size_t kHeaderSize = 12;
inline constexpr std::size_t kAxisSize = 36;
inline constexpr std::size_t kMaxAxes = 20;       // 4 arms, 2 drives
inline constexpr std::size_t kMaxArms = 4;
inline constexpr std::size_t kAxesPerArm = 10;    // GBM_NAX_ARM
inline constexpr std::size_t kMaxPacketSize = kHeaderSize + kMaxAxes * kAxisSize;  // 732
inline constexpr std::int32_t kMaxProtocolNumber = 0x7FFF;

constexpr std::size_t packet_size(std::size_t axes) noexcept { return kHeaderSize + axes * kAxisSize; }

// One open axis. Meaning by direction (controller -> PC / PC -> controller):
//   d1 target position [motor turns]        / target position [motor turns]
//   d2 target velocity [delta motor turns]  / target velocity [delta motor turns]
//   d3 actual position [motor turns]        / measure [sensor unit]
//   d4 actual velocity [delta motor turns]  / velocity contribution [delta motor turns]
//   d5 reference current [A]                / current contribution [A]
//   ext1..ext3 extra data (controller: ext1 dynamic-model current [A], ext2 diagonal inertia [kg m^2])
struct Axis {
  std::int32_t mode = 0;  // SM: the axis mode code (mode.hpp)
  float d1 = 0, d2 = 0, d3 = 0, d4 = 0, d5 = 0;
  float ext1 = 0, ext2 = 0, ext3 = 0;
  friend bool operator==(const Axis&, const Axis&) = default;
};

// A cyclic packet with room for the largest configuration: decoding into it never allocates.
struct Packet {
  std::int32_t num = 0;     // protocol number, 0..0x7FFF
  std::int32_t infpar = 0;  // one byte per arm: drives on (from controller) / exit from open (from PC)
  std::int32_t cmd = 0;     // one byte per arm: special information (motion type in the mode)
  std::size_t count = 0;    // open axes in use, 1..20
  std::array<Axis, kMaxAxes> axes{};

  std::span<Axis> open_axes() noexcept { return {axes.data(), count <= kMaxAxes ? count : kMaxAxes}; }
  std::span<const Axis> open_axes() const noexcept {
    return {axes.data(), count <= kMaxAxes ? count : kMaxAxes};
  }
  // Equal when the headers and the axes in use are equal (slots past count are ignored).
  friend bool operator==(const Packet& a, const Packet& b) noexcept;
};

enum class Direction { to_pc, to_controller };

// What went wrong, without allocating. axis/field locate the offending value (-1 when not about one
// axis/field; field 0 = SM, 1..5 = D1..D5, 6..8 = EXT1..EXT3); got/expected carry sizes or counts.
struct Fault {
  ProtocolErrc code{};  // value 0: no fault
  int axis = -1;
  int field = -1;
  std::int64_t got = 0;
  std::int64_t expected = 0;
  [[nodiscard]] bool ok() const noexcept { return code == ProtocolErrc{}; }
};

// Encodes pkt into out[0 .. packet_size(pkt.count)). out may be larger; the rest is not touched.
[[nodiscard]] Fault encode_packet(const Packet& pkt, std::span<std::byte> out) noexcept;
// Decodes a datagram; its size decides the axis count.
[[nodiscard]] Fault decode_packet(std::span<const std::byte> in, Packet& out) noexcept;
// Decodes a datagram that must carry exactly expected_axes axes (from the initialization packet).
[[nodiscard]] Fault decode_packet(std::span<const std::byte> in, Packet& out, std::size_t expected_axes) noexcept;

// Outside the real-time loop: a Fault as an Error with its context in words (allocates).
Error to_error(const Fault& f, std::string_view what = "c4g packet");
Result<void> to_result(const Fault& f, std::string_view what = "c4g packet");

// Field names for printing: "SM", "D1".."D5", "EXT1".."EXT3" with the direction's meaning.
std::string_view field_name(int field) noexcept;
std::string_view field_meaning(Direction dir, int field) noexcept;
std::string to_string(const Packet& pkt);

// What a datagram is, from its size alone (1200 is never 12 + 36 n, so the two cannot be confused).
enum class DatagramKind { init, cyclic, unknown };
DatagramKind classify(std::size_t size) noexcept;

// Reply numbering. The manual: the reply carries the controller's number (same). Field libraries:
// they reply NUM + 1, wrapping above 0x7FFF to 1 (next).
enum class ReplyNumbering { same, next };
constexpr std::int32_t next_protocol_number(std::int32_t num) noexcept {
  return num >= kMaxProtocolNumber || num < 0 ? 1 : num + 1;
}
constexpr std::int32_t reply_number(std::int32_t num, ReplyNumbering n) noexcept {
  return n == ReplyNumbering::same ? num : next_protocol_number(num);
}

// INFPAR / CMD: one byte per arm, arm 1 in the least significant byte (the first byte on the wire).
inline constexpr std::uint8_t kDrivesOn = 5;       // C4G_STS_MOVING, controller -> PC
inline constexpr std::uint8_t kExitFromOpen = 1;   // C4G_EXIT_FROM_OPEN, PC -> controller
// arm is 1..4; other values give 0 / leave the word unchanged.
constexpr std::uint8_t arm_byte(std::int32_t word, std::size_t arm) noexcept {
  if (arm < 1 || arm > kMaxArms) return 0;
  return static_cast<std::uint8_t>((static_cast<std::uint32_t>(word) >> (8 * (arm - 1))) & 0xFFu);
}
constexpr std::int32_t with_arm_byte(std::int32_t word, std::size_t arm, std::uint8_t value) noexcept {
  if (arm < 1 || arm > kMaxArms) return word;
  const unsigned shift = static_cast<unsigned>(8 * (arm - 1));
  const std::uint32_t w = (static_cast<std::uint32_t>(word) & ~(0xFFu << shift)) |
                          (static_cast<std::uint32_t>(value) << shift);
  return static_cast<std::int32_t>(w);
}
constexpr bool drives_on(std::int32_t infpar, std::size_t arm) noexcept { return arm_byte(infpar, arm) == kDrivesOn; }
constexpr bool exit_from_open(std::int32_t infpar, std::size_t arm) noexcept {
  return arm_byte(infpar, arm) == kExitFromOpen;
}
constexpr std::int32_t request_exit_from_open(std::int32_t infpar, std::size_t arm) noexcept {
  return with_arm_byte(infpar, arm, kExitFromOpen);
}

}  // namespace axon::c4g::protocol

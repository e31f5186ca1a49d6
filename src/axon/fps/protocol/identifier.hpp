// The 29-bit extended CAN identifier of every fps frame.
//
//   bits 28..18  positioner id (11 bits; 0 addresses every positioner on the bus)
//   bits 17..10  command number (8 bits)
//   bits  9..4   command uid (6 bits): pairs a reply with the request that caused it
//   bits  3..0   response code (4 bits): 0 in requests, the result in replies
//
// A request and an accepted reply (code 0) have the same layout; which one a frame is follows
// from who sent it. uid 0 is used for broadcasts and for frames a positioner sends on its own
// (collision reports, the start triggered by the sync line); unicast requests use uids 1..63.
#pragma once

#include "axon/core/error.hpp"
#include "axon/fps/protocol/response.hpp"

#include <cstdint>
#include <string>

namespace axon::fps::protocol {

inline constexpr std::uint16_t kBroadcastId = 0;
inline constexpr std::uint16_t kMaxPositionerId = 0x7FF;  // 2047
inline constexpr std::uint8_t kMaxUid = 0x3F;             // 63
inline constexpr std::uint32_t kMaxIdentifier = 0x1FFF'FFFF;

inline constexpr unsigned kPositionerShift = 18;
inline constexpr unsigned kCommandShift = 10;
inline constexpr unsigned kUidShift = 4;

struct Identifier {
  std::uint16_t positioner = 0;  // 0..2047
  std::uint8_t command = 0;      // raw command number (see commands.hpp); any 8-bit value fits
  std::uint8_t uid = 0;          // 0..63
  ResponseCode response = ResponseCode::accepted;

  [[nodiscard]] constexpr bool is_broadcast() const noexcept { return positioner == kBroadcastId; }
  friend constexpr bool operator==(const Identifier&, const Identifier&) noexcept = default;
};

// Packs the fields; a field that does not fit its bits is an error (never masked).
Result<std::uint32_t> encode_identifier(const Identifier& id);
// Splits a raw identifier; anything above 29 bits is an error.
Result<Identifier> decode_identifier(std::uint32_t raw);

// "positioner 17 command 30 uid 3 COMMAND_ACCEPTED"
std::string to_string(const Identifier& id);

}  // namespace axon::fps::protocol

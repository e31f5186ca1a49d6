// One fps frame as the protocol sees it: the split identifier and the data bytes, and the
// conversions to and from can::Frame (29-bit extended data frames only).
#pragma once

#include "axon/can/frame.hpp"
#include "axon/core/error.hpp"
#include "axon/fps/protocol/commands.hpp"
#include "axon/fps/protocol/identifier.hpp"
#include "axon/fps/protocol/payload.hpp"

#include <cstdint>
#include <span>
#include <string>

namespace axon::fps::protocol {

struct Message {
  Identifier id;
  Payload payload;

  friend bool operator==(const Message&, const Message&) noexcept = default;
};

// What to send, before it is addressed to a positioner and given a uid.
struct Request {
  CommandId command{};
  Payload payload;

  friend bool operator==(const Request&, const Request&) noexcept = default;
};

// Builds the extended frame; fails when a field does not fit (identifier.hpp) or the payload is
// longer than 8 bytes. No command-level checks: use make_request for those.
Result<can::Frame> to_frame(const Identifier& id, std::span<const std::uint8_t> payload);
inline Result<can::Frame> to_frame(const Message& m) { return to_frame(m.id, m.payload); }

// Splits a received frame. Standard (11-bit) and remote frames are ProtocolErrc::not_extended_frame.
// The command number is not looked up here (unknown numbers still decode).
Result<Message> from_frame(const can::Frame& frame);

// A host request, checked against the command table: the host may send it, positioner 0 only for
// broadcast commands, uid 0..63, the payload size the command declares.
Result<can::Frame> make_request(std::uint16_t positioner, CommandId command, std::uint8_t uid,
                                std::span<const std::uint8_t> payload = {});
inline Result<can::Frame> make_request(std::uint16_t positioner, const Request& r, std::uint8_t uid) {
  return make_request(positioner, r.command, uid, r.payload);
}
// A positioner's reply (simulators): `positioner` is the replying robot's own id (1..2047), even
// when the request was a broadcast. The command number is copied as given, so replies to unknown
// commands can be built.
Result<can::Frame> make_reply(std::uint16_t positioner, std::uint8_t command, std::uint8_t uid, ResponseCode code,
                              std::span<const std::uint8_t> payload = {});

// "17 GO_TO_ABSOLUTE_POSITION uid=3 COMMAND_ACCEPTED [00 00 00 10 ...]" for logs.
std::string to_string(const Message& m);

}  // namespace axon::fps::protocol

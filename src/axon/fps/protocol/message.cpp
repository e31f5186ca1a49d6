#include "axon/fps/protocol/message.hpp"

#include "axon/fps/protocol/error.hpp"

#include <fmt/format.h>

namespace axon::fps::protocol {

Result<can::Frame> to_frame(const Identifier& id, std::span<const std::uint8_t> payload) {
  AXON_TRY(raw, encode_identifier(id));
  if (payload.size() > Payload::kMaxSize) {
    return Error(ProtocolErrc::wrong_length, fmt::format("{} data bytes do not fit one frame", payload.size()));
  }
  return can::Frame::extended(raw, payload);
}

Result<Message> from_frame(const can::Frame& frame) {
  if (!frame.is_extended() || frame.is_remote()) {
    return Error(ProtocolErrc::not_extended_frame, frame.to_string());
  }
  AXON_TRY(id, decode_identifier(frame.id()));
  AXON_TRY(p, Payload::from(frame.payload()));
  return Message{id, p};
}

Result<can::Frame> make_request(std::uint16_t positioner, CommandId command, std::uint8_t uid,
                                std::span<const std::uint8_t> payload) {
  const auto& info = command_info(command);
  AXON_TRY(check_request(info, positioner == kBroadcastId, payload.size()));
  return to_frame(Identifier{positioner, info.number(), uid, ResponseCode::accepted}, payload);
}

Result<can::Frame> make_reply(std::uint16_t positioner, std::uint8_t command, std::uint8_t uid, ResponseCode code,
                              std::span<const std::uint8_t> payload) {
  if (positioner == kBroadcastId) {
    return Error(ProtocolErrc::positioner_out_of_range, "a reply must carry the replying positioner's own id, not 0");
  }
  return to_frame(Identifier{positioner, command, uid, code}, payload);
}

std::string to_string(const Message& m) {
  return fmt::format("{} {} uid={} {} [{}]", m.id.positioner, command_name(m.id.command), m.id.uid,
                     response_name(m.id.response), m.payload.to_hex());
}

}  // namespace axon::fps::protocol

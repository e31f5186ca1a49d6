#include "axon/fps/protocol/identifier.hpp"

#include "axon/fps/protocol/error.hpp"

#include <fmt/format.h>

namespace axon::fps::protocol {

Result<std::uint32_t> encode_identifier(const Identifier& id) {
  if (id.positioner > kMaxPositionerId) {
    return Error(ProtocolErrc::positioner_out_of_range, fmt::format("positioner id {}", id.positioner));
  }
  if (id.uid > kMaxUid) return Error(ProtocolErrc::uid_out_of_range, fmt::format("uid {}", id.uid));
  const auto code = static_cast<unsigned>(id.response);
  if (code > kMaxResponseCode) {
    return Error(ProtocolErrc::response_out_of_range, fmt::format("response code {}", code));
  }
  return (std::uint32_t{id.positioner} << kPositionerShift) | (std::uint32_t{id.command} << kCommandShift) |
         (std::uint32_t{id.uid} << kUidShift) | code;
}

Result<Identifier> decode_identifier(std::uint32_t raw) {
  if (raw > kMaxIdentifier) {
    return Error(ProtocolErrc::invalid_identifier, fmt::format("identifier 0x{:X}", raw));
  }
  Identifier id;
  id.positioner = static_cast<std::uint16_t>(raw >> kPositionerShift);
  id.command = static_cast<std::uint8_t>((raw >> kCommandShift) & 0xFF);
  id.uid = static_cast<std::uint8_t>((raw >> kUidShift) & kMaxUid);
  id.response = static_cast<ResponseCode>(raw & 0xF);
  return id;
}

std::string to_string(const Identifier& id) {
  return fmt::format("positioner {} command {} uid {} {}", id.positioner, id.command, id.uid,
                     response_name(id.response));
}

}  // namespace axon::fps::protocol

#include "axon/fps/protocol/error.hpp"

namespace axon::fps::protocol {
namespace {
class ProtocolCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "axon.fps.protocol"; }
  std::string message(int c) const override {
    switch (static_cast<ProtocolErrc>(c)) {
      case ProtocolErrc::invalid_identifier:
        return "fps identifier wider than 29 bits";
      case ProtocolErrc::positioner_out_of_range:
        return "positioner id out of range: ids are 11 bits (1..2047, 0 = broadcast)";
      case ProtocolErrc::uid_out_of_range:
        return "command uid out of range: uids are 6 bits (0..63)";
      case ProtocolErrc::response_out_of_range:
        return "response code out of range: response codes are 4 bits (0..15)";
      case ProtocolErrc::not_extended_frame:
        return "not an fps frame: positioners use 29-bit extended data frames";
      case ProtocolErrc::unknown_command:
        return "unknown fps command number; see docs/fps-protocol.md for the command table";
      case ProtocolErrc::wrong_length:
        return "fps payload has the wrong number of bytes for its command";
      case ProtocolErrc::value_out_of_range:
        return "value out of range for its fps field (values are never wrapped or clamped)";
      case ProtocolErrc::invalid_trajectory:
        return "invalid trajectory: at most 1023 points per arm, times strictly increasing and above 0";
      case ProtocolErrc::broadcast_not_allowed:
        return "this fps command cannot be broadcast; address one positioner";
      case ProtocolErrc::not_sendable:
        return "this fps command is only ever sent by a positioner, never by the host";
      case ProtocolErrc::wrong_mode:
        return "command not available in the firmware that runs (bootloader or main application)";
    }
    return "unknown fps protocol error";
  }
};
}  // namespace

const std::error_category& protocol_category() noexcept {
  static const ProtocolCategory c;
  return c;
}

}  // namespace axon::fps::protocol

#include "axon/blmc/protocol/error.hpp"

namespace axon::blmc::protocol {
namespace {
class ProtocolCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "axon.blmc.protocol"; }
  std::string message(int c) const override {
    switch (static_cast<ProtocolErrc>(c)) {
      case ProtocolErrc::not_standard_frame:
        return "not a blmc frame: motor driver boards use 11-bit standard data frames";
      case ProtocolErrc::wrong_id:
        return "blmc frame has a different identifier than the message being decoded";
      case ProtocolErrc::unknown_id:
        return "identifier is not a blmc message in this direction";
      case ProtocolErrc::wrong_length:
        return "blmc payload has the wrong number of bytes for its message";
      case ProtocolErrc::unknown_command:
        return "unknown blmc command; see docs/blmc-protocol.md for the command table";
      case ProtocolErrc::unknown_error_code:
        return "blmc status byte carries an undefined error code";
      case ProtocolErrc::value_out_of_range:
        return "value out of range for its blmc field (values are never wrapped or clamped)";
      case ProtocolErrc::bad_command_text:
        return "blmc command text must be NAME=value, e.g. ENABLE_SYS=1";
    }
    return "unknown blmc protocol error";
  }
};
}  // namespace

const std::error_category& protocol_category() noexcept {
  static const ProtocolCategory c;
  return c;
}

}  // namespace axon::blmc::protocol

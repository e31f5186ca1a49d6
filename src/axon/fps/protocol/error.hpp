// Errors of the fps protocol codecs: what is wrong with an identifier, a payload or a trajectory
// that the host wants to send or that arrived from a positioner.
//
// These are local, typed failures of the pure codec. They are distinct from the response codes a
// positioner puts into its replies (see response.hpp); response_code_for() maps the ones a
// simulated positioner must answer with.
#pragma once

#include "axon/core/error.hpp"

namespace axon::fps::protocol {

enum class ProtocolErrc {
  invalid_identifier = 1,  // a raw identifier wider than 29 bits
  positioner_out_of_range,  // positioner id above 2047 (11 bits)
  uid_out_of_range,         // command uid above 63 (6 bits)
  response_out_of_range,    // response code above 15 (4 bits)
  not_extended_frame,       // a standard (11-bit) or remote frame where fps frames are extended data frames
  unknown_command,          // a command number neither table knows
  wrong_length,             // a payload whose size does not fit the command
  value_out_of_range,       // a number that does not fit its field or its documented range (never wrapped)
  invalid_trajectory,       // too many points, times not strictly increasing, empty trajectory
  broadcast_not_allowed,    // a unicast-only command addressed to positioner 0
  not_sendable,             // a command only positioners send (collision report, 18)
  wrong_mode,               // a command the addressed firmware (bootloader or application) does not take
};

const std::error_category& protocol_category() noexcept;
inline std::error_code make_error_code(ProtocolErrc e) noexcept {
  return {static_cast<int>(e), protocol_category()};
}

}  // namespace axon::fps::protocol

template <>
struct std::is_error_code_enum<axon::fps::protocol::ProtocolErrc> : std::true_type {};

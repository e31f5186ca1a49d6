// Errors of the blmc protocol codecs: what is wrong with a frame, a value or a command text that the
// host wants to send or that arrived from a motor driver board.
#pragma once

#include "axon/core/error.hpp"

namespace axon::blmc::protocol {

enum class ProtocolErrc {
  not_standard_frame = 1,  // an extended (29-bit) or remote frame: blmc boards use 11-bit data frames
  wrong_id,                // a frame whose identifier is not the message the decoder was asked for
  unknown_id,              // an identifier the protocol does not define (in the expected direction)
  wrong_length,            // a payload whose size does not fit the message
  unknown_command,         // a command code or command name the protocol does not define
  unknown_error_code,      // a status byte carrying an error code the protocol does not define (6)
  value_out_of_range,      // a number that does not fit its field or documented range (never wrapped)
  bad_command_text,        // command text that is not of the form NAME=value
};

const std::error_category& protocol_category() noexcept;
inline std::error_code make_error_code(ProtocolErrc e) noexcept {
  return {static_cast<int>(e), protocol_category()};
}

}  // namespace axon::blmc::protocol

template <>
struct std::is_error_code_enum<axon::blmc::protocol::ProtocolErrc> : std::true_type {};

// Errors of the fps host driver: what went wrong while talking to positioners, beyond the codec
// (ProtocolErrc) and beyond a positioner's own refusal of a command.
//
// A positioner that answers with a non-zero response code produces an Error whose code is the
// protocol's ResponseCode (category "axon.fps.response"): its message carries the code's name,
// meaning and the troubleshooting advice, and `error == ResponseCode::already_in_motion` works.
// HostErrc covers the rest: no answer, safety lock, failed sequences.
#pragma once

#include "axon/core/error.hpp"

namespace axon::fps::host {

enum class HostErrc {
  timeout = 1,           // no reply within the command's timeout (after any retries)
  cancelled,             // the client was stopped while the request waited
  closed,                // the bus closed under the client
  locked,                // the array is locked (collision, lost link, operator or signal): motion refused until unlock()
  collision,             // a robot reported a collision during the operation
  unknown_positioner,    // an id the array has not discovered
  bad_reply,             // a reply whose data does not fit its command (counted, never used)
  position_mismatch,     // a move ended further than the tolerance from its target
  not_ready,             // a robot is not in a state to do this (moving, no datum, collision flag ...)
  sequence_failed,       // a multi-robot sequence did not complete for every robot (see its report)
  start_failed,          // a robot did not acknowledge the start of a trajectory: everyone was stopped
  not_in_bootloader,     // firmware upgrade needs the bootloader running
  upgrade_failed,        // firmware upgrade did not verify (see the per-robot report)
  wrong_executor,        // buses given to one Array live on different executors
  invalid_argument,      // a bad option or input from the caller
  firmware_lacks,        // the robot's firmware version lacks the command or the status layout (firmware_gates.hpp)
};

const std::error_category& host_category() noexcept;
inline std::error_code make_error_code(HostErrc e) noexcept { return {static_cast<int>(e), host_category()}; }

}  // namespace axon::fps::host

template <>
struct std::is_error_code_enum<axon::fps::host::HostErrc> : std::true_type {};

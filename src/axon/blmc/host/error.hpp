// Errors of the blmc host driver, beyond the codec's ProtocolErrc: a board that does not answer,
// does not get ready, reports an error code, or a safety check that stopped the motors.
#pragma once

#include "axon/core/error.hpp"

namespace axon::blmc::host {

enum class HostErrc {
  timeout = 1,       // no status or data frame from the board in time
  not_ready,         // the motors did not finish their alignment within the ready timeout
  board_error,       // the board's status carries an error code (the detail names it)
  stale_data,        // the host saw no measurement frame for longer than the stale limit
  safety_fault,      // a safety check tripped: currents zeroed, motors disabled (detail says why)
  cyclic_active,     // a coroutine call was made while the real-time loop owns the board
  not_cyclic,        // the call needs the board in cyclic mode (start_cyclic first)
  link_overflow,     // a queue between the real-time thread and the bus thread was full
  closed,            // the bus closed under the board
  invalid_argument,  // a bad option or input from the caller
  homing_failed,     // no encoder index found within the homing range or time
  interrupted,       // a stop was requested (Board::interrupt) while waiting for the board
  not_enabled,       // the call needs the motors enabled (MotorBoard::start_control, home)
};

const std::error_category& host_category() noexcept;
inline std::error_code make_error_code(HostErrc e) noexcept { return {static_cast<int>(e), host_category()}; }

}  // namespace axon::blmc::host

template <>
struct std::is_error_code_enum<axon::blmc::host::HostErrc> : std::true_type {};

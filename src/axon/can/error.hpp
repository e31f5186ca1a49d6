// Error codes of the CAN layer.
#pragma once

#include "axon/core/error.hpp"

namespace axon::can {

enum class CanErrc {
  invalid_id = 1,     // id does not fit 11 or 29 bits
  invalid_length,     // more than 8 data bytes / DLC over 8
  parse_error,        // a text line (candump, cansend, CAN@net, socketcand) that does not parse
  protocol_error,     // the peer broke the protocol (unexpected reply, bad handshake)
  device_error,       // the device answered with an error (e.g. CAN@net "R ERR")
  bus_off,            // the controller is bus-off
  tx_overflow,        // a transmit queue or FIFO was full: frame dropped
  rx_overflow,        // a receive queue was full: frame dropped
  closed,             // the bus was closed
  timeout,            // nothing arrived in time
  connect_failed,     // TCP connection to a gateway/daemon failed
  not_supported,      // e.g. AF_CAN missing from the kernel
  bad_spec,           // a bus specification string that does not parse
  io,                 // a socket or file error
};

const std::error_category& can_category() noexcept;
inline std::error_code make_error_code(CanErrc e) noexcept { return {static_cast<int>(e), can_category()}; }

}  // namespace axon::can

template <>
struct std::is_error_code_enum<axon::can::CanErrc> : std::true_type {};

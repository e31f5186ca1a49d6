// Errors of the PLC link (Modbus TCP to the instrument electronics box).
//
// The detail of every error carries what was being done (which address, which host) and
// libmodbus's own message (modbus_strerror) when libmodbus reported it.
#pragma once

#include "axon/core/error.hpp"

namespace axon::fps::plc {

enum class PlcErrc {
  connect_failed = 1,  // TCP connection refused or unreachable
  timeout,             // no answer within the response timeout
  io,                  // the connection broke or a frame was malformed
  bad_address,         // the PLC refused the address (Modbus exception 2, illegal data address)
  device_exception,    // any other Modbus exception the PLC answered with
  invalid_argument,    // a sextant, sensor or option the register map does not have
  bad_map,             // the register map itself is inconsistent
  server_failed,       // the emulator could not listen
};

const std::error_category& plc_category() noexcept;
inline std::error_code make_error_code(PlcErrc e) noexcept { return {static_cast<int>(e), plc_category()}; }

}  // namespace axon::fps::plc

template <>
struct std::is_error_code_enum<axon::fps::plc::PlcErrc> : std::true_type {};

#include "axon/blmc/protocol/status.hpp"

#include "axon/blmc/protocol/error.hpp"

#include <fmt/format.h>

namespace axon::blmc::protocol {

std::string_view name(ErrorCode e) noexcept {
  switch (e) {
    case ErrorCode::none: return "NONE";
    case ErrorCode::encoder: return "ENCODER";
    case ErrorCode::can_recv_timeout: return "CAN_RECV_TIMEOUT";
    case ErrorCode::crit_temp: return "CRIT_TEMP";
    case ErrorCode::pos_converter: return "POS_CONVERTER";
    case ErrorCode::pos_rollover: return "POS_ROLLOVER";
    case ErrorCode::other: return "OTHER";
  }
  return "?";
}

Result<ErrorCode> error_code_from_raw(std::uint8_t raw) {
  if (raw > 7) {
    return Error(ProtocolErrc::value_out_of_range, fmt::format("error code {} wider than 3 bits", raw));
  }
  if (raw == kUndocumentedErrorCode) return Error(ProtocolErrc::unknown_error_code, "status error code 6");
  return static_cast<ErrorCode>(raw);
}

std::uint8_t Status::to_byte() const noexcept {
  return static_cast<std::uint8_t>((system_enabled ? 0x01 : 0) | (motor1_enabled ? 0x02 : 0) |
                                   (motor1_ready ? 0x04 : 0) | (motor2_enabled ? 0x08 : 0) |
                                   (motor2_ready ? 0x10 : 0) | ((static_cast<unsigned>(error) & 7u) << 5));
}

Result<Status> Status::from_byte(std::uint8_t byte) {
  AXON_TRY(err, error_code_from_raw(static_cast<std::uint8_t>(byte >> 5)));
  Status s;
  s.system_enabled = (byte & 0x01) != 0;
  s.motor1_enabled = (byte & 0x02) != 0;
  s.motor1_ready = (byte & 0x04) != 0;
  s.motor2_enabled = (byte & 0x08) != 0;
  s.motor2_ready = (byte & 0x10) != 0;
  s.error = err;
  return s;
}

std::string Status::to_string() const {
  auto motor = [](bool en, bool rdy) -> std::string {
    if (!en && !rdy) return "-";
    if (en && rdy) return "enabled,ready";
    return en ? "enabled" : "ready";
  };
  return fmt::format("{} MTR1({}) MTR2({}) error={}", system_enabled ? "SYS" : "sys-off",
                     motor(motor1_enabled, motor1_ready), motor(motor2_enabled, motor2_ready), name(error));
}

ErrorCode reported_error(const FaultSet& f) noexcept {
  if (f.encoder) return ErrorCode::encoder;
  if (f.transmit) return ErrorCode::other;
  if (f.recv_timeout) return ErrorCode::can_recv_timeout;
  if (f.pos_converter) return ErrorCode::pos_converter;
  if (f.pos_rollover) return ErrorCode::pos_rollover;
  return ErrorCode::none;
}

}  // namespace axon::blmc::protocol
